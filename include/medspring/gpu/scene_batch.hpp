// Scene runs in batches on the GPU (docs/gpu.md, "Study runs on the GPU"): the BatchStepper of
// scene/batch.hpp on a gpu::Engine. Header-only, so that neither the scene layer nor the gpu layer depends
// on the other: a target that links both (the Python module, the GPU tests) includes it. No CUDA header.
//
//   std::vector<BatchRunResult> r = run_scene_batch(runs, gpu::scene_batch_stepper(), {500.0});
#pragma once

#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "medspring/gpu/engine.hpp"
#include "medspring/scene/batch.hpp"

namespace medspring::gpu {

/// How a frame's traces are taken. Device (the default): reduced on the device (Engine::request_traces:
/// per model max |u| over the surface and |u| of its traced points, B x (1 + points) doubles back per
/// frame), the positions copied back only for the field snapshots; the runner falls back to Async when a
/// run's surface map is not a selection of DOF rows (trace_probe). Async: every model's positions back
/// after every frame in one whole-batch copy (request_positions after the step, then poll_positions for
/// each model) and sampled on the host. Sync: Engine::positions per model (B synchronous copies).
enum class Readback { Device, Async, Sync };

/// The runs of one group on one Engine (B models, fp64 by default). Refuses (GpuError, before any device
/// work) a model kind, local overlay or tools the GPU path lacks; the Engine refuses models of different
/// topology, bending terms, no device. substeps(b) is model b's own (each model takes its own substeps,
/// as its CPU run); warnings() are the batch's.
class SceneBatchStepper final : public BatchStepper {
 public:
  SceneBatchStepper(const std::vector<const BuiltScene*>& group, const Options& options,
                    Readback readback = Readback::Device)
      : e_(models_of(group), group.front()->settings.step, options), readback_(readback) {
    if (readback_ == Readback::Async) e_.request_positions();  // the rest state, for the first sample
  }
  void set_loads(int b, const std::vector<PointLoad>& loads) override { e_.set_loads(b, loads); }
  void step() override {
    e_.step();
    if (reduced_) e_.request_traces();
    if (readback_ == Readback::Async) e_.request_positions();
  }
  bool set_trace_probes(const std::vector<TraceProbe>& probes) override {
    if (readback_ != Readback::Device) return false;
    e_.set_trace_probes(probes);
    e_.request_traces();  // the rest state, for the first sample
    reduced_ = true;
    return true;
  }
  void trace_values(std::vector<double>& out) override { e_.traces(out); }
  void positions(int b, MatX3& x) override {
    if (readback_ == Readback::Sync) {
      x = e_.positions(b);
      return;
    }
    // Device: the field snapshot of this frame, one whole-batch copy requested by the first model asking.
    if (readback_ == Readback::Device && snap_frame_ != e_.frames()) {
      if (!reduced_) {  // the runner samples on the host (trace_probe refused): Async from now on
        readback_ = Readback::Async;
      } else {
        e_.request_positions();
        snap_frame_ = e_.frames();
      }
      if (readback_ == Readback::Async) e_.request_positions();  // this frame, then after every step
    }
    const auto start = std::chrono::steady_clock::now();
    while (!e_.poll_positions(b, x)) {  // this frame's snapshot: newer than the one model b saw last
      if (std::chrono::steady_clock::now() - start > std::chrono::seconds(30))
        throw GpuError("GPU: the positions of a frame did not come back within 30 s (asynchronous readback)");
      std::this_thread::yield();
    }
  }
  double time(int) const override { return e_.time(); }
  std::uint64_t substeps(int b) const override { return e_.substeps(b); }
  std::uint64_t warnings(int) const override { return e_.warnings().total(); }
  const Engine& engine() const { return e_; }

 private:
  static std::vector<const Model*> models_of(const std::vector<const BuiltScene*>& group) {
    std::vector<const Model*> m;
    for (const BuiltScene* b : group) {
      require_supported(b->body->kind(), b->settings.local.enabled, !b->scene.tools.empty());
      m.push_back(&b->body->model());
    }
    return m;
  }
  Engine e_;
  Readback readback_ = Readback::Device;
  bool reduced_ = false;                          // set_trace_probes: the traces are reduced on the device
  std::uint64_t snap_frame_ = ~std::uint64_t{0};  // the frame of the last Device-mode position request
};

/// The factory run_scene_batch takes.
inline BatchStepperFactory scene_batch_stepper(const Options& options = {},
                                               Readback readback = Readback::Device) {
  return [options, readback](const std::vector<const BuiltScene*>& group) -> std::unique_ptr<BatchStepper> {
    return std::make_unique<SceneBatchStepper>(group, options, readback);
  };
}

}  // namespace medspring::gpu
