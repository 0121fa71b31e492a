// `medspring accuracy` / `calibrate`: the organ tables (docs/accuracy.md) — FEM cases under matched supports
// and contact loads, every model kind with default and calibrated stiffnesses, errors on held-out cases.
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
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
#include "accuracy_overlay.hpp"
#include "accuracy_regions.hpp"
#include "accuracy_summary.hpp"
#include "accuracy_tables.hpp"
#include "accuracy_volume_terms.hpp"
#include "commands.hpp"
#include "medspring/core/check.hpp"
#include "medspring/fem/local_site.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/validation.hpp"
#include "medspring/fem/vessel.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/io/data_dir.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/io/output_folder.hpp"
#include "medspring/medial/chain.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/models/tissue.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/models/volumetric_moduli.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/sim/simulation.hpp"
#include "scene_support.hpp"
#ifdef MEDSPRING_HAVE_MESHING
#include "medspring/meshing/balloon.hpp"
#endif

namespace medspring::cli::accuracy {

namespace fs = std::filesystem;

namespace {

const VolumetricMesh& volumetric_mesh_of(const Organ& o) {
  if (!o.vmesh)
    o.vmesh = std::make_shared<const VolumetricMesh>(
        fem::volumetric_mesh(o.surface, {.target_nodes = o.target_nodes,
                                         .surface_subdivisions = o.surface_subdivisions,
                                         .sizing = o.interior_sizing}));
  return *o.vmesh;
}

// The volumetric model's surface displacement at `surface`'s vertices (the first rows of its own surface,
// which is `surface` subdivided o.surface_subdivisions times), where the FEM's is sampled.
MatX3 on_organ_surface(const Organ& o, const MatX3& u) {
  return u.topRows(o.surface.num_vertices());
}

// Stiffness families: surface (k, k_r); hybrid (k_surf, k_spoke, k_cl, k_r); multipliers m scale them.
// Volumetric: (springs, volume terms) from E and nu (docs/volumetric.md); no return springs (supports).
BodyPtr make_body(const Organ& o, const Kind& k, const std::vector<Index>& support, const VecX& m) {
  if (k.base == "volumetric") {
    VolumetricSettings s;
    s.E_kPa = o.E_kPa;
    s.nu = o.nu;
    s.spring_scale = m(0);
    s.volume_scale = m(1);
    s.moduli_correction = k.corrected;
    s.compression = o.compression * (m.size() > 2 ? m(2) : 1.0);  // m(2): the nonlinear fit's c multiplier
    // --fit-surface-springs: the surface-layer family (volumetric + local holds the overlay compliance there)
    if (m.size() > 3 && !k.local) s.surface_spring_scale = m(3);
    s.thin_tet = o.thin_tet;  // opt-in thin-tetrahedron terms (docs/volumetric-mesh.md)
    s.thin_tet_q_max = o.thin_tet_q_max;
    if (k.nonlinear) s.duffing = DuffingSettings{};  // Strain, eta = 1 (D-3)
    s.fixed = o.surface_subdivisions > 0 ? o.vsupport : support;
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

double median_update_us(const BodyPtr& body, const Kind& k, Index contact, const Vec3& F, int samples) {
  SimulationSettings ss;
  ss.local.enabled = k.local;
  ss.normals = false;
  if (k.linear_static) ss.step.integrator = Integrator::LinearStatic;
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

}  // namespace

// Everything measured on one organ.
json run_organ(const Organ& o, const Settings& st, json& maps, std::vector<Kind> kinds, bool convergence) {
  const Frame f = principal_frame(o.surface.V);
  const fem::SupportRule rule = o.support ? *o.support : fem::SupportRule{-f.e3, 0.2 * f.thickness};
  const std::vector<Index> support = fem::support_nodes(o.surface, rule);
  const std::vector<double> ts =
      st.quick ? std::vector<double>{-0.3, 0.3} : std::vector<double>{-0.45, -0.15, 0.15, 0.45};
  const std::vector<Index> sites = pick_sites(o.surface.V, f, ts);
  const std::vector<double> forces = !st.forces.empty() ? st.forces
                                     : st.quick         ? std::vector<double>{0.5}
                                                        : std::vector<double>{0.2, 0.5, 1.0};
  // training force: 0.5 N, or the smallest of --forces without it (large-strain runs train on small loads)
  const std::vector<double> train_forces =
      !st.train_forces.empty() ? st.train_forces
      : std::find(forces.begin(), forces.end(), 0.5) != forces.end()
          ? std::vector<double>{0.5}
          : std::vector<double>{*std::min_element(forces.begin(), forces.end())};
  for (double tf : train_forces)
    require(std::find(forces.begin(), forces.end(), tf) != forces.end(), "accuracy: --train-force ", tf,
            " N is not one of the forces");
  // training: the first site (quick) or the first two sites, or --train-sites; every other case is held out
  const std::vector<int> train_sites = !st.train_sites.empty() ? st.train_sites
                                       : st.quick              ? std::vector<int>{0}
                                                               : std::vector<int>{0, 1};
  for (int s : train_sites)
    require(static_cast<std::size_t>(s) < sites.size(), "accuracy: --train-sites ", s, " is not one of the ",
            sites.size(), " sites (0..", sites.size() - 1, ")");
  require(train_sites.size() < sites.size() || train_forces.size() < forces.size(),
          "accuracy: --train-sites and --train-force leave no case held out");
  const auto trains = [&](Index site) {
    return std::find(train_sites.begin(), train_sites.end(), static_cast<int>(site)) != train_sites.end();
  };
  json out = {{"organ", o.name},
              {"surface_nodes", o.surface.num_vertices()},
              {"support_nodes", support.size()},
              {"support_rule",
               {{"direction", {rule.direction(0), rule.direction(1), rule.direction(2)}},
                {"depth_mm", rule.depth},
                {"facing_deg", rule.facing_deg},
                {"caps",
                 [&] {
                   json caps = json::array();
                   for (const auto& [d, depth] : rule.caps)
                     caps.push_back({{"direction", {d(0), d(1), d(2)}}, {"depth_mm", depth}});
                   return caps;
                 }()},
                {"text", o.support_text}}},
              {"contact_radius_mm", st.radius},
              {"sites", sites},
              {"train_sites", train_sites}};

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
    Vec3 fem_mean = Vec3::Zero();  // the FEM's mean displacement over the disk (the site read-out by area)
  };
  std::vector<Case> cases;
  json fem_failed = json::array();
  json fem_strain = json::array();
  for (std::size_t si = 0; si < sites.size(); ++si)
    for (double F : forces) {
      Case c{static_cast<Index>(si),
             F,
             {o.surface.V.row(sites[si]).transpose(), -F * f.e3, st.radius},
             {},
             0,
             false};
      c.train = trains(static_cast<Index>(si)) &&
                std::find(train_forces.begin(), train_forces.end(), F) != train_forces.end();
      bool cached = false;
      note(st, cat(o.name, ": FEM site ", si, ", ", F, " N"));
      MatX3 u_nodes;
      try {
        c.u_fem = ref.surface_displacement(c.load, &c.seconds, &cached, &c.fem_mean, &u_nodes);
      } catch (const SolverError& e) {  // e.g. no equilibrium at a large strain: reported, not hidden
        note(st, cat(o.name, ": FEM site ", si, ", ", F, " N: no equilibrium"));
        fem_failed.push_back({{"site", si}, {"force_N", F}, {"train", c.train}, {"error", e.what()}});
        continue;
      }
      // the strain the FEM reaches (large-strain runs, docs/accuracy.md): nominal = contact displacement /
      // the organ's thickness along the load; peak = the largest principal strains of any FEM element
      const fem::PeakStrain ps = fem::peak_strain(ref.mesh(), u_nodes);
      const double contact_mm = c.u_fem.row(sites[si]).norm();
      fem_strain.push_back({{"site", si},
                            {"force_N", F},
                            {"contact_mm", contact_mm},
                            {"nominal_strain_pct", 100 * contact_mm / f.thickness},
                            {"peak_compressive_strain_pct", 100 * ps.compressive},
                            {"peak_tensile_strain_pct", 100 * ps.tensile}});
      cases.push_back(std::move(c));
    }
  out["fem_failed"] = fem_failed;
  out["fem"]["thickness_mm"] = f.thickness;
  out["fem"]["strain"] = fem_strain;
  require(!cases.empty(), "accuracy: ", o.name, ": CalculiX found no equilibrium for any load");
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

  // the training cases of kind k; with --site-readout disk-mean their site term is the disk mean on the
  // model's own surface (a volumetric model's may be refined: its first rows are the organ's nodes)
  auto training_for = [&](const Kind& k) {
    std::vector<fem::CalibrationCase> training;
    for (const auto& c : cases) {
      if (!c.train) continue;
      fem::CalibrationCase t{c.load, c.u_fem, sites[static_cast<std::size_t>(c.site_index)]};
      t.site_weight = st.site_weight;  // --site-weight
      if (st.site_disk_mean) {
        t.fem_mean = c.fem_mean;
        if (k.base == "volumetric") {
          const VolumetricMesh& vm = volumetric_mesh_of(o);
          t.mean_weights = fem::disk_mean_weights(vm.X.topRows(vm.surface_nodes), vm.F, c.load);
        } else
          t.mean_weights = fem::disk_mean_weights(o.surface.V, o.surface.F, c.load);
      }
      training.push_back(std::move(t));
    }
    return training;
  };

  json rows = json::array();
  if (kinds.empty()) {
    for (bool nl : {false, true})
      for (const char* b : {"surface", "hybrid", "volumetric"}) kinds.push_back({b, nl, false});
    kinds.push_back({"hybrid", true, true});
    kinds.push_back({"hybrid", false, true});
  }
  if (std::find(st.kinds.begin(), st.kinds.end(), "volumetric-corrected") != st.kinds.end())
    kinds.push_back({"volumetric", false, false, true});  // opt-in, linear: the moduli correction
  if (std::find(st.kinds.begin(), st.kinds.end(), "volumetric-local") != st.kinds.end())
    kinds.push_back({"volumetric", false, true});  // opt-in, linear: the disk overlay as a site family
  if (std::find(st.kinds.begin(), st.kinds.end(), "volumetric-static") != st.kinds.end())
    kinds.push_back({"volumetric", false, false, false, true});  // opt-in: the quasi-static linear response
  if (o.atoms.rows() == 0 &&
      std::erase_if(kinds, [](const Kind& k) { return k.base == "hybrid"; }) > 0)  // no medial skeleton
    out["notes"].push_back(
        "hybrid kind left out: it needs a medial skeleton (a kidney's), this organ has none");
  if (!st.kinds.empty())
    std::erase_if(kinds,
                  [&](const Kind& k) {  // "volumetric" is the linear kind, "volumetric-duffing" the other
                    const std::string token = k.base + (k.base == "volumetric" && k.nonlinear ? "-duffing"
                                                        : k.linear_static                     ? "-static"
                                                        : k.corrected                         ? "-corrected"
                                                        : k.base == "volumetric" && k.local   ? "-local"
                                                                                              : "");
                    return std::find(st.kinds.begin(), st.kinds.end(), token) == st.kinds.end();
                  });
  o.E_kPa = st.material.E * 1e3;
  o.nu = st.material.nu;
  o.target_nodes = st.volumetric_nodes;
  o.compression = st.compression;
  o.thin_tet = st.thin_tet;
  o.thin_tet_q_max = st.thin_tet_q_max;
  o.surface_subdivisions = st.surface_subdivisions;
  o.interior_sizing = st.interior_sizing;
  if (std::any_of(kinds.begin(), kinds.end(), [](const Kind& k) { return k.base == "volumetric"; })) {
    const VolumetricMesh& vm = volumetric_mesh_of(o);
    if (o.surface_subdivisions > 0)  // the same rule on the refined surface (its mid-edge points too)
      o.vsupport = fem::support_nodes(SurfaceMesh{vm.X.topRows(vm.surface_nodes), vm.F}, rule);
    out["volumetric"] = {{"nodes", vm.X.rows()},
                         {"surface_nodes", vm.surface_nodes},
                         {"surface_subdivisions", o.surface_subdivisions},
                         {"interior_sizing", to_string(o.interior_sizing)},
                         {"tetrahedra", vm.T.rows()},
                         {"target_nodes", st.volumetric_nodes},
                         {"compression", st.compression},
                         {"thin_tet", to_string(st.thin_tet)},
                         {"thin_tet_q_max", st.thin_tet_q_max}};
    // the mesh's effective moduli from E and nu (docs/volumetric.md, "Effective moduli of the mesh")
    for (const auto& [label, sv] : std::vector<std::pair<std::string, std::pair<double, double>>>{
             {"springs+volume", {1.0, 1.0}}, {"springs", {1.0, 0.0}}}) {
      VecX m(2);
      m << sv.first, sv.second;
      const BodyPtr b = make_body(o, {"volumetric", false, false}, support, m);
      const auto* vb = dynamic_cast<const VolumetricBody*>(b.get());
      const MeshModuli mm = mesh_moduli(b->model(), vm.surface_nodes, vb->stats().volume_mm3, &vm.F);
      const double mu = vb->stats().mu, K = vb->stats().lambda + 2.0 * mu / 3.0;
      out["volumetric"]["effective_moduli"][label] = {{"mu_ratio", mm.mu / mu},
                                                      {"K_ratio", mm.K / K},
                                                      {"mu_min_ratio", mm.mu_min / mu},
                                                      {"mu_max_ratio", mm.mu_max / mu},
                                                      {"mu_affine_ratio", mm.mu_affine / mu},
                                                      {"K_affine_ratio", mm.K_affine / K},
                                                      {"mu_traction_ratio", mm.mu_traction / mu},
                                                      {"K_traction_ratio", mm.K_traction / K},
                                                      {"nu_eff", mm.nu()},
                                                      {"E_eff_kPa", mm.E() * 1e3}};
      note(st, cat(o.name, ": volumetric ", label, ": effective mu/mu = ", mm.mu / mu, " (", mm.mu_min / mu,
                   "..", mm.mu_max / mu, ", affine ", mm.mu_affine / mu, "), K/K = ", mm.K / K, " (affine ",
                   mm.K_affine / K, "), nu_eff = ", mm.nu(), ", E_eff = ", mm.E() * 1e3, " kPa"));
    }
    // Where the error sits (docs/accuracy.md): the small-strain (linear) response of the springs from E and
    // nu and of the P1 finite element on the same tetrahedra, against the FEM, per case
    try {
      VecX ones = VecX::Ones(2);
      const BodyPtr b = make_body(o, {"volumetric", false, false}, support, ones);
      const auto* vb = dynamic_cast<const VolumetricBody*>(b.get());
      std::vector<fem::ContactLoad> loads;
      for (const auto& c : cases) loads.push_back(c.load);
      const std::vector<MatX3> lin = fem::spring_displacement_linear(*b, loads);
      // the disk-mean read-out (docs/accuracy-nonlinear.md, "The load site"): |mean_model - mean_FEM| /
      // |mean_FEM|
      auto mean_err = [&](const MatX3& u, const fem::ContactLoad& l, const Vec3& fm) {
        return 100 * (fem::disk_mean_linear(vm.X.topRows(vm.surface_nodes), vm.F, l, u) - fm).norm() /
               fm.norm();
      };
      const Eigen::SparseMatrix<double> K = p1_stiffness(vm.X, vm.T, vb->stats().mu, vb->stats().lambda);
      const Model& m = b->model();
      Index nf = 0;
      const std::vector<Index> map = fem::free_dof_map(m, nf);
      const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(fem::restrict_to_free(K, map, nf));
      json diag = json::array();
      double sums[6] = {0, 0, 0, 0, 0, 0}, nh = 0;
      for (std::size_t i = 0; i < cases.size(); ++i) {
        const auto& c = cases[i];
        const MatX3 fs = fem::disk_load_linear(vm.X.topRows(vm.surface_nodes), vm.F, c.load.centre,
                                               c.load.radius, c.load.force);
        VecX r = VecX::Zero(nf);
        for (Index a = 0; a < fs.rows(); ++a)
          for (int d = 0; d < 3; ++d)
            if (map[static_cast<std::size_t>(3 * a + d)] >= 0)
              r[map[static_cast<std::size_t>(3 * a + d)]] = fs(a, d);
        const VecX u = ldlt.solve(r);
        MatX3 up = MatX3::Zero(vm.surface_nodes, 3);
        for (Index a = 0; a < vm.surface_nodes; ++a)
          for (int d = 0; d < 3; ++d)
            if (map[static_cast<std::size_t>(3 * a + d)] >= 0)
              up(a, d) = u[map[static_cast<std::size_t>(3 * a + d)]];
        const Index contact = sites[static_cast<std::size_t>(c.site_index)];
        const fem::SurfaceError el = fem::compare(on_organ_surface(o, lin[i]), c.u_fem, contact),
                                ep = fem::compare(on_organ_surface(o, up), c.u_fem, contact);
        const double ml = mean_err(lin[i], c.load, c.fem_mean), mp = mean_err(up, c.load, c.fem_mean);
        const Vec3 fd = c.load.force.normalized();  // the disk means along the load (compliance / |F|)
        const auto along = [&](const MatX3& uu) {
          return fem::disk_mean_linear(vm.X.topRows(vm.surface_nodes), vm.F, c.load, uu).dot(fd);
        };
        diag.push_back({{"site", c.site_index},
                        {"force_N", c.force},
                        {"train", c.train},
                        {"springs_linear_contact_pct", 100 * el.rel(el.contact_error)},
                        {"springs_linear_rms_pct", 100 * el.rel(el.rms)},
                        {"springs_linear_contact_ratio", el.contact_model / el.contact_fem},
                        {"p1_contact_pct", 100 * ep.rel(ep.contact_error)},
                        {"p1_rms_pct", 100 * ep.rel(ep.rms)},
                        {"p1_contact_ratio", ep.contact_model / ep.contact_fem},
                        {"springs_linear_disk_mean_pct", ml},
                        {"p1_disk_mean_pct", mp},
                        {"fem_disk_mean_along_mm", c.fem_mean.dot(fd)},
                        {"springs_linear_disk_mean_along_mm", along(lin[i])},
                        {"p1_disk_mean_along_mm", along(up)}});
        if (!c.train) {
          sums[0] += 100 * el.rel(el.contact_error), sums[1] += 100 * el.rel(el.rms);
          sums[2] += 100 * ep.rel(ep.contact_error), sums[3] += 100 * ep.rel(ep.rms);
          sums[4] += ml, sums[5] += mp;
          nh += 1;
        }
      }
      out["volumetric"]["small_strain"] = {
          {"cases", diag},
          {"held_out_mean_springs_linear_contact_pct", (nh > 0 ? sums[0] / nh : 0.0)},
          {"held_out_mean_springs_linear_rms_pct", (nh > 0 ? sums[1] / nh : 0.0)},
          {"held_out_mean_p1_contact_pct", (nh > 0 ? sums[2] / nh : 0.0)},
          {"held_out_mean_p1_rms_pct", (nh > 0 ? sums[3] / nh : 0.0)},
          {"held_out_mean_springs_linear_disk_mean_pct", (nh > 0 ? sums[4] / nh : 0.0)},
          {"held_out_mean_p1_disk_mean_pct", (nh > 0 ? sums[5] / nh : 0.0)}};
      note(st, cat(o.name, ": small strain, held out: springs (E, nu) contact ",
                   (nh > 0 ? sums[0] / nh : 0.0), " %, RMS ", (nh > 0 ? sums[1] / nh : 0.0),
                   " %; P1 FE on the same tetrahedra contact ", (nh > 0 ? sums[2] / nh : 0.0), " %, RMS ",
                   (nh > 0 ? sums[3] / nh : 0.0), " %; disk-mean site error: springs ",
                   (nh > 0 ? sums[4] / nh : 0.0), " %, P1 ", (nh > 0 ? sums[5] / nh : 0.0), " %"));
      // --volume-term-variants: the volume term per tetrahedron, per node and blended
      // (cmd_accuracy_volume_terms.cpp)
      if (st.volume_term_variants) {
        std::vector<VolumeTermCase> vc;
        for (const auto& c : cases)
          vc.push_back({c.load, c.u_fem, c.fem_mean, sites[static_cast<std::size_t>(c.site_index)], c.train});
        VecX no_volume = VecX::Ones(2);
        no_volume(1) = 0;
        const BodyPtr springs = make_body(o, {"volumetric", false, false}, support, no_volume);
        out["volumetric"]["volume_term_variants"] = volume_term_variants(
            vm, *b, *springs, vb->stats().mu, vb->stats().lambda, o.surface.num_vertices(), vc);
      }
    } catch (const Error& e) {  // a diagnosis, never the reason a run fails
      out["volumetric"]["small_strain"] = {{"error", e.what()}};
    }
  }
  // The displacement of kind k with its families scaled by m (+ local: the last multiplier scales k_loc).
  // volumetric + local: the disk overlay at k_ref, the E, nu body's local_stiffness(), times m(3) = a
  const double k_ref =
      std::any_of(kinds.begin(), kinds.end(), [](const Kind& k) { return k.base == "volumetric" && k.local; })
          ? make_body(o, {"volumetric", false, false}, support, VecX::Ones(2))->local_stiffness()
          : 0.0;
  auto response = [&](const Kind& k, const VecX& m, const fem::ContactLoad& load) {
    const BodyPtr body = make_body(o, k, support, m);
    if (k.linear_static) return fem::spring_displacement_linear(*body, {load})[0];
    if (k.base == "volumetric" && k.local)
      return MatX3(fem::spring_displacement(*body, load) +
                   m(k.local_index()) * fem::disk_local_overlay(*body, load, k_ref));
    if (k.base == "volumetric") return fem::spring_displacement(*body, load);  // its own (refined) surface
    return k.local ? fem::spring_displacement_local(*body, load, body->local_stiffness() * m(k.local_index()))
                   : fem::spring_displacement(*body, load);
  };
  for (const Kind& k : kinds) {
    for (bool calibrated : {false, true}) {
      VecX m = VecX::Ones(k.families());
      json fit = nullptr;
      const std::vector<fem::CalibrationCase> training =
          calibrated ? training_for(k) : std::vector<fem::CalibrationCase>{};
      if (calibrated) {
        note(st, cat(o.name, ": calibrating ", k.label(),
                     " (site read-out: ", st.site_disk_mean ? "disk mean" : "contact node", ")"));
        if (k.base == "volumetric" && k.local)
          fit = fit_volumetric_overlay(
              o.name, st, o.compression, k_ref, [&](const VecX& mm) { return make_body(o, k, support, mm); },
              [&](const VecX& mm, const fem::ContactLoad& l) { return response(k, mm, l); }, training, m);
        else if (k.base == "volumetric") {  // on the small-strain response: one factorisation per ratio
          const auto t0 = std::chrono::steady_clock::now();
          m = fem::calibrate_scale_and_ratio(
              [&](const VecX& mm, const std::vector<fem::ContactLoad>& ls) {
                // the model's own surface: the cost reads the organ's nodes (its first rows) and the disk
                return fem::spring_displacement_linear(*make_body(o, k, support, mm), ls);
              },
              training);
          fit = {{"small_strain_multipliers", {m(0), m(1)}},
                 {"nonlinear", false},
                 {"site_readout", st.site_disk_mean ? "disk-mean" : "node"},
                 {"site_weight", st.site_weight}};
          // then on the full response of the same training loads: the compression coefficient c, which the
          // small-strain response cannot see, and the two scales (docs/accuracy-nonlinear.md, "Calibration of
          // the nonlinear response")
          if (st.fit_nonlinear && o.compression > 0 && !k.linear_static) {  // K0 does not see c
            note(st, cat(o.name, ": small-strain fit springs x ", m(0), ", volume x ", m(1),
                         "; refining with c on the full response"));
            const fem::VolumetricFit vf = fem::calibrate_volumetric_nonlinear(
                [&](const VecX& mm, const fem::ContactLoad& l) { return response(k, mm, l); }, m, training);
            const fem::RefineResult& rr = vf.refine;
            m = vf.m;
            fit["nonlinear"] = true;
            fit["start"] = vf.from_small_strain ? "small-strain fit" : "closed forms (E, nu)";
            fit["spans"] = fem::kVolumetricRefineSpans;
            fit["small_strain_cost"] = vf.small_strain_cost;
            fit["closed_forms_cost"] = vf.closed_forms_cost;
            fit["cost"] = rr.cost;
            fit["evaluations"] = rr.evaluations;
            // --fit-surface-springs: the surface-layer family, from that fit (docs/accuracy-calibration.md)
            if (st.fit_surface_springs) {
              const fem::SurfaceSpringFit sf = fem::refine_surface_springs(
                  [&](const VecX& mm, const fem::ContactLoad& l) { return response(k, mm, l); }, m, training);
              m = sf.m;
              fit["surface_springs"] = {
                  {"multiplier", m(3)}, {"cost", sf.refine.cost}, {"evaluations", sf.refine.evaluations}};
            }
            note(st, cat(o.name, ": nonlinear fit springs x ", m(0), ", volume x ", m(1), ", c ",
                         o.compression, " -> ", o.compression * m(2), " (cost ", rr.start_cost, " -> ",
                         rr.cost, ", ", rr.evaluations, " evaluations)"));
          }
          fit["compression"] = o.compression * (m.size() > 2 ? m(2) : 1.0);
          fit["compression_start"] = o.compression;
          fit["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        } else
          m = fem::calibrate_multipliers(
              [&](const VecX& mm, const fem::ContactLoad& l) { return response(k, mm, l); }, k.families(),
              training, st.quick ? 1 : 2);
      }
      const BodyPtr body = make_body(o, k, support, m);
      json errs = json::array();
      double sum_rms_rel_held = 0, n_held = 0, sum_rms_rel_sites = 0, n_sites = 0;
      // held-out site errors (% of the FEM contact displacement / of the FEM disk mean): mean and max
      double sum_node = 0, max_node = 0, sum_mean = 0, max_mean = 0, max_rms = 0;
      for (const auto& c : cases) {
        MatX3 u;
        double mean_pct = 0;
        try {
          u = response(k, m, c.load);
          mean_pct =
              100 *
              (fem::disk_mean_linear(body->rest_surface(), body->faces(), c.load, u) - c.fem_mean).norm() /
              c.fem_mean.norm();
          u = on_organ_surface(o, u);
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
                        {"disk_mean_error_pct", mean_pct},
                        {"rms_mm", e.rms},
                        {"rms_pct", 100 * e.rel(e.rms)},
                        {"max_mm", e.max},
                        {"max_pct", 100 * e.rel(e.max)},
                        {"regions", regions_json(o.surface.V, u, c.u_fem, c.load, support, e.contact_fem)}});
        if (!c.train) {
          sum_rms_rel_held += e.rel(e.rms);
          n_held += 1;
          const double node_pct = 100 * e.rel(e.contact_error);
          sum_node += node_pct, max_node = std::max(max_node, node_pct);
          sum_mean += mean_pct, max_mean = std::max(max_mean, mean_pct);
          max_rms = std::max(max_rms, 100 * e.rel(e.rms));
        }
        if (!trains(c.site_index)) {  // sites no training load touched
          sum_rms_rel_sites += e.rel(e.rms);
          n_sites += 1;
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
                      {"held_out_sites_mean_rms_pct", n_sites > 0 ? 100 * sum_rms_rel_sites / n_sites : 0.0},
                      {"held_out_max_rms_pct", max_rms},
                      {"held_out_mean_contact_pct", n_held > 0 ? sum_node / n_held : 0.0},
                      {"held_out_max_contact_pct", max_node},
                      {"held_out_mean_disk_mean_pct", n_held > 0 ? sum_mean / n_held : 0.0},
                      {"held_out_max_disk_mean_pct", max_mean},
                      {"cases", errs}});
      if (!fit.is_null()) rows.back()["fit"] = fit;
    }
  }
  out["models"] = rows;
  out["fem"]["total_solve_s"] = fem_seconds;
  return out;
}

}  // namespace medspring::cli::accuracy
