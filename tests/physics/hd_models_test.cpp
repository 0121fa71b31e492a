// Several models per thread (gpu::Options::models_per_thread; hd::node_substep_models and the split-row
// variants, physics/kernels_models.hpp) on the CPU: a batch stepped by groups of M = 2 and 4 models per
// "thread", each table entry loaded once for the group, gives every model's substeps bit for bit as the
// single-model functions applied to that model alone (docs/gpu.md). Checked with EXPECT_EQ: each model's
// loop body is the single-model expression, so GCC (-march=native) contracts both alike here.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "medspring/geometry/phantoms.hpp"
#include "models_stepper.hpp"

namespace medspring {
namespace {

using testing::ModelsBatch;

Model tube_of(bool soft, double mass_scale = 1.0) {
  SurfaceBodyParams p;
  p.duffing.soft = soft;
  const Index rings = 12, spokes = 10;
  for (Index j = 0; j < spokes; ++j) {
    p.fixed.push_back(j);
    p.fixed.push_back((rings - 1) * spokes + j);
  }
  Model m = make_surface_model(tube(rings, spokes, 2.5, 4.0), p, soft ? "soft_tube" : "tube");
  if (mass_scale != 1.0) {
    m.mass *= mass_scale;
    m.damping *= 1.0 / mass_scale;
    m.kr *= mass_scale;
    finalize(m);
  }
  return m;
}

// A hub with 37 spokes and a ring of 37 (the kidney's atoms: heavy rows split over several rows), spread
// stiffnesses, some pinned ring nodes.
Model hub() {
  ModelBuilder b("hub");
  b.add_node(Vec3(0, 0, 0), 0.3, 0.15, 0.02);
  for (int i = 0; i < 37; ++i)
    b.add_node(Vec3(10 * std::cos(0.17 * i), 10 * std::sin(0.17 * i), 0.1 * i), 0.3, 0.15, 0.02, i % 9 == 0);
  for (int i = 0; i < 37; ++i) {
    b.add_spring(0, 1 + i, 0.05 + 0.001 * i, 0.002 * (i % 3), 10.0);
    b.add_spring(1 + i, 1 + (i + 1) % 37, 0.04 + 0.0005 * i, 0.0, 1.7);
  }
  return b.build();
}

std::vector<PointLoad> press(Index node, Vec3 F) {
  PointLoad L;
  L.node = node;
  L.force = F;
  L.t_ramp = 0.5;
  return {L};
}

// B models stepped `substeps` times both ways (model b sits out the substeps k with (k + b) % 5 == 0, as a
// model past its count does in the kernel; the stiffening on every third): every model's positions,
// velocities and stiffening equal, bit for bit.
template <class R, bool Soft>
void expect_models_equal(const std::vector<const Model*>& ms, int M, int chunk, bool compact, int substeps,
                         R h) {
  std::vector<std::vector<PointLoad>> loads;
  for (std::size_t b = 0; b < ms.size(); ++b)
    loads.push_back(press(static_cast<Index>((5 + 17 * b) % static_cast<std::size_t>(ms[0]->num_nodes())),
                          Vec3(0.05 * static_cast<double>(b), 0, -0.3 - 0.1 * static_cast<double>(b))));
  ModelsBatch<R> mb(ms, loads, M, chunk, compact);
  SCOPED_TRACE(ms[0]->name + ", M = " + std::to_string(M) + ", B = " + std::to_string(ms.size()) +
               (mb.split ? ", split rows" : "") +
               (mb.shared_nodes ? ", shared node arrays" : ", per-model nodes") +
               (compact ? ", compact" : ""));
  const std::vector<R> x_start = mb.x;
  const R vmax2 = R(1e30);
  for (int k = 0; k < substeps; ++k) {
    std::vector<bool> active(ms.size());
    for (std::size_t b = 0; b < ms.size(); ++b) active[b] = (static_cast<std::size_t>(k) + b) % 5 != 0;
    const double t = 0.1 * k;
    if (k % 3 == 2)
      mb.template substep<Soft, true>(t, h, vmax2, active);
    else
      mb.template substep<Soft, false>(t, h, vmax2, active);
    if (k % 3 == 2)
      for (std::size_t b = 0; b < ms.size(); ++b)
        if (active[b]) {
          EXPECT_EQ(mb.stiff[b], mb.rstiff[b]) << "substep " << k << ", model " << b;
        }
    int rc = hd::kNodeOk, bc = hd::kNodeOk;
    for (std::size_t b = 0; b < ms.size(); ++b) {
      rc = std::max(rc, mb.rcode[b]);
      bc = std::max(bc, mb.code[b]);
    }
    EXPECT_EQ(bc, rc) << "substep " << k;
  }
  double moved = 0;
  for (std::size_t q = 0; q < mb.x.size(); ++q)
    moved = std::max(moved, std::abs(static_cast<double>(mb.x[q] - x_start[q])));
  EXPECT_GT(moved, 1e-3);  // the models moved: not a match of resting states
  for (int b = 0; b < static_cast<int>(ms.size()); ++b) {
    const auto ub = static_cast<std::size_t>(b);
    EXPECT_EQ(mb.batch_state(b, false), mb.rx[ub]) << "positions of model " << b;
    EXPECT_EQ(mb.batch_state(b, true), mb.rv[ub]) << "velocities of model " << b;
  }
}

TEST(HdModels, ModelsPerThreadGiveEachModelsSubstepsBitForBit) {
  const Model hard = tube_of(false), soft = tube_of(true), heavy = tube_of(true, 1.7);
  for (const int M : {2, 4}) {
    // Shared node arrays (copies of one model with their own loads: the kidney batch of a dataset); B not a
    // multiple of M, so the last group is partial.
    expect_models_equal<double, false>({&hard, &hard, &hard}, M, 1000, false, 60, 0.05);
    expect_models_equal<double, false>({&hard, &hard, &hard, &hard, &hard}, M, 1000, true, 60, 0.05);
    expect_models_equal<double, true>({&soft, &soft, &soft, &soft, &soft}, M, 1000, false, 60, 0.05);
    // Per-model node arrays (a heavier copy): node stride n.
    expect_models_equal<double, true>({&soft, &heavy, &soft, &heavy, &soft}, M, 1000, false, 60, 0.05);
    expect_models_equal<float, true>({&soft, &heavy, &soft}, M, 1000, true, 60, 0.05f);
    expect_models_equal<float, false>({&hard, &hard, &hard, &hard, &hard}, M, 1000, true, 60, 0.05f);
  }
}

// Heavy rows split over several rows (the grid kernel's split table, the kidney's atoms): chunk rows write
// each model's partial sums, lead rows advance every model's node.
TEST(HdModels, ModelsPerThreadOnSplitRowsGiveEachModelsSubstepsBitForBit) {
  const Model h = hub(), soft = tube_of(true);
  for (const int M : {2, 4}) {
    expect_models_equal<double, false>({&h, &h, &h, &h, &h}, M, 8, false, 60, 0.05);
    expect_models_equal<double, false>({&h, &h, &h}, M, 8, true, 60, 0.05);
    expect_models_equal<double, true>({&soft, &soft, &soft}, M, 3, false, 60, 0.05);  // every node split
    expect_models_equal<float, false>({&h, &h, &h, &h, &h}, M, 8, true, 60, 0.05f);
  }
}

}  // namespace
}  // namespace medspring
