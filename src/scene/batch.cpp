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

  auto sample = [&](long k) {
    for (std::size_t b = 0; b < B; ++b) {
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
