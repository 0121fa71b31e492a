// `medspring accuracy` and `medspring calibrate` (docs/accuracy.md): the spring models against the
// CalculiX FEM reference of the same organ under the same supports and contact loads, with default and
// calibrated stiffnesses.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "accuracy_indentation.hpp"
#include "accuracy_summary.hpp"
#include "commands.hpp"
#include "medspring/builders/output_folder.hpp"
#include "medspring/core/check.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/validation.hpp"
#include "medspring/fem/vessel.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/medial/chain.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/models/tissue.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/sim/simulation.hpp"
#include "scene_support.hpp"

namespace medspring::cli {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

struct Organ {
  std::string name;
  SurfaceMesh surface;
  MatX3 atoms;
  // volumetric kind (issue 23): the TetGen mesh of the surface (made once) and the material it gets
  mutable std::shared_ptr<const VolumetricMesh> vmesh;
  mutable double E_kPa = 10, nu = 0.45;
  mutable Index target_nodes = 2000;
};

const VolumetricMesh& volumetric_mesh_of(const Organ& o) {
  if (!o.vmesh)
    o.vmesh = std::make_shared<const VolumetricMesh>(
        fem::volumetric_mesh(o.surface, {.target_nodes = o.target_nodes}));
  return *o.vmesh;
}

// A model kind of the tables: "surface", "hybrid" or "volumetric", linear or Duffing, with or without the
// local overlay.
struct Kind {
  std::string base;  // surface | hybrid | volumetric
  bool nonlinear = false;
  bool local = false;
  std::string label() const {
    return base + (local ? " + local" : "") + (nonlinear ? " (Duffing)" : " (linear)");
  }
  Index stiffness_families() const { return base == "surface" || base == "volumetric" ? 2 : 4; }
  // + eta of the Duffing springs (D-3: k' = eta k / L0^2; the volumetric kind keeps eta = 1: its
  // calibration fits springs and volume terms only) + k_loc
  bool fits_eta() const { return nonlinear && base != "volumetric"; }
  Index families() const { return stiffness_families() + (fits_eta() ? 1 : 0) + (local ? 1 : 0); }
  Index eta_index() const { return fits_eta() ? stiffness_families() : -1; }
  Index local_index() const { return local ? families() - 1 : -1; }
};

// Stiffness families: surface (k, k_r); hybrid (k_surf, k_spoke, k_cl, k_r); multipliers m scale them.
// Volumetric: (springs, volume terms) from E and nu (docs/volumetric.md); no return springs (supports).
BodyPtr make_body(const Organ& o, const Kind& k, const std::vector<Index>& support, const VecX& m) {
  if (k.base == "volumetric") {
    VolumetricSettings s;
    s.E_kPa = o.E_kPa;
    s.nu = o.nu;
    s.spring_scale = m(0);
    s.volume_scale = m(1);
    if (k.nonlinear) s.duffing = DuffingSettings{};  // Strain, eta = 1 (D-3)
    s.fixed = support;
    return std::make_shared<VolumetricBody>(volumetric_mesh_of(o), s, o.name);
  }
  if (k.base == "surface") {
    SurfaceBodyParams p;
    p.k *= m(0);
    p.node.return_k *= m(1);
    if (!k.nonlinear) p.duffing.mode = DuffingMode::Linear;
    if (k.nonlinear) p.duffing.eta *= m(k.eta_index());
    p.fixed = support;
    return std::make_shared<SurfaceBody>(o.surface, p, o.name);
  }
  HybridSettings s;
  s.k_surf *= m(0);
  s.k_spoke *= m(1);
  s.k_cl *= m(2);
  s.surface_node.return_k *= m(3);
  s.atom_node.return_k *= m(3);
  s.nonlinear = k.nonlinear;
  if (k.nonlinear) s.duffing.eta *= m(k.eta_index());
  s.fixed = support;
  return std::make_shared<HybridKidney>(o.surface, o.atoms, s, o.name);
}

// Calibration of the volumetric kind (docs/volumetric.md): two families, springs s1 and volume terms s2. At
// small strain the displacement under (c s1, c s2) is the one under (s1, s2) divided by c, so the fit is a
// golden-section search over the ratio r = s2 / s1 (log range [1e-2, 1e2], 18 evaluations) with the common
// scale c in closed form: the least-squares fit of u / c to the FEM in the cost of fem::calibrate_multipliers
// (mean squared surface error + squared contact error, relative to the load's peak FEM displacement). The
// tables then evaluate (c, c r) with the full (geometrically nonlinear) static solve. ~8x fewer solves than
// the generic coordinate descent.
VecX calibrate_volumetric(const fem::Response& response, const std::vector<fem::CalibrationCase>& training) {
  auto cost = [&](double logr, double& c_out) {
    VecX m(2);
    m << 1.0, std::exp(logr);
    std::vector<MatX3> us;
    double uu = 0, uU = 0;
    for (const auto& t : training) {
      MatX3 u;
      try {
        u = response(m, t.load);
      } catch (const SolverError&) {
        return std::numeric_limits<double>::infinity();
      }
      const double s = std::max(t.u_fem.rowwise().norm().maxCoeff(), 1e-12);
      const double wn = 1.0 / (s * s * static_cast<double>(u.rows())), wc = 1.0 / (s * s);
      uu += wn * u.squaredNorm() + wc * u.row(t.contact).squaredNorm();
      uU += wn * (u.array() * t.u_fem.array()).sum() + wc * u.row(t.contact).dot(t.u_fem.row(t.contact));
      us.push_back(std::move(u));
    }
    const double a = uU > 0 && uu > 0 ? uU / uu : 1.0;  // a = 1 / c
    double cst = 0;
    for (std::size_t i = 0; i < training.size(); ++i) {
      const auto& t = training[i];
      const double s = std::max(t.u_fem.rowwise().norm().maxCoeff(), 1e-12);
      cst += (a * us[i] - t.u_fem).squaredNorm() / (s * s * static_cast<double>(us[i].rows()));
      cst += (a * us[i].row(t.contact) - t.u_fem.row(t.contact)).squaredNorm() / (s * s);
    }
    c_out = 1.0 / a;
    return cst;
  };
  const double g = (std::sqrt(5.0) - 1) / 2;
  double lo = std::log(1e-2), hi = std::log(1e2), ca = 1, cb = 1;
  double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
  double fa = cost(a, ca), fb = cost(b, cb);
  for (int it = 0; it < 16; ++it) {
    if (fa < fb) {
      hi = b;
      b = a;
      fb = fa;
      cb = ca;
      a = hi - g * (hi - lo);
      fa = cost(a, ca);
    } else {
      lo = a;
      a = b;
      fa = fb;
      ca = cb;
      b = lo + g * (hi - lo);
      fb = cost(b, cb);
    }
  }
  const double logr = fa < fb ? a : b, c = fa < fb ? ca : cb;
  VecX m(2);
  m << c, c * std::exp(logr);
  return m;
}

struct Frame {
  Vec3 c, e1, e3;  // centroid, long axis, thin axis (the load presses along -e3, the support is at -e3)
  double half_length = 0, thickness = 0;
};

Frame principal_frame(const MatX3& V) {
  Frame f;
  f.c = V.colwise().mean().transpose();
  const MatX3 D = V.rowwise() - f.c.transpose();
  Eigen::SelfAdjointEigenSolver<Mat3> es(D.transpose() * D);
  f.e3 = es.eigenvectors().col(0);
  f.e1 = es.eigenvectors().col(2);
  const VecX p1 = D * f.e1, p3 = D * f.e3;
  f.half_length = 0.5 * (p1.maxCoeff() - p1.minCoeff());
  f.thickness = p3.maxCoeff() - p3.minCoeff();
  return f;
}

// Sites on the +e3 side at fractions t of the half length along e1: the most +e3 node near each.
std::vector<Index> pick_sites(const MatX3& V, const Frame& f, const std::vector<double>& ts) {
  std::vector<Index> out;
  for (double t : ts) {
    Index best = -1;
    double top = -1e300;
    for (Index i = 0; i < V.rows(); ++i) {
      const Vec3 d = V.row(i).transpose() - f.c;
      if (std::abs(d.dot(f.e1) - t * f.half_length) > 0.1 * f.half_length) continue;
      if (d.dot(f.e3) > top) {
        top = d.dot(f.e3);
        best = i;
      }
    }
    require(best >= 0, "accuracy: no surface node near site t = ", t);
    out.push_back(best);
  }
  return out;
}

double median_update_us(const BodyPtr& body, const Kind& k, Index contact, const Vec3& F, int samples) {
  SimulationSettings ss;
  ss.local.enabled = k.local;
  ss.normals = false;
  Simulation sim(body, ss);
  sim.set_loads({{.node = contact, .force = F, .t_ramp = 0}});
  sim.advance(50);
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(samples));
  for (int i = 0; i < samples; ++i) {
    const auto a = std::chrono::steady_clock::now();
    sim.update();
    us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count());
  }
  std::nth_element(us.begin(), us.begin() + static_cast<long>(us.size() / 2), us.end());
  return us[us.size() / 2];
}

