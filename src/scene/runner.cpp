// Running a built scene (scene/runner.hpp).
#include "medspring/scene/runner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <set>

#include "medspring/core/binary.hpp"
#include "medspring/core/check.hpp"
#include "medspring/models/smrm_tree.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/static_solve.hpp"

namespace medspring {

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

constexpr char kTraceTag[] = "medspring-scene-trace-v1";   // read: runs without the tool section
constexpr char kTraceTag2[] = "medspring-scene-trace-v2";  // written: + tool traces and contact history
constexpr std::size_t kMaxHistory = std::size_t{1} << 30;

std::vector<std::vector<double>*> tool_vectors(SceneTrace::ToolTrace& t) {
  return {&t.fx, &t.fy, &t.fz, &t.tx, &t.ty, &t.tz, &t.area, &t.penetration, &t.grasp};
}

void put_vector(ByteWriter& w, const std::vector<double>& v) {
  w.u64(v.size());
  w.doubles(v.data(), static_cast<Index>(v.size()));
}
std::vector<double> get_vector(ByteReader& r, const char* field) {
  std::vector<double> v(static_cast<std::size_t>(r.count(field, sizeof(double))));
  r.doubles(v.data(), static_cast<Index>(v.size()));
  return v;
}

// The runner's part of a checkpoint: where the run is, its traces and per-update times so far.
std::string encode_progress(const std::string& scene, long k, Index frames, SceneTrace& t,
                            const std::vector<double>& us, const ToolSimulation* tools) {
  ByteWriter w;
  w.str(kTraceTag2);
  w.str(scene);
  w.i64(k);
  w.i64(frames);
  for (const auto* v : {&t.time, &t.force, &t.max_disp, &t.local_contact, &t.energy}) put_vector(w, *v);
  w.u64(t.node_disp.size());
  for (const auto& v : t.node_disp) put_vector(w, v);
  w.u64(t.atom_disp.size());
  for (const auto& v : t.atom_disp) put_vector(w, v);
  put_vector(w, std::vector<double>(us.begin(), us.begin() + k));
  w.u64(t.tools.size());  // rigid tools (docs/tools.md): their traces and the contact's history
  for (auto& tt : t.tools)
    for (const auto* v : tool_vectors(tt)) put_vector(w, *v);
  if (!t.tools.empty()) w.str(tools->save_history(), kMaxHistory);
  return std::move(w.bytes());
}

}  // namespace

void scene_trace_sample(const BuiltScene& b, double time, const Vec3& applied, const MatX3& surface,
                        const MatX3& x, double local_contact, SceneTrace& tr) {
  const MatX3& S0 = b.body->rest_surface();
  const Model& model = b.body->model();
  if (tr.node_disp.size() != b.trace_nodes.size()) tr.node_disp.resize(b.trace_nodes.size());
  if (tr.atom_disp.size() != b.trace_atom_dofs.size()) tr.atom_disp.resize(b.trace_atom_dofs.size());
  tr.time.push_back(time);
  tr.force.push_back(applied.norm());
  tr.max_disp.push_back((surface - S0).rowwise().norm().maxCoeff());
  tr.local_contact.push_back(local_contact);
  for (std::size_t k = 0; k < b.trace_nodes.size(); ++k) {
    const Index i = b.trace_nodes[k];
    tr.node_disp[k].push_back((surface.row(i) - S0.row(i)).norm());
  }
  for (std::size_t k = 0; k < b.trace_atom_dofs.size(); ++k) {
    const Index i = b.trace_atom_dofs[k];
    tr.atom_disp[k].push_back((x.row(i) - model.x0.row(i)).norm());
  }
}

