// The 1 kHz haptic loop of ALGORITHMS.md §2.5 on a gpu::Engine (docs/gpu.md): the CPU loop's virtual
// coupling (sim/haptics.hpp, HapticSettings) with the contact node read from the device through the
// engine's asynchronous node readback (request_node / poll_node: 3 reals, pinned, double-buffered), never
// a copy of the state.
//
//   gpu::Engine e({&kidney.model()}, {});
//   gpu::HapticLoop loop(e, 0, contact_node);
//   for (;;) { Vec3 reaction = loop.tick(device_position()); send_to_device(reaction); }
#pragma once

#include "medspring/gpu/engine.hpp"
#include "medspring/sim/haptics.hpp"

namespace medspring::gpu {

class HapticLoop {
 public:
  /// Couples a tool to node `contact` of model `model` of `engine` (which must outlive the loop). The
  /// tick must be a whole multiple of the engine's dt. The model's loads are replaced by the coupling
  /// force. Throws InvalidInput naming the setting at fault.
  HapticLoop(Engine& engine, int model, Index contact, const HapticSettings& settings = {});

  /// One tick: x_c is the newest contact position the device has delivered (the read requested at the
  /// end of the previous tick; when it has not arrived yet, the one before is used and stale_ticks()
  /// counts it — the loop never waits for the GPU, except once on the first tick). Then the CPU loop's
  /// coupling F = k_vc (x_tool - x_c) + b_vc (v_tool - v_c), saturated to f_max, is applied to the
  /// contact node for the tick, the engine advances by `tick`, and the next read is requested.
  /// Returns the reaction for the device, -F (N).
  Vec3 tick(const Vec3& x_tool);
  /// Lets go of the tissue (no tool force until the next tick()).
  void release();

  const HapticSample& last() const { return last_; }
  long stale_ticks() const { return stale_; }
  int frames_per_tick() const { return frames_per_tick_; }

 private:
  Engine& engine_;
  int model_;
  Index contact_;
  HapticSettings settings_;
  int frames_per_tick_ = 1;
  bool first_ = true, have_read_ = false;
  long stale_ = 0;
  Vec3 x_c_ = Vec3::Zero(), tool_prev_ = Vec3::Zero(), contact_prev_ = Vec3::Zero();
  HapticSample last_;
};

}  // namespace medspring::gpu
