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

// Several models per thread (Options::models_per_thread 2, 4: each table entry loaded once for M models)
// give the states of one model per thread: a batch of 5 kidneys (the last group partial) with their own
// loads, full and compact (per-spring) parameters, fp64 and fp32. CPU-side twin: HdModels.* (bit for bit).
TEST(GpuCompact, ModelsPerThreadGiveTheStatesOfOneModelPerThread) {
  REQUIRE_GPU();
  const HybridKidney kidney = hybrid_kidney_phantom();
  const Model& m = kidney.model();
  const std::vector<const Model*> models(5, &m);
  StepSettings s;
  for (const gpu::Precision p : {gpu::Precision::Double, gpu::Precision::Float})
    for (const bool compact : {false, true})
      for (const int M : {2, 4}) {
        gpu::Options one, many;
        one.precision = many.precision = p;
        one.compact_params = many.compact_params = compact;
        one.compact_max_classes = many.compact_max_classes = 65536;
        one.gather_batch = many.gather_batch = 1;
        many.models_per_thread = M;
        gpu::Engine a(models, s, one), b(models, s, many);
        for (int i = 0; i < 5; ++i) {
          const auto L = press(40 + 90 * i, Vec3(0.05 * i, 0, -0.3 - 0.15 * i));
          a.set_loads(i, L);
          b.set_loads(i, L);
        }
        double worst = 0, peak = 0;
        for (int f = 1; f <= 200; ++f) {
          EXPECT_EQ(a.step().substeps, b.step().substeps) << "frame " << f;
          if (f % 50 == 0)
            for (int i = 0; i < 5; ++i) {
              worst = std::max(
                  {worst, rel(b.positions(i), a.positions(i)), rel(b.velocities(i), a.velocities(i))});
              peak = std::max(peak, (a.positions(i) - m.x0).cwiseAbs().maxCoeff());
            }
        }
        for (int i = 0; i < 5; ++i) EXPECT_EQ(a.substeps(i), b.substeps(i)) << i;
        EXPECT_GT(peak, 0.05);  // the loads moved the models (mm)
        // The same arithmetic per model; nvcc may contract f += t e differently in the two kernels.
        EXPECT_LE(worst, p == gpu::Precision::Double ? 1e-12 : 1e-4) << M << (compact ? " compact" : "");
        std::printf("models per thread %d, %s, %s: max relative difference to one model per thread %.3g\n", M,
                    p == gpu::Precision::Double ? "fp64" : "fp32", compact ? "compact" : "full", worst);
      }
}

// What models_per_thread cannot do is refused, naming what to use instead: a value other than 0, 1, 2, 4
// (before any device work), a batch with per-model spring parameters, the one-block-per-model kernel.
TEST(GpuCompact, ModelsPerThreadRefusesWhatItCannotRun) {
  const Model m = tube_model(6, 8);
  gpu::Options bad;
  bad.models_per_thread = 3;
  EXPECT_THROW(gpu::Engine({&m, &m}, StepSettings{}, bad), InvalidInput);
  REQUIRE_GPU();
  Model stiff = m;
  for (double& k : stiff.springs.k) k *= 1.5;
  finalize(stiff);
  gpu::Options o;
  o.models_per_thread = 2;
  try {
    gpu::Engine e({&m, &stiff}, StepSettings{}, o);
    ADD_FAILURE() << "per-model spring parameters were accepted with 2 models per thread";
  } catch (const gpu::GpuError& e) {
    EXPECT_NE(std::string(e.what()).find("models_per_thread 1"), std::string::npos) << e.what();
  }
  o.kernel = gpu::Options::Kernel::PerBlock;
  EXPECT_THROW(gpu::Engine({&m, &m}, StepSettings{}, o), gpu::GpuError);
}

// The packed table (Options::packed_table: one 32-bit word per entry, classes of (L0, k, k', 1/k)) gives
// the states of the unpacked compact table on the tube and the kidney (its split rows; a class per spring)
// with fewer bytes; where it cannot run it is refused (one block per model, models per thread) or, for a
// batch whose springs differ, not used, with the reason. CPU-side twin: physics_tests PackedTable.*.
TEST(GpuCompact, PackedTableGivesTheStatesOfTheUnpackedTable) {
  REQUIRE_GPU();
  const Model tube = tube_model(40, 30);
  const HybridKidney kidney = hybrid_kidney_phantom();
  StepSettings s;
  for (const gpu::Precision p : {gpu::Precision::Double, gpu::Precision::Float})
    for (const Model* m : {&tube, &kidney.model()}) {
      gpu::Options unpacked, packed;
      unpacked.precision = packed.precision = p;
      unpacked.compact_max_classes = packed.compact_max_classes = 65536;
      unpacked.gather_batch = packed.gather_batch = 1;
      packed.packed_table = true;
      gpu::Engine a({m}, s, unpacked), b({m}, s, packed);
      ASSERT_TRUE(b.pack_report().fits) << b.packed_table_note();
      EXPECT_FALSE(a.pack_report().fits);  // not requested
      EXPECT_LT(b.device_bytes(), a.device_bytes());
      const auto loads = m == &tube ? press(20 * 30, Vec3(0, 0, -0.8), 150) : press(223, Vec3(0, 0, -1.0));
      a.set_loads(0, loads);
      b.set_loads(0, loads);
      double worst = 0, peak = 0;
      for (int f = 1; f <= 300; ++f) {
        EXPECT_EQ(a.step().substeps, b.step().substeps) << "frame " << f;
        if (f % 50 == 0) {
          worst =
              std::max({worst, rel(b.positions(0), a.positions(0)), rel(b.velocities(0), a.velocities(0))});
          peak = std::max(peak, (a.positions(0) - m->x0).cwiseAbs().maxCoeff());
        }
      }
      EXPECT_GT(peak, 0.05);
      EXPECT_LE(worst, p == gpu::Precision::Double ? 1e-12 : 1e-4) << m->name;
      std::printf(
          "packed table %s, %s: %lld classes in %d bits, offsets up to %lld; max relative difference "
          "%.3g; device bytes %zu -> %zu\n",
          m->name.c_str(), p == gpu::Precision::Double ? "fp64" : "fp32", b.pack_report().classes,
          b.pack_report().class_bits, b.pack_report().max_offset, worst, a.device_bytes(), b.device_bytes());
    }
}

TEST(GpuCompact, PackedTableIsRefusedOrNotUsedWhereItCannotRun) {
  REQUIRE_GPU();
  const Model m = tube_model(6, 8);
  Model stiff = m;
  for (double& k : stiff.springs.k) k *= 1.5;
  finalize(stiff);
  gpu::Options o;
  o.packed_table = true;
  {
    gpu::Engine e({&m, &stiff}, StepSettings{}, o);  // the models' springs differ: one table cannot serve
    EXPECT_FALSE(e.pack_report().fits);
    EXPECT_NE(e.packed_table_note().find("unpacked table runs"), std::string::npos) << e.packed_table_note();
  }
  gpu::Options block = o;
  block.kernel = gpu::Options::Kernel::PerBlock;
  EXPECT_THROW(gpu::Engine({&m}, StepSettings{}, block), gpu::GpuError);
  gpu::Options many = o;
  many.models_per_thread = 2;
  EXPECT_THROW(gpu::Engine({&m, &m}, StepSettings{}, many), gpu::GpuError);
}

}  // namespace
}  // namespace medspring
