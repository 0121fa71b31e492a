// `medspring haptics --device cuda` (docs/gpu.md, "The haptic read"): the haptic loop on gpu::HapticLoop.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "medspring/models/body.hpp"
#include "medspring/sim/haptics.hpp"

namespace medspring::cli {

struct HapticsGpuRun {
  std::vector<HapticSample> samples;  // one per tick, as HapticLoop::samples() of the CPU loop
  TickStats stats;
  int updates_per_tick = 1;
  std::uint64_t warnings = 0;
  long stale_ticks = 0;  // ticks that used the previous tick's contact read (the GPU had not delivered)
  std::string device;    // the card's name
};

/// Replays `path` as run_trajectory does, on gpu::HapticLoop over a one-model gpu::Engine of `body`.
/// Throws (exit 1, one line naming the cause and --device cpu) in a build without the CUDA backend, on
/// a machine without a usable device, for --local or a model kind the GPU path lacks.
HapticsGpuRun run_haptics_gpu(const Body& body, const SimulationSettings& settings, Index contact,
                              const HapticSettings& hs, const Trajectory& path, double duration);

}  // namespace medspring::cli