struct Settings {
  fem::Material material;
  double radius = 8.0;
  bool quick = false;
  std::vector<std::string> kinds;  // --kinds: the bases to run (empty: all)
  Index volumetric_nodes = 2000;   // --nodes
  std::vector<double> forces;      // --forces (N; default 0.2, 0.5, 1.0)
  int level = 1;
  bool quiet = false;
};

// --kinds surface,hybrid,volumetric (default all) and --nodes N (volumetric node count, default 2000).
void read_kind_options(const Args& args, Settings& st, const std::string& cmd) {
  if (auto k = args.get("kinds")) {
    std::stringstream ss(*k);
    std::string item;
    while (std::getline(ss, item, ',')) {
      require(item == "surface" || item == "hybrid" || item == "volumetric" || item == "volumetric-duffing",
              cmd, ": --kinds: unknown kind '", item,
              "' (expected surface, hybrid, volumetric, volumetric-duffing)");
      st.kinds.push_back(item);
    }
    require(!st.kinds.empty(), cmd, ": --kinds must name at least one kind");
  }
  if (auto f = args.get("forces")) {
    std::stringstream ss(*f);
    std::string item;
    while (std::getline(ss, item, ',')) {
      char* end = nullptr;
      const double v = std::strtod(item.c_str(), &end);
      require(end && *end == '\0' && std::isfinite(v) && v > 0 && v <= 100, cmd, ": --forces: '", item,
              "' is not a force in (0, 100] N");
      st.forces.push_back(v);
    }
    require(!st.forces.empty(), cmd, ": --forces must list at least one force");
  }
  const long long nodes = args.integer("nodes", 2000);
  require(nodes >= 10 && nodes <= 200000, cmd, ": --nodes must be in [10, 200000] (got ", nodes, ")");
  st.volumetric_nodes = static_cast<Index>(nodes);
}

void note(const Settings& s, const std::string& line) {
  if (!s.quiet) std::cerr << line << std::endl;
}

