// Compact parameters on the device (gpu::Options::compact_params, docs/gpu.md): 2-byte classes instead of
// per-entry stiffnesses and per-node masses. The kernels read the same values, so the states must equal
// those of the full arrays; the CPU-side check of the same arithmetic is physics_tests
// SpringTable.CompactParametersGiveBitIdenticalSteps. Skips without a device.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "gpu_test_support.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/physics/integrators.hpp"

namespace medspring {
namespace {

// Steps the same model with full and compact parameters; returns the largest relative difference.
// gather: the compact engine's gather batch (gpu::Options::gather_batch); max_classes: its class cap.
double compact_difference(const Model& m, const std::vector<PointLoad>& loads, gpu::Precision p,
                          gpu::Options::Kernel kernel, int frames, std::size_t* bytes_full,
                          std::size_t* bytes_compact, int gather = 1, int max_classes = kCompactClasses) {
  StepSettings s;
  gpu::Options full, compact;
  full.precision = compact.precision = p;
  full.kernel = compact.kernel = kernel;
  full.compact_params = false;  // the per-entry arrays (compact parameters are the default)
  compact.compact_params = true;
  compact.compact_max_classes = max_classes;
  compact.gather_batch = gather;
  gpu::Engine a({&m}, s, full), b({&m}, s, compact);
  a.set_loads(0, loads);
  b.set_loads(0, loads);
  double worst = 0, peak = 0;
  for (int f = 1; f <= frames; ++f) {
    EXPECT_EQ(a.step().substeps, b.step().substeps) << "frame " << f;
    if (f % 10 == 0) {
      worst = std::max({worst, rel(b.positions(0), a.positions(0)), rel(b.velocities(0), a.velocities(0))});
      peak = std::max(peak, (a.positions(0) - m.x0).cwiseAbs().maxCoeff());
    }
  }
  EXPECT_GT(peak, 0.05);  // the load moved the model (mm): not a match of resting states
  *bytes_full = a.device_bytes();
  *bytes_compact = b.device_bytes();
  std::printf(
      "compact %s, %s, %s kernel, gather %d: max relative difference %.3g, peak %.3g mm, device bytes "
      "%zu -> %zu\n",
      m.name.c_str(), p == gpu::Precision::Double ? "fp64" : "fp32",
      kernel == gpu::Options::Kernel::PerBlock ? "one-block-per-model" : "grid", gather, worst, peak,
      *bytes_full, *bytes_compact);
  return worst;
}

TEST(GpuCompact, TubeStatesEqualTheFullArraysWithFewerBytes) {
  REQUIRE_GPU();
  const Model m = tube_model(40, 30);
  const auto loads = press(20 * 30, Vec3(0, 0, -0.8), 150);
  for (const gpu::Precision p : {gpu::Precision::Double, gpu::Precision::Float})
    for (const gpu::Options::Kernel k : {gpu::Options::Kernel::Grid, gpu::Options::Kernel::PerBlock}) {
      std::size_t full = 0, compact = 0;
      EXPECT_LE(compact_difference(m, loads, p, k, 400, &full, &compact), 1e-14);
      EXPECT_LT(compact, full);
    }
}

// The gather batch (Options::gather_batch 2, 4: entries loaded before any force is formed, summed in entry
// order) gives the states of one entry at a time, to rounding (the compiler may contract f += t e into an
// FMA differently); the real-mesh case: the kidney with as many classes as it has stiffnesses (a
// per-spring table). CPU-side twin: HdKernels.GatherBatchesGiveTheSameForces.
TEST(GpuCompact, GatherBatchesAndPerSpringClassesGiveTheSameStates) {
  REQUIRE_GPU();
  const Model m = tube_model(40, 30);
  const auto loads = press(20 * 30, Vec3(0, 0, -0.8), 150);
  const HybridKidney kidney = hybrid_kidney_phantom();
  for (const gpu::Precision p : {gpu::Precision::Double, gpu::Precision::Float})
    for (const int gather : {2, 4}) {
      std::size_t full = 0, compact = 0;
      const double tol = p == gpu::Precision::Double ? 1e-12 : 1e-4;  // fp32: as GPU against CPU (gpu.md)
      EXPECT_LE(compact_difference(m, loads, p, gpu::Options::Kernel::Grid, 400, &full, &compact, gather),
                tol);
      EXPECT_LE(compact_difference(kidney.model(), press(223, Vec3(0, 0, -1.0)), p,
                                   gpu::Options::Kernel::Grid, 200, &full, &compact, gather, 65536),
                tol);
      EXPECT_LT(compact, full);
    }
}

// The kidney's springs are nearly all distinct (1,442 classes, over kCompactClasses): it keeps its arrays.
TEST(GpuCompact, KidneyOverTheClassCapKeepsItsArrays) {
  REQUIRE_GPU();
  const HybridKidney kidney = hybrid_kidney_phantom();
  std::size_t full = 0, compact = 0;
  EXPECT_EQ(compact_difference(kidney.model(), press(223, Vec3(0, 0, -1.0)), gpu::Precision::Double,
                               gpu::Options::Kernel::Grid, 200, &full, &compact),
            0.0);
  EXPECT_LT(compact, full);  // the node parameters (one class) still compact
}

}  // namespace
}  // namespace medspring
