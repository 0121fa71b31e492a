// The summary of one scene run as JSON (paper/run_summary.hpp).
#include "medspring/paper/run_summary.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

namespace medspring::paper {

namespace {

using json = nlohmann::json;

json num(double x) {
  return std::isfinite(x) ? json(x) : json(nullptr);
}

json describe(const BuiltScene& b) {
  const Model& m = b.body->model();
  return {{"kind", b.body->kind()},
          {"name", m.name},
          {"surface_nodes", b.body->num_surface_nodes()},
          {"triangles", b.body->faces().rows()},
          {"masses", m.num_nodes()},
          {"springs", m.num_springs()},
          {"atoms", b.atoms_rest.rows()},
          {"dt_ms", b.settings.step.dt},
          {"dt_safe_rest_ms", b.dt_safe_rest},
          {"build_seconds", b.build_seconds},
          {"notes", b.notes}};
}

}  // namespace

std::string describe_built_json(const BuiltScene& built) {
  return describe(built).dump();
}

std::string run_summary_json(const BuiltScene& b, const SceneResult& r, const SummaryExtras& x) {
  const RunSummary& s = r.summary;
  json loads = json::array();
  for (const PointLoad& L : b.loads)
    loads.push_back({{"node", L.node},
                     {"force_N", {L.force.x(), L.force.y(), L.force.z()}},
                     {"magnitude_N", L.force.norm()},
                     {"t_release_ms", num(L.t_release)}});
  json atoms_rest = json::array();
  for (Index a = 0; a < b.atoms_rest.rows(); ++a)
    atoms_rest.push_back({b.atoms_rest(a, 0), b.atoms_rest(a, 1), b.atoms_rest(a, 2)});
  json curve = json::array();
  for (const StaticPoint& p : x.static_curve) curve.push_back({p.force, p.contact_mm});
  auto name_or_null = [](const std::string& n) { return n.empty() ? json(nullptr) : json(n); };
  const json summary = {{"scene", b.scene.name},
                        {"scene_file", b.scene.file.string()},
                        {"description", b.scene.description},
                        {"model", describe(b)},
                        {"loads", loads},
                        {"trace_nodes", b.trace_nodes},
                        {"trace_atoms", b.trace_atoms},
                        {"atoms_rest", atoms_rest},
                        {"duration_ms", b.scene.duration},
                        {"updates", s.updates},
                        {"run_seconds", s.wall_seconds},
                        {"median_update_us", s.median_update_us},
                        {"mean_update_us", s.mean_update_us},
                        {"substeps", s.substeps},
                        {"warnings", s.warnings},
                        {"contact_peak_mm", s.contact_peak_mm},
                        {"contact_hold_mm", s.contact_hold_mm},
                        {"atom_hold_mm", s.atom_hold_mm},
                        {"local_hold_mm", s.local_hold_mm},
                        {"max_disp_peak_mm", s.max_disp_peak_mm},
                        {"final_max_disp_mm", s.final_max_disp_mm},
                        {"release_ms", num(s.release_time)},
                        {"return_ms", num(s.return_ms)},
                        {"return_tolerance_mm", s.return_tolerance},
                        {"max_rho_kappa", s.max_rho_kappa},
                        {"rho_kappa_violations", s.rho_kappa_violations},
                        {"rho_kappa_updates", s.rho_kappa_updates},
                        {"max_turning_change_deg", s.max_turning_change_deg},
                        {"max_turning_atom", s.max_turning_atom},
                        {"hold_turning_change_deg", s.hold_turning_change_deg},
                        {"pvd", name_or_null(x.pvd)},
                        {"atoms_pvd", name_or_null(x.atoms_pvd)},
                        {"frames", json::parse(x.frames_json)},
                        {"first_update", r.first_update},
                        {"resumed_from_ms", num(x.resumed_from_ms)},
                        {"stopped", r.stopped},
                        {"checkpoint", name_or_null(x.checkpoint)},
                        {"static_curve", curve}};
  return summary.dump(2);
}

}  // namespace medspring::paper