// Everything measured on one organ.
json run_organ(const Organ& o, const Settings& st, json& maps, std::vector<Kind> kinds = {},
               bool convergence = true) {
  const Frame f = principal_frame(o.surface.V);
  const fem::SupportRule rule{-f.e3, 0.2 * f.thickness};
  const std::vector<Index> support = fem::support_nodes(o.surface.V, rule);
  const std::vector<double> ts =
      st.quick ? std::vector<double>{-0.3, 0.3} : std::vector<double>{-0.45, -0.15, 0.15, 0.45};
  const std::vector<Index> sites = pick_sites(o.surface.V, f, ts);
  const std::vector<double> forces = !st.forces.empty() ? st.forces
                                     : st.quick         ? std::vector<double>{0.5}
                                                        : std::vector<double>{0.2, 0.5, 1.0};
  // training force: 0.5 N, or the smallest of --forces without it (large-strain runs train on small loads)
  const double train_force = std::find(forces.begin(), forces.end(), 0.5) != forces.end()
                                 ? 0.5
                                 : *std::min_element(forces.begin(), forces.end());
  // training: the first site at 0.5 N (quick) or the first two sites at 0.5 N; every other case is held out
  const std::size_t train_sites = st.quick ? 1 : 2;
  json out = {
      {"organ", o.name},
      {"surface_nodes", o.surface.num_vertices()},
      {"support_nodes", support.size()},
      {"support_rule",
       {{"direction", {rule.direction(0), rule.direction(1), rule.direction(2)}}, {"depth_mm", rule.depth}}},
      {"contact_radius_mm", st.radius},
      {"sites", sites}};

  fem::OrganMeshSettings ms;
  ms.subdivisions = st.level - 1;
  note(st, cat(o.name, ": meshing (level ", st.level, ")"));
  const fem::OrganReference ref(o.surface, st.material, rule, ms);
  out["fem"] = {{"nodes", ref.mesh().num_nodes()},
                {"elements", ref.mesh().num_elements()},
                {"fixed_nodes", ref.fixed_fem_nodes().size()},
                {"level", st.level}};

  struct Case {
    Index site_index;
    double force;
    fem::ContactLoad load;
    MatX3 u_fem;
    double seconds;
    bool train;
  };
  std::vector<Case> cases;
  for (std::size_t si = 0; si < sites.size(); ++si)
    for (double F : forces) {
      Case c{static_cast<Index>(si),
             F,
             {o.surface.V.row(sites[si]).transpose(), -F * f.e3, st.radius},
             {},
             0,
             false};
      c.train = si < train_sites && F == train_force;
      bool cached = false;
      note(st, cat(o.name, ": FEM site ", si, ", ", F, " N"));
      c.u_fem = ref.surface_displacement(c.load, &c.seconds, &cached);
      cases.push_back(std::move(c));
    }
  double fem_seconds = 0;
  for (const auto& c : cases) fem_seconds += c.seconds;
  out["fem"]["median_solve_s"] = [&] {
    std::vector<double> v;
    for (const auto& c : cases) v.push_back(c.seconds);
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    return v[v.size() / 2];
  }();

  // mesh convergence of the reference: the contact displacement of the first case at the next level
  if (!st.quick && convergence) {
    fem::OrganMeshSettings fine = ms;
    fine.subdivisions = st.level;
    note(st, cat(o.name, ": FEM convergence (level ", st.level + 1, ")"));
    const fem::OrganReference ref2(o.surface, st.material, rule, fine);
    double secs = 0;
    const MatX3 u2 = ref2.surface_displacement(cases[0].load, &secs);
    const Index c = sites[0];
    out["fem"]["convergence"] = {
        {"level", st.level + 1},
        {"nodes", ref2.mesh().num_nodes()},
        {"contact_mm", u2.row(c).norm()},
        {"contact_mm_level", cases[0].u_fem.row(c).norm()},
        {"rel_change", (u2.row(c) - cases[0].u_fem.row(c)).norm() / u2.row(c).norm()},
        {"solve_s", secs}};
  }

  std::vector<fem::CalibrationCase> training;
  for (const auto& c : cases)
    if (c.train) training.push_back({c.load, c.u_fem, sites[static_cast<std::size_t>(c.site_index)]});

  json rows = json::array();
  if (kinds.empty()) {
    for (bool nl : {false, true})
      for (const char* b : {"surface", "hybrid", "volumetric"}) kinds.push_back({b, nl, false});
    kinds.push_back({"hybrid", true, true});
    kinds.push_back({"hybrid", false, true});
  }
  if (!st.kinds.empty())
    std::erase_if(
        kinds, [&](const Kind& k) {  // "volumetric" is the linear kind, "volumetric-duffing" the other
          const std::string token = k.base + (k.base == "volumetric" && k.nonlinear ? "-duffing" : "");
          return std::find(st.kinds.begin(), st.kinds.end(), token) == st.kinds.end();
        });
  o.E_kPa = st.material.E * 1e3;
  o.nu = st.material.nu;
  o.target_nodes = st.volumetric_nodes;
  if (std::any_of(kinds.begin(), kinds.end(), [](const Kind& k) { return k.base == "volumetric"; })) {
    const VolumetricMesh& vm = volumetric_mesh_of(o);
    out["volumetric"] = {{"nodes", vm.X.rows()},
                         {"surface_nodes", vm.surface_nodes},
                         {"tetrahedra", vm.T.rows()},
                         {"target_nodes", st.volumetric_nodes}};
  }
  // The displacement of kind k with its families scaled by m (+ local: the last multiplier scales k_loc).
  auto response = [&](const Kind& k, const VecX& m, const fem::ContactLoad& load) {
    const BodyPtr body = make_body(o, k, support, m);
    return k.local ? fem::spring_displacement_local(*body, load, body->local_stiffness() * m(k.local_index()))
                   : fem::spring_displacement(*body, load);
  };
  for (const Kind& k : kinds) {
    for (bool calibrated : {false, true}) {
      VecX m = VecX::Ones(k.families());
      if (calibrated) {
        note(st, cat(o.name, ": calibrating ", k.label()));
        if (k.base == "volumetric")
          m = calibrate_volumetric(
              [&](const VecX& mm, const fem::ContactLoad& l) { return response(k, mm, l); }, training);
        else
          m = fem::calibrate_multipliers(
              [&](const VecX& mm, const fem::ContactLoad& l) { return response(k, mm, l); }, k.families(),
              training, st.quick ? 1 : 2);
      }
      const BodyPtr body = make_body(o, k, support, m);
      json errs = json::array();
      double sum_rms_rel_held = 0, n_held = 0;
      for (const auto& c : cases) {
        MatX3 u;
        try {
          u = response(k, m, c.load);
        } catch (const SolverError& e) {
          errs.push_back({{"site", c.site_index}, {"force_N", c.force}, {"error", e.what()}});
          continue;
        }
        const Index contact = sites[static_cast<std::size_t>(c.site_index)];
        const fem::SurfaceError e = fem::compare(u, c.u_fem, contact);
        // the contact error split along the load and across it (a sliding of the contact node)
        const Vec3 fd = c.load.force.normalized(), du = (u.row(contact) - c.u_fem.row(contact)).transpose();
        const double along = std::abs(du.dot(fd)), across = (du - du.dot(fd) * fd).norm();
        errs.push_back({{"site", c.site_index},
                        {"contact_error_along_pct", 100 * e.rel(along)},
                        {"contact_error_across_pct", 100 * e.rel(across)},
                        {"force_N", c.force},
                        {"train", c.train},
                        {"contact_fem_mm", e.contact_fem},
                        {"contact_model_mm", e.contact_model},
                        {"contact_error_mm", e.contact_error},
                        {"contact_error_pct", 100 * e.rel(e.contact_error)},
                        {"rms_mm", e.rms},
                        {"rms_pct", 100 * e.rel(e.rms)},
                        {"max_mm", e.max},
                        {"max_pct", 100 * e.rel(e.max)}});
        if (!c.train) {
          sum_rms_rel_held += e.rel(e.rms);
          n_held += 1;
        }
        if (c.site_index == 0 && c.force == forces.back() && k.base == "hybrid" && !k.local && k.nonlinear) {
          const VecX d = (u - c.u_fem).rowwise().norm();
          maps[o.name + (calibrated ? " calibrated" : " default")] = {
              {"V", std::vector<double>(o.surface.V.data(), o.surface.V.data() + o.surface.V.size())},
              {"F", std::vector<Index>(o.surface.F.data(), o.surface.F.data() + o.surface.F.size())},
              {"error_mm", std::vector<double>(d.data(), d.data() + d.size())},
              {"title", cat(o.name, ": ", k.label(), calibrated ? ", calibrated" : ", default", " vs FEM, ",
                            c.force, " N at site 0")}};
        }
      }
      const double us = median_update_us(body, k, sites[0], -0.5 * f.e3, st.quick ? 100 : 500);
      rows.push_back({{"kind", k.label()},
                      {"base", k.base},
                      {"nonlinear", k.nonlinear},
                      {"local", k.local},
                      {"calibrated", calibrated},
                      {"multipliers", std::vector<double>(m.data(), m.data() + m.size())},
                      {"update_us", us},
                      {"held_out_mean_rms_pct", n_held > 0 ? 100 * sum_rms_rel_held / n_held : 0.0},
                      {"cases", errs}});
    }
  }
  out["models"] = rows;
  out["fem"]["total_solve_s"] = fem_seconds;
  return out;
}

