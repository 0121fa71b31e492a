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

/// How the runs' positions come back after every frame: Async, one whole-batch copy per frame
/// (request_positions after the step, then poll_positions for each model: one device-to-host transfer
/// instead of B); Sync, Engine::positions per model (B synchronous copies).
enum class Readback { Async, Sync };

/// The runs of one group on one Engine (B models, fp64 by default). Refuses (GpuError, before any device
/// work) a model kind, local overlay or tools the GPU path lacks; the Engine refuses models of different
/// topology, bending terms, no device. substeps(b) is model b's own (each model takes its own substeps,
/// as its CPU run); warnings() are the batch's.
class SceneBatchStepper final : public BatchStepper {
 public:
  SceneBatchStepper(const std::vector<const BuiltScene*>& group, const Options& options,
                    Readback readback = Readback::Async)
      : e_(models_of(group), group.front()->settings.step, options), async_(readback == Readback::Async) {
    if (async_) e_.request_positions();  // the rest state, for the first sample
  }
  void set_loads(int b, const std::vector<PointLoad>& loads) override { e_.set_loads(b, loads); }
  void step() override {
    e_.step();
    if (async_) e_.request_positions();
  }
  void positions(int b, MatX3& x) override {
    if (!async_) {
      x = e_.positions(b);
      return;
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
  bool async_ = true;
};

/// The factory run_scene_batch takes.
inline BatchStepperFactory scene_batch_stepper(const Options& options = {},
                                               Readback readback = Readback::Async) {
  return [options, readback](const std::vector<const BuiltScene*>& group) -> std::unique_ptr<BatchStepper> {
    return std::make_unique<SceneBatchStepper>(group, options, readback);
  };
}

}  // namespace medspring::gpu