Index summarize_trace(const BuiltScene& b, const SceneTrace& tr, RunSummary& s) {
  // Releases: the last one, if every load is released.
  if (!b.loads.empty()) {
    s.release_time = 0;
    for (const PointLoad& L : b.loads) s.release_time = std::max(s.release_time, L.t_release);
  }
  const double first_release = b.loads.empty() ? INFINITY : b.loads.front().t_release;
  const Index T = tr.size();
  Index hold = T - 1;            // the last frame with the first load on (or the end)
  for (Index q = 0; q < T; ++q)  // the frame at t_release already shows the force released
    if (tr.time[q] < first_release - 1e-9) hold = q;
  if (!tr.node_disp.empty()) {
    s.contact_peak_mm = *std::max_element(tr.node_disp[0].begin(), tr.node_disp[0].end());
    s.contact_hold_mm = tr.node_disp[0][hold];
  }
  if (!tr.atom_disp.empty()) s.atom_hold_mm = tr.atom_disp[0][hold];
  s.local_hold_mm = tr.local_contact[hold];
  s.max_disp_peak_mm = *std::max_element(tr.max_disp.begin(), tr.max_disp.end());
  s.final_max_disp_mm = tr.max_disp.back();
  if (std::isfinite(s.release_time)) {
    Index last_out = -1;
    for (Index q = 0; q < T; ++q)
      if (tr.time[q] >= s.release_time - 1e-9 && tr.max_disp[q] > s.return_tolerance) last_out = q;
    if (last_out + 1 < T)
      s.return_ms = last_out < 0 ? 0.0 : std::max(0.0, tr.time[last_out + 1] - s.release_time);
  }
  return hold;
}