// ---- The vessel (docs/accuracy.md, "The vessel"): SMRM centerline against the FEM wall ----------------

// An SMRM parameter set: the scene's own settings ("default"), the wall's E set to the material's
// ("material", what a scene's "material" block gives) and the material's with fitted multipliers on the
// chain springs k_cl, the return springs k_r and the bending stiffness k_b ("calibrated").
SmrmSettings vessel_settings(const SmrmSettings& base, const fem::Material& mat, bool material, const VecX& m,
                             bool nonlinear) {
  SmrmSettings s = base;
  if (material) s.wall.E = mat.E;
  s.chain.k *= m(0);
  s.chain.kr *= m(1);
  s.wall.E *= m(2);
  s.chain.nonlinear = nonlinear;
  if (nonlinear && m.size() > 3) s.chain.duffing.eta *= m(3);  // Duffing strength of the chain springs
  return s;
}

json run_vessel(Scene scene0, const std::string& name, const Settings& st, const fem::Material& mat,
                const fem::VesselMeshSettings& vms, FileLoader& loader) {
  require(scene0.model.kind == ModelKind::Smrm, "accuracy: the vessel scene must be an smrm model");
  scene0.loads.clear();  // the sites and loads are the table's
  scene0.record.atoms.clear();
  scene0.record.nodes.clear();
  const BuiltScene built = build_scene(scene0, &loader);
  const auto vessel = std::dynamic_pointer_cast<const SmrmVessel>(built.body);
  require(vessel != nullptr, "accuracy: the vessel scene did not build one SMRM vessel");
  const Index n = vessel->num_atoms(), M = vessel->grid().spokes;
  const MatX3& C0 = vessel->rest_atoms();
  const MatX3& S0 = vessel->rest_surface();
  const SmrmSettings& base = vessel->settings();
  const VecX kb0 = vessel->bending_stiffness();  // at base.wall.E (Wall mode: k_b is linear in E)
  require(base.bending == BendingMode::Wall, "accuracy: the vessel must use wall bending");

  std::vector<Index> sites;
  if (st.quick)
    sites = {n / 2, n / 3};
  else
    sites = {n / 2, n / 4, (3 * n) / 8, (5 * n) / 8, (3 * n) / 4};  // the first (the paper's atom) trains
  const std::vector<double> forces =
      st.quick ? std::vector<double>{0.005} : std::vector<double>{0.05, 0.5};  // the paper's light, strong
  // The paper's atom under the light force trains: the regime of a centerline model (under the strong
  // force the thin wall of the FEM folds, docs/accuracy.md); every other case is held out.
  auto is_train = [&](std::size_t si, double F) { return si == 0 && F == forces.front(); };
  json out = {{"vessel", name},
              {"atoms", n},
              {"surface_nodes", vessel->num_surface_nodes()},
              {"length_mm",
               [&] {
                 double l = 0;
                 for (Index i = 0; i + 1 < n; ++i) l += (C0.row(i + 1) - C0.row(i)).norm();
                 return l;
               }()},
              {"radius_min_mm", vessel->atom_radius().minCoeff()},
              {"radius_max_mm", vessel->atom_radius().maxCoeff()},
              {"thickness_ratio", vms.thickness_ratio},
              {"material", {{"E_kPa", mat.E * 1e3}, {"nu", mat.nu}}},
              {"default_wall_E_kPa", base.wall.E * 1e3},
              {"sites", sites},
              {"forces_N", forces},
              {"load",
               "uniform traction (fixed direction) over the outer wall within half an atom spacing of the "
               "loaded atom; the SMRM gets the whole force on that atom (D-14)"}};

  note(st, cat(name, ": meshing the wall"));
  const fem::VesselReference ref(*vessel, mat, vms);
  out["fem"] = {{"nodes", ref.tube().mesh.num_nodes()},         {"elements", ref.tube().mesh.num_elements()},
                {"fixed_nodes", ref.fixed_fem_nodes().size()},  {"spokes", ref.tube().spokes},
                {"axial_subdivisions", vms.axial_subdivisions}, {"layers", vms.layers}};

  struct Case {
    Index site_index, atom;
    double force;
    Vec3 F;
    fem::VesselFemResult fem;
    bool train;
  };
  std::vector<Case> cases;
  json fem_failed = json::array();  // loads under which CalculiX found no equilibrium (reported, not hidden)
  for (std::size_t si = 0; si < sites.size(); ++si)
    for (double F : forces) {
      const Index a = sites[si];
      const Vec3 d = (C0.row(a) - S0.row(a * M)).normalized();  // inward normal of spoke 0 of ring a
      note(st, cat(name, ": FEM atom ", a, ", ", F, " N"));
      try {
        Case c{static_cast<Index>(si), a, F, F * d, ref.solve(a, F * d), is_train(si, F)};
        cases.push_back(std::move(c));
      } catch (const SolverError& e) {
        note(st, cat(name, ": FEM atom ", a, ", ", F, " N: no equilibrium"));
        fem_failed.push_back({{"atom", a}, {"force_N", F}, {"train", is_train(si, F)}, {"error", e.what()}});
      }
    }
  out["fem_failed"] = fem_failed;
  require(!cases.empty() && cases[0].train, "accuracy: ", name,
          ": the FEM found no equilibrium for the training loads");
  {
    std::vector<double> v;
    for (const auto& c : cases) v.push_back(c.fem.solve_seconds);
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    out["fem"]["median_solve_s"] = v[v.size() / 2];
  }
  if (!st.quick) {  // mesh convergence: the light training case on a finer wall
    fem::VesselMeshSettings fine = vms;
    fine.spoke_stride = std::max<Index>(1, (2 * vms.spoke_stride) / 3);  // 10 -> 15 spokes of 30
    fine.axial_subdivisions = 2 * vms.axial_subdivisions;
    note(st, cat(name, ": FEM convergence (finer wall)"));
    const fem::VesselReference ref2(*vessel, mat, fine);
    const Case& c0 = cases[0];
    const fem::VesselFemResult r2 = ref2.solve(c0.atom, c0.F);
    out["fem"]["convergence"] = {
        {"nodes", ref2.tube().mesh.num_nodes()},
        {"spokes", ref2.tube().spokes},
        {"axial_subdivisions", fine.axial_subdivisions},
        {"layers", fine.layers},
        {"loaded_mm", r2.centerline.row(c0.atom).norm()},
        {"loaded_mm_level", c0.fem.centerline.row(c0.atom).norm()},
        {"rel_change", (r2.centerline.row(c0.atom) - c0.fem.centerline.row(c0.atom)).norm() /
                           r2.centerline.row(c0.atom).norm()},
        {"solve_s", r2.solve_seconds}};
  }

  std::vector<fem::CalibrationCase> training;
  for (const auto& c : cases)
    if (c.train) training.push_back({{C0.row(c.atom).transpose(), c.F, 0.0}, c.fem.centerline, c.atom});
  // The centerline of a parameter set: the chain with k_cl, k_r scaled and k_b = kb0 E / E_base.
  auto centerline = [&](const SmrmSettings& s, const Vec3& F, Index atom) {
    const VecX kb = kb0 * (s.wall.E / base.wall.E);
    const Model chain = make_chain_model(C0, s.chain, name, kb);
    return fem::smrm_centerline_displacement(chain, atom, F);
  };
  auto nearest_atom = [&](const Vec3& p) {
    Index best = 0;
    for (Index i = 1; i < n; ++i)
      if ((C0.row(i).transpose() - p).squaredNorm() < (C0.row(best).transpose() - p).squaredNorm()) best = i;
    return best;
  };
  json rows = json::array();
  for (bool nl : {false, true})
    for (const char* params : {"default", "material", "calibrated"}) {
      const bool material = std::string(params) != "default",
                 calibrated = std::string(params) == "calibrated";
      VecX m = VecX::Ones(nl ? 4 : 3);
      if (calibrated) {
        note(st, cat(name, ": calibrating SMRM", nl ? " (Duffing)" : " (linear)"));
        m = fem::calibrate_multipliers(
            [&](const VecX& mm, const fem::ContactLoad& l) {
              return centerline(vessel_settings(base, mat, true, mm, nl), l.force, nearest_atom(l.centre));
            },
            static_cast<Index>(m.size()), training, st.quick ? 1 : 2);
      }
      const SmrmSettings s = vessel_settings(base, mat, material, m, nl);
      json errs = json::array();
      for (const auto& c : cases) {
        MatX3 u;
        try {
          u = centerline(s, c.F, c.atom);
        } catch (const SolverError& e) {
          errs.push_back({{"atom", c.atom}, {"force_N", c.force}, {"error", e.what()}});
          continue;
        }
        const fem::CenterlineError e = fem::compare_centerline(u, c.fem.centerline, c.atom);
        State state = make_state(vessel->model());
        state.x = C0 + u;
        MatX3 surf;
        vessel->map_to_surface(state, surf);
        const VecX ds = ((surf - S0) - c.fem.lumen).rowwise().norm();
        const double lumen_rms = std::sqrt(ds.squaredNorm() / static_cast<double>(ds.size()));
        errs.push_back({{"atom", c.atom},
                        {"site", c.site_index},
                        {"force_N", c.force},
                        {"train", c.train},
                        {"loaded_fem_mm", e.loaded_fem},
                        {"loaded_model_mm", e.loaded_model},
                        {"loaded_error_mm", e.loaded_error},
                        {"loaded_error_pct", 100 * e.rel(e.loaded_error)},
                        {"rms_mm", e.rms},
                        {"rms_pct", 100 * e.rel(e.rms)},
                        {"max_mm", e.max},
                        {"max_pct", 100 * e.rel(e.max)},
                        {"lumen_rms_mm", lumen_rms},
                        {"lumen_rms_pct", 100 * e.rel(lumen_rms)}});
      }
      // time per update of this parameter set (the vessel rebuilt with it; stiffer = more sub-steps)
      Scene sc = scene0;
      sc.model.smrm = s;
      const BuiltScene b = build_scene(sc, &loader);
      SimulationSettings ss = b.settings;
      ss.local.enabled = false;
      ss.normals = false;
      Simulation sim(b.body, ss);
      sim.set_loads({{.node = sites[0] * M, .force = cases[0].F, .t_ramp = 0}});
      sim.advance(50);
      std::vector<double> us;
      for (int i = 0; i < (st.quick ? 100 : 500); ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        sim.update();
        us.push_back(
            std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
      }
      std::nth_element(us.begin(), us.begin() + static_cast<long>(us.size() / 2), us.end());
      rows.push_back({{"kind", std::string("SMRM") + (nl ? " (Duffing)" : " (linear)")},
                      {"nonlinear", nl},
                      {"params", params},
                      {"calibrated", calibrated},
                      {"multipliers", std::vector<double>(m.data(), m.data() + m.size())},
                      {"k_cl_N_per_mm", s.chain.k},
                      {"k_r_N_per_mm", s.chain.kr},
                      {"wall_E_kPa", s.wall.E * 1e3},
                      {"eta", nl ? s.chain.duffing.eta : 0.0},
                      {"update_us", us[us.size() / 2]},
                      {"cases", errs}});
    }
  out["models"] = rows;
  return out;
}

Organ phantom_organ() {
  const HybridKidney hk = hybrid_kidney_phantom();
  Organ o;
  o.name = "kidney phantom";
  o.surface = {hk.rest_surface(), hk.faces()};
  o.atoms = kidney_phantom_atoms();
  return o;
}

std::optional<Organ> real_kidney(const fs::path& scenes, FileLoader& loader, std::string& why) {
  const fs::path file = scenes / "kidney_1.0N_nonlinear.json";
  try {
    const Scene scene = load_scene(file);
    const BuiltScene built = build_scene(scene, &loader);
    Organ o;
    o.name = "real kidney";
    o.surface = {built.body->rest_surface(), built.body->faces()};
    o.atoms = built.atoms_rest;
    return o;
  } catch (const Error& e) {
    why = e.what();
    return std::nullopt;
  }
}

std::string pct(double v) {
  return cat(std::round(v * 10) / 10);
}

std::string markdown(const json& j) {
  std::ostringstream md;
  md << "# MedSpring accuracy against the CalculiX FEM reference\n\n";
  md << "Material: compressible Neo-Hookean, E = " << j["material"]["E_kPa"].get<double>()
     << " kPa, nu = " << j["material"]["nu"].get<double>()
     << ". Loads: uniform traction over a contact disk of radius " << j["contact_radius_mm"].get<double>()
     << " mm, the same total force and distribution on the FEM "
     << "boundary and on the spring surface. Support: surface nodes within 20 % of the thickness of the "
     << "extreme point opposite the load (fixed in the FEM, pinned in the springs). Spring models are "
        "compared "
     << "at their static equilibrium. Errors in mm and in % of the FEM contact displacement.\n\n";
  md << "## FEM pipeline against closed forms\n\n| case | level | nodes | quantity | FEM | analytic | error "
        "% | solve s |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& v : j["validation"])
    md << "| " << v["name"].get<std::string>() << " | " << v["level"] << " | " << v["nodes"] << " | "
       << v["quantity"].get<std::string>() << " | " << v["fem"].get<double>() << " | "
       << v["analytic"].get<double>() << " | " << pct(100 * v["rel_error"].get<double>()) << " | "
       << pct(v["solve_s"].get<double>()) << " |\n";
  for (const auto& o : j["organs"]) {
    md << "\n## " << o["organ"].get<std::string>() << "\n\n";
    md << "FEM: " << o["fem"]["nodes"] << " nodes, " << o["fem"]["elements"]
       << " quadratic tetrahedra (C3D10), " << o["fem"]["fixed_nodes"] << " fixed; median CalculiX solve "
       << pct(o["fem"]["median_solve_s"].get<double>()) << " s. Spring support: " << o["support_nodes"]
       << " pinned surface nodes.\n";
    if (o["fem"].contains("convergence")) {
      const auto& c = o["fem"]["convergence"];
      md << "Mesh convergence of the reference (site 0, 0.2 N): contact displacement "
         << c["contact_mm_level"].get<double>() << " mm -> " << c["contact_mm"].get<double>()
         << " mm at level " << c["level"] << " (" << c["nodes"] << " nodes): change "
         << pct(100 * c["rel_change"].get<double>()) << " % (target < 2 %).\n";
    }
    if (o.contains("volumetric"))
      md << "Volumetric spring model: " << o["volumetric"]["nodes"] << " nodes ("
         << o["volumetric"]["surface_nodes"] << " on the surface), " << o["volumetric"]["tetrahedra"]
         << " linear tetrahedra (TetGen -pqY).\n";
    md << "\n| model | parameters | update us | case | contact FEM mm | contact model mm | contact err % | "
          "RMS mm | RMS % | max mm | max % |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : o["models"]) {
      for (const auto& c : r["cases"]) {
        md << "| " << r["kind"].get<std::string>() << " | "
           << (r["calibrated"].get<bool>() ? "calibrated" : "default") << " | "
           << pct(r["update_us"].get<double>()) << " | site " << c["site"] << ", "
           << c["force_N"].get<double>() << " N";
        if (c.contains("error")) {
          md << " | no equilibrium | | | | | | |\n";
          continue;
        }
        md << (c["train"].get<bool>() ? " (train)" : "") << " | " << pct(c["contact_fem_mm"].get<double>())
           << " | " << pct(c["contact_model_mm"].get<double>()) << " | "
           << pct(c["contact_error_pct"].get<double>()) << " | " << pct(c["rms_mm"].get<double>()) << " | "
           << pct(c["rms_pct"].get<double>()) << " | " << pct(c["max_mm"].get<double>()) << " | "
           << pct(c["max_pct"].get<double>()) << " |\n";
      }
    }
  }
  for (const auto& v : j.value("vessels", json::array())) {
    md << "\n## " << v["vessel"].get<std::string>() << ": SMRM centerline against the FEM wall\n\n";
    md << "The wall as a tube of quadratic tetrahedra around the SMRM's rest rings (" << v["atoms"]
       << " atoms, length " << pct(v["length_mm"].get<double>()) << " mm, lumen radius "
       << pct(v["radius_min_mm"].get<double>()) << "-" << pct(v["radius_max_mm"].get<double>())
       << " mm), wall thickness " << v["thickness_ratio"].get<double>()
       << " x the lumen radius, both end rings clamped; E = " << v["material"]["E_kPa"].get<double>()
       << " kPa, nu = " << v["material"]["nu"].get<double>() << ". FEM: " << v["fem"]["nodes"] << " nodes, "
       << v["fem"]["elements"] << " C3D10 (" << v["fem"]["spokes"] << " spokes, "
       << v["fem"]["axial_subdivisions"] << " rings per atom interval, " << v["fem"]["layers"]
       << " layer(s) through the wall); median CalculiX solve "
       << pct(v["fem"]["median_solve_s"].get<double>()) << " s. Load: " << v["load"].get<std::string>()
       << ". Compared: the SMRM atoms against the centroid of the FEM wall's mid-surface ring at each atom, "
          "in % of the FEM displacement of the loaded atom; lumen = the SMRM's rebuilt surface against the "
          "FEM lumen (RMS). Parameters: default = the scene's (wall E "
       << v["default_wall_E_kPa"].get<double>()
       << " kPa), material = wall E set to the material's, calibrated = the material's with k_cl, k_r, k_b "
          "fitted on the (train) cases.\n";
    if (v["fem"].contains("convergence")) {
      const auto& c = v["fem"]["convergence"];
      md << "Mesh convergence (first case on a wall of " << c["nodes"] << " nodes, " << c["spokes"]
         << " spokes, " << c["axial_subdivisions"] << " rings per interval, " << c["layers"]
         << " layers): loaded-atom displacement " << c["loaded_mm_level"].get<double>() << " mm -> "
         << c["loaded_mm"].get<double>() << " mm, change " << pct(100 * c["rel_change"].get<double>())
         << " %.\n";
    }
    for (const auto& f : v.value("fem_failed", json::array()))
      md << "CalculiX found no equilibrium at atom " << f["atom"] << ", " << f["force_N"].get<double>()
         << " N (left out of the table): " << f["error"].get<std::string>().substr(0, 160) << "\n";
    md << "\n| model | parameters | update us | case | loaded FEM mm | loaded SMRM mm | loaded err % | "
          "centerline RMS % | centerline max % | lumen RMS % |\n|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : v["models"])
      for (const auto& c : r["cases"]) {
        md << "| " << r["kind"].get<std::string>() << " | " << r["params"].get<std::string>() << " | "
           << pct(r["update_us"].get<double>()) << " | atom " << c["atom"] << ", "
           << c["force_N"].get<double>() << " N";
        if (c.contains("error")) {
          md << " | no equilibrium | | | | | |\n";
          continue;
        }
        md << (c["train"].get<bool>() ? " (train)" : "") << " | " << pct(c["loaded_fem_mm"].get<double>())
           << " | " << pct(c["loaded_model_mm"].get<double>()) << " | "
           << pct(c["loaded_error_pct"].get<double>()) << " | " << pct(c["rms_pct"].get<double>()) << " | "
           << pct(c["max_pct"].get<double>()) << " | " << pct(c["lumen_rms_pct"].get<double>()) << " |\n";
      }
  }
  if (j.contains("indentation")) md << indentation_markdown(j["indentation"]);
  md << "\nFigures: figures/speed_accuracy.png (time per update against the mean held-out RMS error, FEM "
        "solve "
        "time for scale), figures/error_*.png (surface error maps).\n";
  return md.str();
}

}  // namespace

