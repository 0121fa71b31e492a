// Scene runs in batches (scene/batch.hpp, docs/gpu.md "Study runs on the GPU").
#include "medspring/scene/batch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "medspring/core/check.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/state.hpp"

namespace medspring {

namespace {

// The CPU reference: one State per model, step() per frame with the held DOF loads in f_ext.
class CpuBatchStepper final : public BatchStepper {
 public:
  explicit CpuBatchStepper(const std::vector<const BuiltScene*>& group)
      : settings_(group.front()->settings.step) {
    for (const BuiltScene* b : group) {
      models_.push_back(&b->body->model());
      states_.push_back(make_state(*models_.back()));
      prepare_step(*models_.back(), states_.back(), settings_);
    }
    loads_.resize(group.size());
  }
  void set_loads(int b, const std::vector<PointLoad>& loads) override {
    loads_.at(static_cast<std::size_t>(b)) = loads;
  }
  void step() override {
    for (std::size_t b = 0; b < models_.size(); ++b) {
      State& s = states_[b];
      accumulate_loads(loads_[b], s.t, s.f_ext);
      medspring::step(*models_[b], s, settings_);
    }
  }
  void positions(int b, MatX3& x) override { x = states_.at(static_cast<std::size_t>(b)).x; }
  double time(int b) const override { return states_.at(static_cast<std::size_t>(b)).t; }
  std::uint64_t substeps(int b) const override { return states_.at(static_cast<std::size_t>(b)).substeps; }
  std::uint64_t warnings(int b) const override {
    return states_.at(static_cast<std::size_t>(b)).warnings.total();
  }

