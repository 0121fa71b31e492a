// The haptic loop on the GPU engine (gpu/haptics.hpp, docs/gpu.md): sim/haptics.cpp's coupling with the
// contact node read through the engine's asynchronous node readback.
#include "medspring/gpu/haptics.hpp"

#include <chrono>
#include <cmath>
#include <thread>

#include "medspring/core/check.hpp"

namespace medspring::gpu {

HapticLoop::HapticLoop(Engine& engine, int model, Index contact, const HapticSettings& s)
    : engine_(engine), model_(model), contact_(contact), settings_(s) {
  require(model >= 0 && model < engine.batch(), "gpu::HapticLoop: model ", model, " out of range (batch of ",
          engine.batch(), ")");
  require(contact >= 0 && contact < engine.nodes(), "gpu::HapticLoop: contact node ", contact,
          " out of range (", engine.nodes(), " nodes)");
  require(std::isfinite(s.tick) && s.tick > 0, "haptics.tick: must be > 0 ms (got ", s.tick, ")");
  require(std::isfinite(s.k_vc) && s.k_vc >= 0, "haptics.k_vc: must be >= 0 (got ", s.k_vc, ")");
  require(std::isfinite(s.b_vc) && s.b_vc >= 0, "haptics.b_vc: must be >= 0 (got ", s.b_vc, ")");
  require(std::isfinite(s.f_max) && s.f_max > 0, "haptics.f_max: must be > 0 N (got ", s.f_max, ")");
  const double dt = engine.settings().dt;
  const double ratio = s.tick / dt;
  frames_per_tick_ = static_cast<int>(std::lround(ratio));
  require(frames_per_tick_ >= 1 && std::abs(ratio - frames_per_tick_) <= 1e-9 * ratio,
          "haptics.tick: ", s.tick, " ms is not a whole multiple of the step dt (", dt, " ms)");
  engine_.request_node(model_, contact_);
}

Vec3 HapticLoop::tick(const Vec3& x_tool) {
  const auto start = std::chrono::steady_clock::now();
  Vec3 read;
  if (engine_.poll_node(read)) {
    x_c_ = read;
    have_read_ = true;
  } else if (!have_read_) {  // the first read: wait for it once
    while (!engine_.poll_node(read)) std::this_thread::yield();
    x_c_ = read;
    have_read_ = true;
  } else {
    ++stale_;
  }
  Vec3 v_tool = Vec3::Zero(), v_c = Vec3::Zero();
  if (!first_) {
    v_tool = (x_tool - tool_prev_) / settings_.tick;
    v_c = (x_c_ - contact_prev_) / settings_.tick;
  }
  Vec3 F = settings_.k_vc * (x_tool - x_c_) + settings_.b_vc * (v_tool - v_c);  // §2.5 virtual coupling
  const double norm = F.norm();
  const bool saturated = norm > settings_.f_max;
  if (saturated) F *= settings_.f_max / norm;
  if (!F.allFinite()) F.setZero();
  HapticSample s;
  s.t = engine_.time();
  s.tool = x_tool;
  s.contact = x_c_;
  s.force = F;
  s.saturated = saturated;
  PointLoad L;
  L.node = contact_;
  L.force = F;
  L.t_ramp = 0;  // held for the whole tick
  engine_.set_loads(model_, {L});
  for (int i = 0; i < frames_per_tick_; ++i) engine_.step();
  engine_.request_node(model_, contact_);
  s.compute_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  tool_prev_ = x_tool;
  contact_prev_ = x_c_;
  first_ = false;
  last_ = s;
  return -F;
}

void HapticLoop::release() {
  engine_.set_loads(model_, {});
  first_ = true;
}

}  // namespace medspring::gpu
