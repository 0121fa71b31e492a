// The experiment set of the study and the vessel tree's scenes (paper/study.hpp).
#include "internal.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/spring_law.hpp"

namespace medspring::paper {

const std::vector<Experiment>& experiments() {
  static const std::vector<Experiment> list = {
      {"kidney_1.0N_nonlinear", "kidney", 1.0, true, false, true, "1.0 N nonlinear"},
      {"kidney_1.0N_linear", "kidney", 1.0, false, false, true, "1.0 N linear"},
      {"kidney_0.2N_nonlinear", "kidney", 0.2, true, false, false, "0.2 N nonlinear"},
      {"kidney_0.2N_linear", "kidney", 0.2, false, false, false, "0.2 N linear"},
      {"vessel_light_nonlinear", "vessel", 0.05, true, false, false, "light 0.05 N nonlinear"},
      {"vessel_light_linear", "vessel", 0.05, false, false, false, "light 0.05 N linear"},
      {"vessel_strong_nonlinear", "vessel", 0.5, true, false, true, "strong 0.5 N nonlinear"},
      {"vessel_strong_linear", "vessel", 0.5, false, false, true, "strong 0.5 N linear"},
      {"vessel_light_nonlinear_local", "vessel", 0.05, true, true, false, "light 0.05 N nonlinear + local"},
      {"vessel_light_linear_local", "vessel", 0.05, false, true, false, "light 0.05 N linear + local"},
      {"vessel_strong_nonlinear_local", "vessel", 0.5, true, true, false, "strong 0.5 N nonlinear + local"},
      {"vessel_strong_linear_local", "vessel", 0.5, false, true, false, "strong 0.5 N linear + local"},
      // The paper's literal constants (D-3): Duffing `Absolute`, k' = k / (10 mm)^2 = 0.01 k.
      {"kidney_1.0N_nonlinear", "kidney", 1.0, true, false, false, "1.0 N nonlinear, paper-literal", true},
      {"vessel_strong_nonlinear", "vessel", 0.5, true, false, false, "strong 0.5 N nonlinear, paper-literal",
       true},
  };
  return list;
}

Scene experiment_scene(const Experiment& e, const std::filesystem::path& scenes_dir, bool phantom) {
  Scene s = load_scene(scenes_dir / (phantom ? "phantom" : "") / (e.file + ".json"));
  if (e.literal) {
    s.name += "_literal";
    s.model.hybrid.duffing.mode = DuffingMode::Absolute;
    s.model.smrm.chain.duffing.mode = DuffingMode::Absolute;
    s.model.surface.duffing.mode = DuffingMode::Absolute;
    s.description += " Paper-literal constants: Duffing `Absolute` (k' = k / (10 mm)^2 = 0.01 k).";
  }
  return s;
}

namespace detail {

std::vector<Centerline> phantom_tree_lines() {
  auto line = [](const std::vector<Vec3>& pts, const std::vector<double>& r, const std::string& name) {
    Centerline c;
    c.name = name;
    c.points.resize(static_cast<Index>(pts.size()), 3);
    c.radii.resize(static_cast<Index>(pts.size()));
    for (std::size_t k = 0; k < pts.size(); ++k) {
      c.points.row(static_cast<Index>(k)) = pts[k].transpose();
      c.radii[static_cast<Index>(k)] = r[k];
    }
    return c;
  };
  std::vector<Vec3> trunk;
  std::vector<double> rt;
  for (int k = 0; k <= 20; ++k) {  // 0..40 mm along x, turning gently towards -y
    const double x = 2.0 * k;
    trunk.emplace_back(x, -0.004 * x * x, 0.0);
    rt.push_back(6.0 - 0.02 * x);
  }
  std::vector<Vec3> a = trunk, b = trunk;
  std::vector<double> ra = rt, rb = rt;
  const Vec3 j = trunk.back();
  for (int k = 1; k <= 30; ++k) {  // the aorta goes on and down
    const double s = 2.0 * k;
    a.push_back(j + Vec3(s, -0.3 * s - 0.004 * s * s, 0.0));
    ra.push_back(5.0);
  }
  for (int k = 1; k <= 15; ++k) {  // the branch leaves upwards
    const double s = 2.0 * k;
    b.push_back(j + Vec3(0.3 * s, s, 0.05 * s));
    rb.push_back(2.5);
  }
  return {line(a, ra, "aorta"), line(b, rb, "branch")};
}

std::string tree_scene_json(const std::string& name, const fs::path& file, const std::string& unit,
                            Index node, Index atom, double force, Index every, bool blend) {
  json source = {{"file", file.string()}, {"unit", unit}, {"branches", "all"}};
  if (blend) source["blend"] = true;
  const json j = {
      {"name", name},
      {"description", "vessel tree (issue 17): every branch of the centerline file, shared junction atoms"},
      {"model", {{"kind", "smrm"}, {"source", {{"centerline", source}}}, {"nonlinear", true}}},
      {"loads", json::array({{{"node", node},
                              {"direction", "inward_normal"},
                              {"magnitude", force},
                              {"t_ramp", 20},
                              {"t_release", 500}}})},
      {"integrator", {{"method", "symplectic_euler"}, {"dt", 0.5}, {"substep", true}}},
      {"duration", 1000},
      {"local", {{"enabled", false}}},
      {"record",
       {{"every", every},
        {"key_times", json::array({495, 500, 505, 510, 520, 1000})},
        {"atoms", json::array({atom})}}}};
  return j.dump(2);
}

const SceneRun& find_run(const std::vector<SceneRun>& runs, const std::string& set, const std::string& file) {
  for (const auto& r : runs)
    if (r.set == set && r.e.file == file && !r.e.literal) return r;
  throw Error(cat("paper: no run ", set, "/", file));
}

void record_geometry(SceneRun& r, const BuiltScene& built) {
  const MatX3& S0 = built.body->rest_surface();
  r.contact = S0.row(built.loads.front().node).transpose();
  r.dir_force = built.loads.front().force.normalized();
  r.center = 0.5 * (S0.colwise().minCoeff() + S0.colwise().maxCoeff()).transpose();
  r.size = (S0.colwise().maxCoeff() - S0.colwise().minCoeff()).norm();
  r.notes = built.notes;
}

}  // namespace detail
}  // namespace medspring::paper