 private:
  StepSettings settings_;
  std::vector<const Model*> models_;
  std::vector<State> states_;
  std::vector<std::vector<PointLoad>> loads_;
};

std::string hex(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%a", v);
  return buf;
}

long updates_of(const BuiltScene& b) {
  return std::max(1L, static_cast<long>(std::ceil(b.scene.duration / b.settings.step.dt - 1e-9)));
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// scene_trace_sample's record from the values of trace_probe's probe (hd::trace_sample's layout).
void trace_append(const BuiltScene& b, double time, const Vec3& applied, const double* v, SceneTrace& tr) {
  const std::size_t nodes = b.trace_nodes.size(), atoms = b.trace_atom_dofs.size();
  if (tr.node_disp.size() != nodes) tr.node_disp.resize(nodes);
  if (tr.atom_disp.size() != atoms) tr.atom_disp.resize(atoms);
  tr.time.push_back(time);
  tr.force.push_back(applied.norm());
  tr.max_disp.push_back(v[0]);
  tr.local_contact.push_back(0.0);
  for (std::size_t k = 0; k < nodes; ++k) tr.node_disp[k].push_back(v[1 + k]);
  for (std::size_t k = 0; k < atoms; ++k) tr.atom_disp[k].push_back(v[1 + nodes + k]);
}

// One group: runs of one batch_key stepped together; results written into out[index[k]].
void run_group(const std::vector<const BuiltScene*>& runs, const std::vector<std::size_t>& index, int group,
               const BatchStepperFactory& make, const std::vector<double>& times,
               std::vector<BatchRunResult>& out) {
  std::vector<const BuiltScene*> g;
  for (std::size_t i : index) g.push_back(runs[i]);
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<BatchStepper> stepper = make(g);
  require(stepper != nullptr, "batch run: the stepper factory returned nothing");
  const BuiltScene& first = *g.front();
  const long n = updates_of(first);
  const double dt = first.settings.step.dt;
  std::set<long> keys;  // frames recorded for fields: the rest state, the key times, the last (SceneRunner)
  for (double t : times) keys.insert(std::clamp(static_cast<long>(std::ceil(t / dt - 1e-9)), 0L, n));
  keys.insert(0);
  keys.insert(n);
  const bool want_fields = !times.empty();

  const std::size_t B = g.size();
  std::vector<SceneTrace> traces(B);
  std::vector<std::vector<double>> frame_times(B);
  std::vector<std::vector<MatX3>> frames(B);
  std::vector<State> states;  // for map_to_surface (positions only)
  std::vector<MatX3> surface(B);
  MatX3 f_ext;
  for (const BuiltScene* b : g) states.push_back(make_state(b->body->model()));
  std::vector<double> us(static_cast<std::size_t>(n));
  // The traces reduced by the stepper (on the device) where it can: then positions come back only for
  // the field snapshots.
  std::vector<TraceProbe> probes(B);
  bool reduced = true;
  for (std::size_t b = 0; b < B && reduced; ++b) reduced = trace_probe(*g[b], probes[b]);
  reduced = reduced && stepper->set_trace_probes(probes);
  std::size_t width = 1;
  for (const TraceProbe& p : probes) width = std::max(width, 1 + p.point_dof.size());
  std::vector<double> values;

  auto sample = [&](long k) {
    if (reduced) {
      stepper->trace_values(values);
      require(values.size() == B * width, "batch run: the stepper gave ", values.size(), " trace values for ",
              B, " models of ", width);
    }
    for (std::size_t b = 0; b < B; ++b) {
      if (reduced) {
        const BuiltScene& s = *g[b];
        const double t = stepper->time(static_cast<int>(b));
        Vec3 applied = Vec3::Zero();
        for (const PointLoad& L : s.loads) applied += L.at(t);  // Simulation::applied_force
        trace_append(s, t, applied, values.data() + b * width, traces[b]);
        if (want_fields && keys.count(k) > 0) {
          stepper->positions(static_cast<int>(b), states[b].x);
          states[b].t = t;
          s.body->map_to_surface(states[b], surface[b]);
          frame_times[b].push_back(t);
          frames[b].push_back(surface[b] - s.body->rest_surface());
        }
        continue;
      }
      const BuiltScene& s = *g[b];
      stepper->positions(static_cast<int>(b), states[b].x);
      const double t = stepper->time(static_cast<int>(b));
      states[b].t = t;
      s.body->map_to_surface(states[b], surface[b]);
      Vec3 applied = Vec3::Zero();
      for (const PointLoad& L : s.loads) applied += L.at(t);  // Simulation::applied_force
      scene_trace_sample(s, t, applied, surface[b], states[b].x, 0.0, traces[b]);
      if (want_fields && keys.count(k) > 0) {
        frame_times[b].push_back(t);
        frames[b].push_back(surface[b] - s.body->rest_surface());
      }
    }
  };
  auto set_loads = [&] {
    for (std::size_t b = 0; b < B; ++b)
      stepper->set_loads(static_cast<int>(b), frame_dof_loads(*g[b]->body, g[b]->loads,
                                                              stepper->time(static_cast<int>(b)), f_ext));
  };

  sample(0);
  for (long k = 1; k <= n; ++k) {
    set_loads();  // the loads at the frame start, held over the frame (Simulation::update)
    const auto a = std::chrono::steady_clock::now();
    stepper->step();
    us[static_cast<std::size_t>(k - 1)] =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count();
    sample(k);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double med = median(us);
  double mean = 0;
  for (double u : us) mean += u;
  mean /= static_cast<double>(n);
  for (std::size_t b = 0; b < B; ++b) {
    BatchRunResult& r = out[index[b]];
    RunSummary& s = r.summary;
    s.updates = static_cast<Index>(n);
    s.wall_seconds = seconds;
    s.median_update_us = med;
    s.mean_update_us = mean;
    s.substeps = stepper->substeps(static_cast<int>(b));
    s.warnings = stepper->warnings(static_cast<int>(b));
    summarize_trace(*g[b], traces[b], s);
    for (double t : times) {  // the first recorded frame reaching each time (SceneRunner::run)
      std::size_t j = 0;
      while (j + 1 < frame_times[b].size() && frame_times[b][j] < t - 1e-9) ++j;
      r.field_times.push_back(frame_times[b][j]);
      r.fields.push_back(frames[b][j]);
    }
    r.run_seconds = seconds;
    r.group = group;
    r.group_size = static_cast<int>(B);
  }
}

}  // namespace

std::unique_ptr<BatchStepper> make_cpu_batch_stepper(const std::vector<const BuiltScene*>& group) {
  require(!group.empty(), "batch run: empty group");
  return std::make_unique<CpuBatchStepper>(group);
}

std::vector<PointLoad> frame_dof_loads(const Body& body, const std::vector<PointLoad>& loads, double t,
                                       MatX3& f_ext) {
  const Model& m = body.model();
  f_ext.setZero(m.num_nodes(), 3);
  bool any = false;
  for (const PointLoad& L : loads) {  // as Simulation::update
    const double s = L.scale(t);
    if (s != 0.0) {
      body.transfer_force(L.node, s * L.force, f_ext);
      any = true;
    }
  }
  std::vector<PointLoad> out;
  if (!any) return out;
  for (Index i = 0; i < f_ext.rows(); ++i)
    if (f_ext.row(i).squaredNorm() > 0.0)
      out.push_back({.node = i, .force = f_ext.row(i).transpose(), .t_on = 0.0, .t_ramp = 0.0});
  return out;
}

bool trace_probe(const BuiltScene& b, TraceProbe& p) {
  const std::string kind = b.body->kind();
  if (kind != "surface" && kind != "hybrid" && kind != "volumetric") return false;
  // The map applied to x_i = (i, i^2, -i): a row selection gives each surface row one such triple (an
  // interpolation between rows would not: the mean of squares is not the square of the mean).
  const Model& m = b.body->model();
  const Index n = m.num_nodes();
  State st = make_state(m);
  for (Index i = 0; i < n; ++i) {
    const auto d = static_cast<double>(i);
    st.x.row(i) = Vec3(d, d * d, -d).transpose();
  }
  MatX3 S;
  b.body->map_to_surface(st, S);
  const MatX3& S0 = b.body->rest_surface();
  if (S.rows() != S0.rows()) return false;
  p.surface_dof.resize(static_cast<std::size_t>(S.rows()));
  for (Index s = 0; s < S.rows(); ++s) {
    const double d = S(s, 0);
    if (!(d >= 0 && d < static_cast<double>(n) && d == std::floor(d) && S(s, 1) == d * d && S(s, 2) == -d))
      return false;
    p.surface_dof[static_cast<std::size_t>(s)] = static_cast<Index>(d);
  }
  p.surface_rest = S0;
  const std::size_t points = b.trace_nodes.size() + b.trace_atom_dofs.size();
  p.point_dof.clear();
  p.point_rest.resize(static_cast<Index>(points), 3);
  for (Index i : b.trace_nodes) {
    if (i < 0 || i >= S0.rows()) return false;
    p.point_rest.row(static_cast<Index>(p.point_dof.size())) = S0.row(i);
    p.point_dof.push_back(p.surface_dof[static_cast<std::size_t>(i)]);
  }
  for (Index i : b.trace_atom_dofs) {
    if (i < 0 || i >= n) return false;
    p.point_rest.row(static_cast<Index>(p.point_dof.size())) = m.x0.row(i);
    p.point_dof.push_back(i);
  }
  return true;
}

std::string batch_unsupported(const BuiltScene& b) {
  if (b.settings.local.enabled)
    return "the local deformation overlay (scene \"local\") runs in the Simulation around the step; the "
           "batch "
           "path steps the spring network only";
  if (!b.scene.tools.empty()) return "rigid tools (scene \"tools\") are not part of the batch path";
  return "";
}

std::string batch_key(const BuiltScene& b) {
  const Model& m = b.body->model();
  const StepSettings& s = b.settings.step;
  return cat(b.body->kind(), ':', m.num_nodes(), ':', m.num_springs(), ':', updates_of(b), ':', hex(s.dt),
             ':', static_cast<int>(s.integrator), s.substep, ':', hex(s.safety), ':', s.max_substeps, ':',
             s.guard, ':', hex(s.v_max), ':', s.max_rollbacks, ':', s.threads);
}

std::vector<BatchRunResult> run_scene_batch(const std::vector<const BuiltScene*>& runs,
                                            const BatchStepperFactory& make,
                                            const std::vector<double>& times) {
  for (std::size_t i = 0; i < runs.size(); ++i) {
    require(runs[i] != nullptr, "batch run ", i, ": no scene");
    const std::string why = batch_unsupported(*runs[i]);
    if (!why.empty()) throw InvalidInput(cat("batch run ", i, " (scene '", runs[i]->scene.name, "'): ", why));
    for (std::size_t k = 0; k < times.size(); ++k)
      if (!(std::isfinite(times[k]) && times[k] >= 0 && times[k] <= runs[i]->scene.duration))
        throw InvalidInput(cat("field_times[", k, "]: ", times[k], " ms is outside the scene's [0, ",
                               runs[i]->scene.duration, "] ms"));
  }
  std::vector<std::string> order;  // keys in order of first appearance
  std::map<std::string, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const std::string key = batch_key(*runs[i]);
    auto [it, fresh] = groups.try_emplace(key);
    if (fresh) order.push_back(key);
    it->second.push_back(i);
  }
  std::vector<BatchRunResult> out(runs.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    run_group(runs, groups[order[k]], static_cast<int>(k), make, times, out);
  return out;
}

}  // namespace medspring