SceneResult run_scene(const BuiltScene& b, const RunHooks& hooks) {
  const Scene& scene = b.scene;
  Simulation sim(b.body, b.settings);
  sim.set_loads(b.loads);
  std::optional<ToolSimulation> tools;  // scene.tools: rigid instruments (docs/tools.md)
  if (!scene.tools.empty()) {
    tools.emplace(sim, scene.contact);
    for (const SceneTool& t : scene.tools) {
      const Index k = tools->add_tool(t.tool, t.path.front().pose);
      tools->set_path(k, t.path);
    }
  }
  const double dt = b.settings.step.dt;
  const long n = std::max(1L, static_cast<long>(std::ceil(scene.duration / dt - 1e-9)));

  // Updates whose frame is written: every N, the last, and the first reaching each key time.
  std::set<long> keys;
  for (double t : scene.record.key_times)
    keys.insert(std::clamp(static_cast<long>(std::ceil(t / dt - 1e-9)), 0L, n));

  SceneResult res;
  SceneTrace& tr = res.trace;
  tr.node_disp.assign(b.trace_nodes.size(), {});
  tr.atom_disp.assign(b.trace_atoms.size(), {});
  tr.tools.assign(scene.tools.size(), {});
  std::vector<double> us(static_cast<std::size_t>(n));
  long k0 = 0;        // updates done before this call
  Index frames0 = 0;  // frames recorded before this call
  if (hooks.resume != nullptr) {
    apply_checkpoint(*hooks.resume, sim, "resume");  // first: another model is the mismatch to name
    const std::string what = cat("resume: checkpoint of '", hooks.resume->model_name, "'");
    ByteReader r(hooks.resume->extra, what, "scene checkpoint");
    const std::string tag = hooks.resume->extra.empty() ? std::string() : r.str("tag");
    if (tag != kTraceTag && tag != kTraceTag2)
      throw InvalidInput(cat(what, ": it holds no scene run (saved by another program?)"));
    const std::string name = r.str("scene");
    if (name != scene.name)
      throw InvalidInput(cat(what, ": saved from scene '", name, "', this is scene '", scene.name, "'"));
    k0 = static_cast<long>(r.i64());
    frames0 = static_cast<Index>(r.i64());
    for (auto* v : {&tr.time, &tr.force, &tr.max_disp, &tr.local_contact, &tr.energy})
      *v = get_vector(r, "trace");
    if (r.u64() != tr.node_disp.size()) r.fail("traced nodes differ from the scene's");
    for (auto& v : tr.node_disp) v = get_vector(r, "node trace");
    if (r.u64() != tr.atom_disp.size()) r.fail("traced atoms differ from the scene's");
    for (auto& v : tr.atom_disp) v = get_vector(r, "atom trace");
    const std::vector<double> done = get_vector(r, "update times");
    const std::uint64_t saved_tools = tag == kTraceTag2 ? r.u64() : 0;
    if (saved_tools != tr.tools.size())
      throw InvalidInput(cat(what, ": saved with ", saved_tools, " tools, the scene has ", tr.tools.size()));
    for (auto& tt : tr.tools)
      for (auto* v : tool_vectors(tt)) *v = get_vector(r, "tool trace");
    if (!tr.tools.empty()) tools->restore_history(r.str("contact history", kMaxHistory), what);
    r.finish();
    bool sizes = k0 >= 0 && k0 <= n && frames0 >= 0 && done.size() == static_cast<std::size_t>(k0);
    for (const auto* v : {&tr.time, &tr.force, &tr.max_disp, &tr.local_contact, &tr.energy})
      sizes = sizes && v->size() == static_cast<std::size_t>(k0 + 1);
    for (const auto& v : tr.node_disp) sizes = sizes && v.size() == static_cast<std::size_t>(k0 + 1);
    for (const auto& v : tr.atom_disp) sizes = sizes && v.size() == static_cast<std::size_t>(k0 + 1);
    for (auto& tt : tr.tools)
      for (const auto* v : tool_vectors(tt)) sizes = sizes && v->size() == static_cast<std::size_t>(k0 + 1);
    if (!sizes) throw InvalidInput(cat(what, ": its traces do not match update ", k0, " of ", n));
    std::copy(done.begin(), done.end(), us.begin());
    res.first_update = k0 + 1;
  }
  const Model& model = b.body->model();
  const Index contact = b.loads.empty() ? -1 : b.loads.front().node;

  const auto* vessel = dynamic_cast<const SmrmVessel*>(b.body.get());
  const auto* tree = dynamic_cast<const SmrmTree*>(b.body.get());  // vessel trees: per branch
  SmrmTree::Workspace tree_ws;
  if (tree) tree_ws = tree->make_workspace();
  std::vector<double> turning;  // max_i |alpha_i - alpha_i^0| per sampled frame (vessels)
  auto sample = [&] {
    if (vessel || tree) {
      RunSummary& q = res.summary;
      const CurvatureCheck v =
          vessel ? vessel->validity(sim.state().x) : tree->validity(sim.state().x, tree_ws);
      q.max_rho_kappa = std::max(q.max_rho_kappa, v.max_rho_kappa);
      q.rho_kappa_violations += v.violations;
      q.rho_kappa_updates += v.violations > 0 ? 1 : 0;
      Index atom = -1;
      const double t = vessel ? vessel->max_turning_change_deg(sim.state().x, &atom)
                              : tree->max_turning_change_deg(sim.state().x, tree_ws, &atom);
      if (t > q.max_turning_change_deg || q.max_turning_atom < 0) {
        q.max_turning_change_deg = t;
        q.max_turning_atom = atom;
      }
      turning.push_back(t);
    }
    double uc = 0.0;
    const auto& patch = sim.local_nodes();
    for (std::size_t r = 0; r < patch.size(); ++r)
      if (patch[r] == contact) uc = sim.local_displacement().row(static_cast<Index>(r)).norm();
    scene_trace_sample(b, sim.time(), sim.applied_force(), sim.surface(), sim.state().x, uc, tr);
    tr.energy.push_back(total_energy(model, sim.state().x, sim.state().v));
    for (std::size_t k = 0; k < tr.tools.size(); ++k) {
      const ToolState& ts = tools->contact().state(static_cast<Index>(k));
      SceneTrace::ToolTrace& tt = tr.tools[k];
      for (int d = 0; d < 3; ++d) {
        (d == 0 ? tt.fx : d == 1 ? tt.fy : tt.fz).push_back(ts.force[d]);
        (d == 0 ? tt.tx : d == 1 ? tt.ty : tt.tz).push_back(ts.torque[d]);
      }
      tt.area.push_back(ts.area);
      tt.penetration.push_back(ts.penetration);
      tt.grasp.push_back(ts.grasp_force.norm());
    }
  };
  auto record = [&] {
    RecordedFrame f{frames0 + static_cast<Index>(res.frames.size()), sim.time()};
    res.frames.push_back(f);
    if (hooks.on_frame) hooks.on_frame(sim, f);
  };

  if (hooks.resume == nullptr) {
    sample();
    if (scene.record.frames) record();  // the rest state
  }
  auto checkpoint = [&](long k) {
    Checkpoint c = make_checkpoint(sim);
    c.extra = encode_progress(scene.name, k, frames0 + static_cast<Index>(res.frames.size()), tr, us,
                              tools ? &*tools : nullptr);
    hooks.on_checkpoint(c);
  };
  const long progress_every = std::max(1L, n / 100);
  const auto t_start = std::chrono::steady_clock::now();
  long last = n;  // the last update done
  for (long k = k0 + 1; k <= n; ++k) {
    const auto a = std::chrono::steady_clock::now();
    if (tools)
      tools->update();
    else
      sim.update();
    us[static_cast<std::size_t>(k - 1)] =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count();
    sample();
    if (scene.record.frames && (k % scene.record.every == 0 || k == n || keys.count(k) > 0)) record();
    if (hooks.on_progress && k % progress_every == 0)
      hooks.on_progress(static_cast<double>(k) / static_cast<double>(n));
    const bool stop = k < n && sim.time() >= hooks.stop_at - 1e-9;
    if (hooks.on_checkpoint && ((hooks.checkpoint_every > 0 && k % hooks.checkpoint_every == 0) || stop))
      checkpoint(k);
    if (stop) {
      last = k;
      res.stopped = true;
      break;
    }
  }
  us.resize(static_cast<std::size_t>(last));
  RunSummary& s = res.summary;
  s.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  s.updates = static_cast<Index>(last);
  s.median_update_us = median(us);
  double sum = 0;
  for (double u : us) sum += u;
  s.mean_update_us = sum / static_cast<double>(std::max(1L, last));
  s.substeps = sim.state().substeps;
  s.warnings = sim.state().warnings.total();

  const Index hold = summarize_trace(b, tr, s);
  if ((vessel || tree) && !turning.empty()) {
    const Index offset =
        tr.size() - static_cast<Index>(turning.size());  // a resumed run samples from its resume
    if (hold >= offset) s.hold_turning_change_deg = turning[static_cast<std::size_t>(hold - offset)];
  }
  if (hooks.on_progress) hooks.on_progress(1.0);
  return res;
}

std::vector<StaticPoint> static_response(const BuiltScene& b, int points) {
  require(!b.loads.empty(), "static response: the scene has no load");
  require(points >= 2, "static response: need at least 2 points (got ", points, ")");
  const Body& body = *b.body;
  const Model& m = body.model();
  const PointLoad& L = b.loads.front();
  const MatX3& S0 = body.rest_surface();
  State st = make_state(m);
  MatX3 f(m.num_nodes(), 3), S;
  std::vector<StaticPoint> out;
  for (int k = 0; k < points; ++k) {
    const double s = static_cast<double>(k) / static_cast<double>(points - 1);
    f.setZero();
    if (s > 0) body.transfer_force(L.node, s * L.force, f);
    const StaticResult r = static_equilibrium(m, f, {.tolerance = 1e-8},
                                              st.x);  // 1e-8 N: round-off on organs 300 mm from the origin
    st.x = r.x;
    body.map_to_surface(st, S);
    out.push_back({s * L.force.norm(), (S.row(L.node) - S0.row(L.node)).norm(),
                   (S - S0).rowwise().norm().maxCoeff(), r.iterations});
  }
  return out;
}

}  // namespace medspring
