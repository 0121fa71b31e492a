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

#include "accuracy_summary.hpp"
#include "commands.hpp"
#include "medspring/builders/output_folder.hpp"
#include "medspring/core/check.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/validation.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/surface_body.hpp"
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
  Index families() const {
    return (base == "surface" || base == "volumetric" ? 2 : 4) + (local ? 1 : 0);  // + k_loc
  }
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
    const Index nb = k.families() - (k.local ? 1 : 0);
    const BodyPtr body = make_body(o, k, support, m.head(nb));
    return k.local ? fem::spring_displacement_local(*body, load, body->local_stiffness() * m(nb))
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
      const Index nb = k.families() - (k.local ? 1 : 0);
      const BodyPtr body = make_body(o, k, support, m.head(nb));
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
        errs.push_back({{"site", c.site_index},
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
  md << "\nFigures: figures/speed_accuracy.png (time per update against the mean held-out RMS error, FEM "
        "solve "
        "time for scale), figures/error_*.png (surface error maps).\n";
  return md.str();
}

}  // namespace

int cmd_accuracy(const Args& args) {
  args.require_known({"out", "force", "quick", "quiet", "json", "E-kPa", "nu", "radius", "level", "scenes",
                      "kinds", "nodes", "no-validation", "forces", "organs"});
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
  json val = json::array();
  for (int level = 1; level <= (args.flag("no-validation") ? 0 : st.quick ? 1 : 3); ++level) {
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
  if (organ_list.find("phantom") != std::string::npos) organs.push_back(phantom_organ());
  FileLoader loader;
  if (!st.quick && organ_list.find("kidney") != std::string::npos) {
    const fs::path scenes =
        find_folder(args.get("scenes"), MEDSPRING_SOURCE_SCENES_DIR, "scenes", "bundled scenes", "phantom");
    std::string why;
    if (auto k = real_kidney(scenes, loader, why))
      organs.push_back(std::move(*k));
    else
      j["notes"].push_back("real kidney left out: " + why);
  }
  json maps = json::object();
  for (const auto& o : organs) j["organs"].push_back(run_organ(o, st, maps));

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
  if (!st.quick && !keep_latest_accuracy(j) && !args.flag("json"))
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