int cmd_accuracy(const Args& args) {
  args.require_known({"out",          "force",      "quick",         "quiet",       "json",
                      "E-kPa",        "nu",         "radius",        "level",       "scenes",
                      "kinds",        "nodes",      "no-validation", "forces",      "organs",
                      "vessel-E-kPa", "wall-ratio", "no-vessel",     "vessel-only", "indentation-only"});
  const auto out = args.get("out");
  if (!out) throw InvalidInput("accuracy: --out DIR is required");
  Settings st;
  st.material = fem::Material::from_kpa(args.number("E-kPa", 10.0), args.number("nu", 0.45));
  fem::validate_material(st.material, "accuracy: --E-kPa/--nu");
  st.radius = args.number("radius", 8.0);
  require(std::isfinite(st.radius) && st.radius > 0, "accuracy: --radius must be > 0 mm");
  st.quick = args.flag("quick");
  st.quiet = args.flag("quiet") || args.flag("json");
  st.level = static_cast<int>(args.integer("level", 1));
  require(st.level >= 1 && st.level <= 3, "accuracy: --level must be 1, 2 or 3");
  read_kind_options(args, st, "accuracy");
  const bool force = args.flag("force");
  check_output_folder(*out, force);

  json j = {{"material", {{"E_kPa", st.material.E * 1e3}, {"nu", st.material.nu}}},
            {"contact_radius_mm", st.radius},
            {"quick", st.quick},
            {"units", "mm, N, MPa; times in s (FEM) and us (updates)"}};
  const bool vessel_only = args.flag("vessel-only");
  require(!(vessel_only && args.flag("no-vessel")),
          "accuracy: --vessel-only and --no-vessel exclude each other");
  const bool indentation_only = args.flag("indentation-only");  // issue 18: only the sphere indentation
  require(!(vessel_only && indentation_only),
          "accuracy: --vessel-only and --indentation-only exclude each other");
  json val = json::array();
  for (int level = 1; level <= (args.flag("no-validation") || vessel_only || indentation_only ? 0
                                : st.quick                                                    ? 1
                                                                                              : 3);
       ++level) {
    note(st, cat("validation level ", level));
    std::vector<fem::ValidationResult> rs = {fem::validate_uniaxial(level), fem::validate_cantilever(level)};
    if (!st.quick || level == 1)
      for (const auto& r : fem::validate_boussinesq(level)) rs.push_back(r);
    for (const auto& r : rs)
      val.push_back({{"name", r.name},
                     {"level", r.level},
                     {"nodes", r.nodes},
                     {"quantity", r.quantity},
                     {"fem", r.fem},
                     {"analytic", r.analytic},
                     {"rel_error", r.rel_error},
                     {"solve_s", r.solve_seconds}});
  }
  j["validation"] = val;

  // --organs phantom,kidney (default both; --quick: the phantom)
  const std::string organ_list = args.get_or("organs", "phantom,kidney");
  require(organ_list == "phantom" || organ_list == "kidney" || organ_list == "phantom,kidney" ||
              organ_list == "kidney,phantom",
          "accuracy: --organs must be phantom, kidney or phantom,kidney (got '", organ_list, "')");
  std::vector<Organ> organs;
  if (!vessel_only && organ_list.find("phantom") != std::string::npos) organs.push_back(phantom_organ());
  FileLoader loader;
  if ((!st.quick || indentation_only) && !vessel_only && organ_list.find("kidney") != std::string::npos) {
    const fs::path scenes =
        find_folder(args.get("scenes"), MEDSPRING_SOURCE_SCENES_DIR, "scenes", "bundled scenes", "phantom");
    std::string why;
    if (auto k = real_kidney(scenes, loader, why))
      organs.push_back(std::move(*k));
    else
      j["notes"].push_back("real kidney left out: " + why);
  }
  // The vessel material and wall (checked before any solve)
  const fem::Material vessel_mat =
      fem::Material::from_kpa(args.number("vessel-E-kPa", 1e3 * SmrmSettings{}.wall.E), st.material.nu);
  fem::validate_material(vessel_mat, "accuracy: --vessel-E-kPa");
  fem::VesselMeshSettings vms;  // 10 FEM spokes, one ring per atom interval: ~4,400 nodes on the aorta
  vms.spoke_stride = 3;
  vms.axial_subdivisions = 1;
  vms.solver.increments = 2;
  vms.thickness_ratio = args.number("wall-ratio", SmrmSettings{}.wall.thickness_ratio);
  require(std::isfinite(vms.thickness_ratio) && vms.thickness_ratio > 0 && vms.thickness_ratio <= 1,
          "accuracy: --wall-ratio must be in (0, 1] (wall thickness / lumen radius)");
  json maps = json::object();
  j["organs"] = json::array();
  for (const auto& o : organs)
    if (!indentation_only) j["organs"].push_back(run_organ(o, st, maps));
  if (!args.flag("no-vessel") && !indentation_only) {
    const fs::path scenes =
        find_folder(args.get("scenes"), MEDSPRING_SOURCE_SCENES_DIR, "scenes", "bundled scenes", "phantom");
    Scene vs = load_scene(scenes / "phantom" / "vessel_light_nonlinear.json");
    std::string vname = "vessel phantom (straight)";
    if (st.quick) {
      vs.model.atoms = 12;  // 27.5 mm of the straight phantom: a wall mesh that solves in seconds
      vs.model.smrm.atoms = 12;
    } else {
      try {
        Scene real = load_scene(scenes / "vessel_light_nonlinear.json");
        build_scene(real, &loader);  // the aorta centerline must be readable
        vs = real;
        vname = "aorta (VMR 0159)";
      } catch (const Error& e) {
        j["notes"].push_back(std::string("real aorta left out (phantom vessel used): ") + e.what());
      }
    }
    vs.model.smrm.wall.thickness_ratio = vms.thickness_ratio;
    j["vessels"].push_back(run_vessel(vs, vname, st, vessel_mat, vms, loader));
  }
  if ((!st.quick || indentation_only) && !vessel_only && !organs.empty()) {  // a rigid sphere (issue 18)
    const Organ& o = organs.back();  // the real kidney when it could be built
    const Frame f = principal_frame(o.surface.V);
    IndentationOrgan io{o.name,
                        o.surface,
                        o.atoms,
                        o.name == "real kidney" ? TissueOrgan::RealKidney : TissueOrgan::Phantom,
                        o.surface.V.row(pick_sites(o.surface.V, f, {-0.45})[0]).transpose(),
                        -f.e3,
                        fem::SupportRule{-f.e3, 0.2 * f.thickness}};
    IndentationSettings is;
    is.material = st.material;
    is.level = st.level;
    is.note = [&](const std::string& m) { note(st, m); };
    note(st, "indentation: Hertz validation");
    j["indentation"]["hertz"] = hertz_validation_json(is.hertz_level);
    j["indentation"]["organs"].push_back(indentation_study(io, is));
  }

  const fs::path scripts = find_folder(std::nullopt, MEDSPRING_SOURCE_PAPER_SCRIPTS_DIR, "scripts",
                                       "figure scripts", "accuracy_plots.py");
  const char* py_env = std::getenv("MEDSPRING_PYTHON");
  const std::string python = py_env && *py_env ? py_env : "/usr/bin/python3";
  write_output_folder(*out, force, [&](const fs::path& dir) {
    fs::create_directories(dir / "figures");
    std::ofstream(dir / "accuracy.json") << j.dump(1) << '\n';
    std::ofstream(dir / "error_maps.json") << maps.dump() << '\n';
    std::ofstream(dir / "accuracy.md") << markdown(j);
    const std::string cmd = "'" + python + "' '" + (scripts / "accuracy_plots.py").string() + "' '" +
                            dir.string() + "' > '" + (dir / "figures.log").string() + "' 2>&1";
    if (std::system(cmd.c_str()) != 0)
      throw Error(cat("accuracy: the figures failed (python3 with matplotlib); see ",
                      (dir / "figures.log").string()));
    fs::remove(dir / "figures.log");
  });
  // The full run is kept as the latest for `medspring paper`'s summary (accuracy_summary.hpp).
  if (!st.quick && !vessel_only && !indentation_only && !keep_latest_accuracy(j) && !args.flag("json"))
    std::cout << "accuracy: note: could not keep the run as " << latest_accuracy_path().string() << std::endl;
  if (args.flag("json"))
    std::cout << j.dump(1) << '\n';
  else
    std::cout << "accuracy: wrote " << *out << "/accuracy.md, accuracy.json and figures/" << std::endl;
  return 0;
}

}  // namespace medspring::cli

