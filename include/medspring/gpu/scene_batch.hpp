// Scene runs in batches on the GPU (docs/gpu.md, "Study runs on the GPU"): the BatchStepper of
// scene/batch.hpp on a gpu::Engine. Header-only, so that neither the scene layer nor the gpu layer depends
// on the other: a target that links both (the Python module, the GPU tests) includes it. No CUDA header.
//
//   std::vector<BatchRunResult> r = run_scene_batch(runs, gpu::scene_batch_stepper(), {500.0});
#pragma once

#include <memory>
#include <vector>

#include "medspring/gpu/engine.hpp"
#include "medspring/scene/batch.hpp"

namespace medspring::gpu {

/// The runs of one group on one Engine (B models, fp64 by default). Refuses (GpuError, before any device
/// work) a model kind, local overlay or tools the GPU path lacks; the Engine refuses models of different
/// topology, bending terms, no device. substeps() and warnings() are the batch's: every model takes the
/// substeps of the stiffest one (each model's own count in the usual case).
class SceneBatchStepper final : public BatchStepper {
 public:
  SceneBatchStepper(const std::vector<const BuiltScene*>& group, const Options& options)
      : e_(models_of(group), group.front()->settings.step, options) {}
  void set_loads(int b, const std::vector<PointLoad>& loads) override { e_.set_loads(b, loads); }
  void step() override { e_.step(); }
  void positions(int b, MatX3& x) override { x = e_.positions(b); }
  double time(int) const override { return e_.time(); }
  std::uint64_t substeps(int) const override { return e_.substeps(); }
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
};

/// The factory run_scene_batch takes.
inline BatchStepperFactory scene_batch_stepper(const Options& options = {}) {
  return [options](const std::vector<const BuiltScene*>& group) -> std::unique_ptr<BatchStepper> {
    return std::make_unique<SceneBatchStepper>(group, options);
  };
}

}  // namespace medspring::gpu
