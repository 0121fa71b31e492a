// Scene runs in batches (docs/gpu.md, "Study runs on the GPU"): B runs of scenes whose models share one
// topology stepped together by a batch engine — the CUDA backend's gpu::Engine (`medspring study --device
// cuda`), or the CPU reference below, which steps each model with step() — and each run's traces and
// summary computed by the same code as run_scene (scene_trace_sample, summarize_trace).
//
//   std::vector<BatchRunResult> r = run_scene_batch({&a, &b, &c}, make_cpu_batch_stepper, {500.0});
//   r[1].summary.contact_hold_mm, r[1].fields[0]   // as run_scene / SceneRunner for run b
//
// Engine layer: Eigen only, no CUDA header (the GPU stepper is made by the caller, python/src/bind_gpu.cpp).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "medspring/physics/trace_table.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/runner.hpp"

namespace medspring {

/// What run_scene_batch needs of a batch engine: B models of one topology advanced one frame at a time.
class BatchStepper {
 public:
  virtual ~BatchStepper() = default;
  /// Loads of model b on its DOFs, held until changed (frame_dof_loads gives constant ones).
  virtual void set_loads(int b, const std::vector<PointLoad>& loads) = 0;
  /// One frame of the settings' dt for every model.
  virtual void step() = 0;
  /// Positions of model b (#nodes x 3).
  virtual void positions(int b, MatX3& x) = 0;
  virtual double time(int b) const = 0;             // ms
  virtual std::uint64_t substeps(int b) const = 0;  // substeps taken so far
  virtual std::uint64_t warnings(int b) const = 0;  // Warnings::total() so far
  /// Optional (docs/gpu.md, "Study runs on the GPU"): the stepper computes each frame's trace values
  /// itself (gpu::SceneBatchStepper: on the device) from one probe per model; then run_scene_batch reads
  /// trace_values() after every frame and positions() only for the field snapshots. Returns false when
  /// the stepper has no such reduction (the default): the runner samples positions() on the host.
  virtual bool set_trace_probes(const std::vector<TraceProbe>& /*probes*/) { return false; }
  /// After step() (and before the first): every model's values of this frame, B x (1 + points) as
  /// hd::trace_sample writes them (max |u| over the surface, then |u| of each traced point).
  virtual void trace_values(std::vector<double>& /*out*/) {}
};

/// Makes the stepper of a group of runs (same topology, step settings and number of updates); the runs'
/// models are group[i]->body->model(), their settings group[0]->settings.step. May throw (GpuError: no
/// device, a model kind the GPU lacks): run_scene_batch lets it through.
using BatchStepperFactory =
    std::function<std::unique_ptr<BatchStepper>(const std::vector<const BuiltScene*>& group)>;

/// The CPU reference: each model stepped by step() from its own State (x0, v = 0), as Simulation does.
std::unique_ptr<BatchStepper> make_cpu_batch_stepper(const std::vector<const BuiltScene*>& group);

/// The DOF loads of one frame starting at time t: the scene's surface loads scaled at t and transferred
/// by the body, summed per DOF exactly as Simulation::update fills f_ext; each non-zero DOF row becomes a
/// constant load (t_on 0, no ramp, never released) of that row. `f_ext` is work space (resized).
std::vector<PointLoad> frame_dof_loads(const Body& body, const std::vector<PointLoad>& loads, double t,
                                       MatX3& f_ext);

/// What a run samples per frame (physics/trace_table.hpp): its surface as DOF rows (the body's
/// map_to_surface when that is a selection of DOF rows, as for the surface and hybrid bodies) with the
/// rest surface, then its traced points: trace_nodes (surface rows, rest surface) and trace_atom_dofs
/// (model rest positions), in scene_trace_sample's order. False when the map is not a row selection.
bool trace_probe(const BuiltScene& built, TraceProbe& probe);

/// Why a built scene cannot run in a batch ("" when it can): the local deformation overlay and rigid
/// tools need the Simulation around the step, which the batch path does not run.
std::string batch_unsupported(const BuiltScene& built);

/// The key under which runs share a batch: node and spring count, number of updates, step settings.
std::string batch_key(const BuiltScene& built);

struct BatchRunResult {
  RunSummary summary;
  std::vector<double> field_times;  // the frames' times of `fields` (first recorded frame >= each time)
  std::vector<MatX3> fields;        // surface displacement at those frames, mm (as SceneRunner)
  double run_seconds = 0.0;         // wall time of the run's group, shared by its runs
  int group = 0;                    // which batch it ran in (0, 1, ... in order of first appearance)
  int group_size = 0;
};

/// Runs every scene for its duration in batches of runs with equal batch_key (one stepper per group, in
/// order of first appearance), recording per run what run_scene records (traces without energy and
/// tools) and its summary by summarize_trace; fields (surface displacement) at `field_times` as
/// SceneRunner. median_update_us is the batch's frame time, and substeps and warnings are the stepper's
/// for the model. Throws InvalidInput for a run batch_unsupported refuses or a bad field time, and
/// whatever the factory throws.
std::vector<BatchRunResult> run_scene_batch(const std::vector<const BuiltScene*>& runs,
                                            const BatchStepperFactory& make,
                                            const std::vector<double>& field_times);

}  // namespace medspring