namespace medspring::cli {

int cmd_calibrate(const Args& args) {
  args.require_known(
      {"organ", "kind", "linear", "E-kPa", "nu", "radius", "json", "quiet", "scenes", "nodes"});
  Settings st;
  st.material = fem::Material::from_kpa(args.number("E-kPa", 10.0), args.number("nu", 0.45));
  fem::validate_material(st.material, "calibrate: --E-kPa/--nu");
  st.radius = args.number("radius", 8.0);
  require(std::isfinite(st.radius) && st.radius > 0, "calibrate: --radius must be > 0 mm");
  st.quiet = args.flag("quiet") || args.flag("json");
  const std::string organ = args.get_or("organ", "phantom"), kind = args.get_or("kind", "hybrid");
  require(organ == "phantom" || organ == "kidney", "calibrate: --organ must be phantom or kidney");
  require(kind == "hybrid" || kind == "surface" || kind == "volumetric",
          "calibrate: --kind must be hybrid, surface or volumetric");
  read_kind_options(args, st, "calibrate");
  Organ o;
  FileLoader loader;
  if (organ == "phantom") {
    o = phantom_organ();
  } else {
    const fs::path scenes =
        find_folder(args.get("scenes"), MEDSPRING_SOURCE_SCENES_DIR, "scenes", "bundled scenes", "phantom");
    std::string why;
    auto k = real_kidney(scenes, loader, why);
    if (!k) throw InvalidInput("calibrate: the real kidney could not be built: " + why);
    o = std::move(*k);
  }
  json maps;
  const json r = run_organ(o, st, maps, {{kind, !args.flag("linear"), false}}, false);
  json out = {{"organ", r["organ"]}, {"material", {{"E_kPa", st.material.E * 1e3}, {"nu", st.material.nu}}}};
  for (const auto& m : r["models"]) {
    if (!m["calibrated"].get<bool>()) {
      out["default_held_out_mean_rms_pct"] = m["held_out_mean_rms_pct"];
      continue;
    }
    const auto mult = m["multipliers"].get<std::vector<double>>();
    out["multipliers"] = mult;
    if (kind == "surface")
      out["parameters"] = {{"k_N_per_mm", 0.05 * mult[0]}, {"k_r_N_per_mm", 0.02 * mult[1]}};
    else if (kind == "volumetric")
      out["parameters"] = {{"spring_scale", mult[0]}, {"volume_scale", mult[1]}};
    else
      out["parameters"] = {{"k_surf_N_per_mm", 0.05 * mult[0]},
                           {"k_spoke_N_per_mm", 0.05 * mult[1]},
                           {"k_cl_N_per_mm", 0.1 * mult[2]},
                           {"k_r_N_per_mm", 0.02 * mult[3]},
                           {"k_loc_N_per_mm", 0.05 * mult[0]}};
    if (!args.flag("linear") && mult.size() > (kind == "surface" ? 2u : 4u))
      out["parameters"]["eta"] = mult[kind == "surface" ? 2 : 4];  // Duffing strength (D-3), default 1
    out["held_out_mean_rms_pct"] = m["held_out_mean_rms_pct"];
    out["cases"] = m["cases"];
  }
  if (args.flag("json")) {
    std::cout << out.dump(1) << '\n';
    return 0;
  }
  std::cout << "calibrate: " << o.name << ", " << kind << (args.flag("linear") ? " (linear)" : " (Duffing)")
            << ", E = " << st.material.E * 1e3 << " kPa, nu = " << st.material.nu << "\n";
  for (const auto& [key, v] : out["parameters"].items())
    std::cout << "  " << key << " = " << v.get<double>() << "\n";
  std::cout << "  held-out mean RMS surface error: " << out["held_out_mean_rms_pct"].get<double>()
            << " % of the FEM contact displacement (default parameters: "
            << out["default_held_out_mean_rms_pct"].get<double>() << " %)\n";
  for (const auto& c : out["cases"])
    if (c.contains("train") && !c["train"].get<bool>())
      std::cout << "  held out: site " << c["site"] << ", " << c["force_N"].get<double>() << " N: contact "
                << c["contact_error_pct"].get<double>() << " %, RMS " << c["rms_pct"].get<double>() << " %\n";
  return 0;
}

}  // namespace medspring::cli
