// The study's driver (paper/study.hpp): every scene parsed first, then the runs, the vessel tree, the
// timing of Tables I and II, the figures, tables.json, results.json and report.md.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "internal.hpp"
#include "medspring/core/check.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/physics/spring_law.hpp"

namespace medspring::paper {

namespace detail {

json parameters_json(const SceneRun& kidney, const SceneRun& vessel) {
  const Scene& ks = kidney.scene;
  const Scene& vs = vessel.scene;
  const HybridSettings& h = ks.model.hybrid;
  const SmrmSettings& v = vs.model.smrm;
  auto node = [](const NodeParams& p) {
    return json{{"mass_g", p.mass}, {"beta", p.beta}, {"k_r", p.return_k}};
  };
  return {{"kidney",
           {{"surface_node", node(h.surface_node)},
            {"atom_node", node(h.atom_node)},
            {"k_surf", h.k_surf},
            {"k_spoke", h.k_spoke},
            {"k_cl", h.k_cl},
            {"spokes_per_atom", h.spokes_per_atom},
            {"visibility_filter", h.visibility_filter},
            {"duffing_mode", to_string(h.duffing.mode)},
            {"duffing_eta", h.duffing.eta},
            {"duffing_length_mm", h.duffing.length},
            {"dt_ms", ks.step.dt},
            {"integrator", to_string(ks.step.integrator)},
            {"substep", ks.step.substep}}},
          {"vessel",
           {{"chain", node(NodeParams{v.chain.mass, v.chain.beta, v.chain.kr})},
            {"spokes", v.spokes},
            {"k_cl", v.chain.k},
            {"bending", v.bending == BendingMode::Wall ? "wall" : "springs"},
            {"k_b", v.chain.kb},
            {"wall_E_MPa", v.wall.E},
            {"wall_thickness_ratio", v.wall.thickness_ratio},
            {"duffing_mode", to_string(v.chain.duffing.mode)},
            {"duffing_eta", v.chain.duffing.eta},
            {"atoms", vs.model.atoms},
            {"frames_mode", to_string(v.frames.mode)},
            {"frames_anchor", to_string(v.frames.anchor)},
            {"dt_ms", vs.step.dt},
            {"k_loc", v.k_loc}}}};
}

}  // namespace detail

using namespace detail;

std::string run_study(const StudyOptions& o, StudyHost& host) {
  using clock_type = std::chrono::steady_clock;
  const auto t_start = clock_type::now();
  require(!o.out_dir.empty(), "paper: no output folder");
  require(!o.scenes_dir.empty(), "paper: no scenes folder");
  if (o.figures) require(o.timing, "paper: the figures include the timing plot: timing must be on");
  std::vector<std::string> notes;
  const fs::path data = o.data_dir.empty() ? scene_data_dir() : o.data_dir;
  bool real = !o.quick;
  if (real) {
    std::error_code ec;
    if (!fs::exists(data / "kidney_left_hubmap_vhm.obj", ec) ||
        !fs::exists(data / "vmr-0159-aorta-centerline.vtp", ec)) {
      real = false;
      notes.push_back(cat("The real anatomy was not found in ", data.string(),
                          " (set MEDSPRING_DATA): the figures use the phantoms."));
    }
    if (real && host.loader() == nullptr) {
      real = false;
      notes.push_back("No file loader: the study runs on the phantoms.");
    }
  }
  const std::string primary = real ? "real" : "phantom";
  std::vector<std::string> sets = {primary};
  if (real) sets.push_back("phantom");

  // Every scene is parsed and validated before anything is written.
  std::vector<SceneRun> runs;
  for (const auto& set : sets)
    for (const Experiment& e : experiments()) {
      if (e.literal && set != primary) continue;  // the paper-literal set: on the report's anatomy only
      SceneRun r;
      r.e = e;
      r.set = set;
      r.scene = experiment_scene(e, o.scenes_dir, set != "real");
      // Runs without rendered figures keep fewer frames (the key times are always written).
      if (o.quick || set != primary || e.literal || !o.figures)
        r.scene.record.every = std::max<Index>(r.scene.record.every, 100);
      runs.push_back(std::move(r));
    }

  const fs::path root = o.out_dir;
  fs::create_directories(root / "figures");
  fs::create_directories(root / "data");
  fs::create_directories(root / "logs");

  // ---- the simulations ------------------------------------------------------------------------------
  for (std::size_t k = 0; k < runs.size(); ++k) {
    SceneRun& r = runs[k];
    const std::string name = r.e.file + (r.e.literal ? "_literal" : "");
    host.begin(cat("[", k + 1, "/", runs.size(), "] ", r.set, " ", name));
    const BuiltScene built = build_scene(r.scene, host.loader());
    r.rel = cat("scenes/", r.set, "/", name);
    r.dir = root / r.rel;
    r.summary = json::parse(host.run_to_folder(built, r.dir, r.e.static_curve));
    record_geometry(r, built);
    const MatX3& A = built.atoms_rest;
    if (A.rows() >= 2) {
      r.axis = (A.row(A.rows() - 1) - A.row(0)).transpose().normalized();
      const Index a = std::clamp<Index>(20, 1, static_cast<Index>(A.rows()) - 2);
      r.tangent = (A.row(a + 1) - A.row(a - 1)).transpose().normalized();
      r.radius = (r.contact - A.row(a).transpose()).norm();
      r.model_facts["contact_radius_mm"] = r.radius;
      double spacing = 0;
      for (Index q = 1; q < A.rows(); ++q) spacing += (A.row(q) - A.row(q - 1)).norm();
      r.model_facts["atom_spacing_mm"] = spacing / static_cast<double>(A.rows() - 1);
    }
    if (const auto* h = dynamic_cast<const HybridKidney*>(built.body.get())) {
      const HybridStats st = h->stats();
      r.model_facts["spokes"] = st.spokes;
      r.model_facts["visibility_filtered"] = st.visibility_filtered;
      r.model_facts["visibility_rejected"] = st.visibility.rejected;
      r.model_facts["visibility_fallbacks"] = st.visibility.fallbacks;
    }
    const Model& m = built.body->model();
    r.model_facts["dt_safe_rest_ms"] = m.dt_safe_rest();
    const double updates = std::max(1.0, r.summary["updates"].get<double>());
    const double substeps = r.summary["substeps"].get<double>();
    r.model_facts["substeps_per_update"] = substeps / updates;
    r.model_facts["effective_step_ms"] = built.settings.step.dt * updates / std::max(1.0, substeps);
    host.end(cat(r.summary["updates"].get<long>(), " updates, ", r.summary["frames"].size(), " frames"));
  }

  // ---- the whole vessel tree (issue 17) ---------------------------------------------------------------
  std::vector<SceneRun> tree_runs;
  json tree = nullptr;
  if (o.tree) tree = run_tree(o, host, primary, root, tree_runs);

  // ---- Tables I and II ------------------------------------------------------------------------------
  json tables = nullptr;
  if (o.timing) {
    const TimingProtocol p = o.quick ? TimingProtocol{50, 2, 150} : TimingProtocol{200, 5, 400};
    host.begin("timing Tables I and II");
    const std::vector<TimedCase> timed = time_cases(timing_cases(), p, [&](double x) { host.update(x); });
    host.end(cat(timed.size(), " cases x ", p.rounds * p.per_round, " timed updates"));
    tables = tables_json(timed, p, cpu_name());
  }

  // ---- figures ----------------------------------------------------------------------------------------
  if (o.figures) {
    host.begin("figures");
    make_figures(o, root, primary, runs, tree_runs, tables["cases"]);
    host.end("rendered");
  }

  // ---- tables.json and results.json ---------------------------------------------------------------------
  json scenes_json = json::array(), runs_json = json::array();
  for (const auto& r : runs) {
    json s = r.summary;
    s.erase("frames");
    s.erase("atoms_rest");
    s["set"] = r.set;
    s["folder"] = r.rel;
    if (!r.e.literal) scenes_json.push_back(s);
    runs_json.push_back({{"file", r.e.file},
                         {"group", r.e.group},
                         {"set", r.set},
                         {"label", r.e.label},
                         {"force_N", r.e.force},
                         {"nonlinear", r.e.nonlinear},
                         {"local", r.e.local},
                         {"literal", r.e.literal},
                         {"folder", r.rel},
                         {"facts", r.model_facts},
                         {"notes", r.notes},
                         {"summary", s}});
  }
  const double seconds = std::chrono::duration<double>(clock_type::now() - t_start).count();
  if (o.timing) {
    json tables_out = tables;
    tables_out["scenes"] = scenes_json;
    tables_out["paper_seconds"] = seconds;
    tables_out["quick"] = o.quick;
    tables_out["tree"] = tree;
    write_text(root / "tables.json", tables_out.dump(2) + "\n");
  }
  const json results = {{"meta",
                         {{"command", o.command},
                          {"quick", o.quick},
                          {"date", now_utc()},
                          {"machine", cpu_name()},
                          {"seconds", seconds},
                          {"primary", primary},
                          {"sets", sets},
                          {"figures", o.figures},
                          {"notes", notes}}},
                        {"runs", runs_json},
                        {"tree", tree},
                        {"tables", tables},
                        {"parameters", parameters_json(find_run(runs, primary, "kidney_1.0N_nonlinear"),
                                                       find_run(runs, primary, "vessel_light_nonlinear"))},
                        {"accuracy_markdown", o.accuracy_markdown}};
  const std::string text = results.dump(2) + "\n";
  write_text(root / "results.json", text);
  if (o.report) render_report(root / "results.json", root / "report.md", o);
  return text;
}

}  // namespace medspring::paper
