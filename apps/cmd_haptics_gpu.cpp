// `medspring haptics --device cuda` (docs/gpu.md): the CPU loop's virtual coupling on gpu::HapticLoop, the
// contact node read back asynchronously from the device. Compiled in every build; without the CUDA
// backend it refuses in one line.
#include <cmath>

#include "haptics_gpu.hpp"
#include "medspring/core/check.hpp"
#ifdef MEDSPRING_HAVE_GPU
#include "medspring/gpu/engine.hpp"
#include "medspring/gpu/haptics.hpp"
#endif

namespace medspring::cli {

#ifdef MEDSPRING_HAVE_GPU
HapticsGpuRun run_haptics_gpu(const Body& body, const SimulationSettings& settings, Index contact,
                              const HapticSettings& hs, const Trajectory& path, double duration) {
  require(!path.empty(), "run_trajectory: empty trajectory");
  gpu::require_supported(body.kind(), settings.local.enabled, false);  // before any device work
  require_index(contact, body.num_surface_nodes(), "--node: surface node");
  // surface and hybrid bodies: surface node i is DOF i (identity map), so the GPU loop's model node.
  gpu::Engine engine({&body.model()}, settings.step);
  gpu::HapticLoop loop(engine, 0, contact, hs);
  HapticsGpuRun r;
  const long ticks = static_cast<long>(std::floor(duration / hs.tick + 1e-9));  // as run_trajectory
  r.samples.reserve(static_cast<std::size_t>(std::max(0L, ticks)));
  for (long k = 0; k < ticks; ++k) {
    loop.tick(trajectory_position(path, static_cast<double>(k) * hs.tick));
    r.samples.push_back(loop.last());
  }
  r.stats = tick_stats(r.samples);
  r.updates_per_tick = loop.frames_per_tick();
  r.warnings = engine.warnings().total();
  r.stale_ticks = loop.stale_ticks();
  r.device = engine.device().name;
  return r;
}
#else
HapticsGpuRun run_haptics_gpu(const Body&, const SimulationSettings&, Index, const HapticSettings&,
                              const Trajectory&, double) {
  throw Error(
      "--device cuda: this build has no CUDA backend (MEDSPRING_CUDA, docs/gpu.md); run it on the CPU engine "
      "with --device cpu");
}
#endif

}  // namespace medspring::cli
