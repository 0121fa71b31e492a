// The GPU path's arithmetic on the CPU: the spring table gather and hd::node_substep (the code the CUDA
// kernels run, physics/kernels.hpp) against the engine's own step() (docs/gpu.md).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>
#include <string>

#include "gather_stepper.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/spring_table.hpp"

namespace medspring {
namespace {

using testing::GatherStepper;
using testing::relative_difference;

Model small_tube(bool soft) {
  SurfaceBodyParams p;
  p.duffing.soft = soft;
  const Index rings = 12, spokes = 10;
  for (Index j = 0; j < spokes; ++j) {
    p.fixed.push_back(j);
    p.fixed.push_back((rings - 1) * spokes + j);
  }
  return make_surface_model(tube(rings, spokes, 2.5, 4.0), p, soft ? "soft_tube" : "tube");
}

// A soft spring pulled past its peak (§1.7): node 1 is held by its return spring.
Model soft_pair() {
  ModelBuilder b("soft_pair");
  b.add_node(Vec3(0, 0, 0), 0.3, 0.15, 0.02, true);
  b.add_node(Vec3(10, 0, 0), 0.3, 0.15, 0.02);
  b.add_spring(0, 1, 0.05, -0.05 / 100.0, 10.0);
  return b.build();
}

std::vector<PointLoad> press(Index node, Vec3 F) {
  PointLoad L;
  L.node = node;
  L.force = F;
  L.t_on = 1.0;
  L.t_ramp = 10.0;
  L.t_release = 60.0;
  PointLoad L2 = L;  // a second load on the same node: summed in load order
  L2.force = 0.25 * F;
  L2.t_ramp = 0.0;
  return {L, L2};
}

// Runs step() and the gather stepper side by side; returns the largest relative difference seen.
template <class R>
double compare(const Model& m, const std::vector<PointLoad>& loads, int frames, double dt = 0.5) {
  StepSettings s;
  s.dt = dt;
  State st = make_state(m, s);
  GatherStepper<R> g(m, loads);
  double worst = 0, peak = 0;
  for (int f = 0; f < frames; ++f) {
    const StepStatus status = step(m, st, s, &loads);
    EXPECT_EQ(status.code, StepCode::Ok) << "frame " << f;
    g.frame(s);
    worst = std::max({worst, relative_difference(g.x, st.x), relative_difference(g.v, st.v)});
    peak = std::max(peak, (st.x - m.x0).cwiseAbs().maxCoeff());
    EXPECT_NEAR(g.stiffening, st.stiffening, (sizeof(R) == 8 ? 1e-9 : 1e-4) * st.stiffening) << "frame " << f;
  }
  EXPECT_GT(peak, 0.05);  // the load moved the model (mm): not a trivial match
  EXPECT_EQ(g.substeps, static_cast<long>(st.substeps));
  ::testing::Test::RecordProperty(
      sizeof(R) == 8 ? "max_relative_difference_fp64" : "max_relative_difference_fp32",
      (std::ostringstream() << std::scientific << worst).str());
  EXPECT_EQ(g.failures, 0);
  EXPECT_TRUE(st.x.allFinite());
  return worst;
}

TEST(SpringTable, EntriesPerNodeInSpringOrderPaddedWithSelf) {
  const Model m = small_tube(false);
  const SpringTableArrays<double> T = make_spring_table<double>(m);
  const auto view = T.view();
  std::vector<int> degree(static_cast<std::size_t>(m.num_nodes()), 0);
  for (Index s = 0; s < m.num_springs(); ++s) {
    ++degree[static_cast<std::size_t>(m.springs.i[static_cast<std::size_t>(s)])];
    ++degree[static_cast<std::size_t>(m.springs.j[static_cast<std::size_t>(s)])];
  }
  for (Index a = 0; a < m.num_nodes(); ++a) {
    const int sl = a / hd::kSlice;
    int e = view.slice_begin[sl] + a % hd::kSlice;
    int real = 0;
    for (int j = 0; j < view.slice_width[sl]; ++j, e += hd::kSlice) {
      if (view.other[e] == a) {
        EXPECT_EQ(view.k[e], 0.0);
        continue;
      }
      ++real;
      EXPECT_GT(view.L0[e], 0.0);
    }
    EXPECT_EQ(real, degree[static_cast<std::size_t>(a)]) << "node " << a;
  }
}

TEST(SpringTable, RefusesBendingTerms) {
  ModelBuilder b("bent");
  for (int i = 0; i < 3; ++i) b.add_node(Vec3(2.5 * i, 0, 0), 0.3, 0.15, 0.02, i == 0);
  b.add_spring(0, 1, 0.05, 0.0, 2.5);
  b.add_spring(1, 2, 0.05, 0.0, 2.5);
  b.add_bending(0, 1, 2, 0.01);
  const Model m = b.build();
  EXPECT_THROW(make_spring_table<double>(m), InvalidInput);
}

TEST(HdKernels, LoadScaleIsPointLoadScale) {
  PointLoad L;
  L.t_on = 2;
  L.t_ramp = 4;
  L.t_release = 9;
  for (bool down : {false, true}) {
    L.ramp_down = down;
    for (double t = 0; t < 16; t += 0.37)
      EXPECT_EQ(hd::load_scale(t, L.t_on, L.t_ramp, L.t_release, L.ramp_down), L.scale(t)) << t;
  }
}

TEST(HdKernels, SoftLawClampsBeyondThePeak) {
  const double k = 0.05, kp = -0.05 / 100.0;
  const double peak = std::sqrt(k / (3 * -kp));
  const double phi_peak = k * peak + kp * peak * peak * peak;
  EXPECT_DOUBLE_EQ(hd::spring_tension(k, kp, 2 * peak), phi_peak);
  EXPECT_DOUBLE_EQ(hd::spring_tension(k, kp, -2 * peak), -phi_peak);
  EXPECT_EQ(hd::spring_tension_derivative(k, kp, 2 * peak), 0.0);
  EXPECT_NEAR(hd::spring_tension(k, kp, 0.5 * peak), k * 0.5 * peak + kp * std::pow(0.5 * peak, 3), 1e-15);
}

// The gather adds each node's spring terms in spring order, starting from its return spring and load:
// the serial spring pass's order. Expected: equal up to the compiler's FMA contraction choices (the CPU
// build contracts with -march=native), far below the 1e-12 the GPU agreement tests ask for.
TEST(HdKernels, GatherStepEqualsEngineStepHardTube) {
  const Model m = small_tube(false);
  EXPECT_LE(compare<double>(m, press(55, Vec3(0, 0, -0.8)), 300), 1e-13);
}

TEST(HdKernels, GatherStepEqualsEngineStepSoftTube) {
  const Model m = small_tube(true);
  ASSERT_TRUE(m.has_soft_springs);
  EXPECT_LE(compare<double>(m, press(65, Vec3(0.3, 0, -0.6)), 300), 1e-13);
}

TEST(HdKernels, GatherStepEqualsEngineStepSoftSpringPastItsPeak) {
  const Model m = soft_pair();
  PointLoad L;
  L.node = 1;
  L.force = Vec3(0.5, 0, 0);  // the spring carries at most ~0.19 N
  L.t_ramp = 5;
  EXPECT_LE(compare<double>(m, {L}, 400), 1e-13);
  StepSettings s;
  State st = make_state(m, s);
  const std::vector<PointLoad> loads{L};
  for (int f = 0; f < 400; ++f) step(m, st, s, &loads);
  EXPECT_GT(st.x(1, 0) - 10.0, std::sqrt(0.05 / (3 * 0.05 / 100.0)));  // beyond the peak: clamped law used
}

// fp32 (the GPU's option): the same trajectory to a stated tolerance, 2e-5 of the largest coordinate.
TEST(HdKernels, Fp32GatherFollowsTheFp64Engine) {
  const Model m = small_tube(false);
  EXPECT_LE(compare<float>(m, press(55, Vec3(0, 0, -0.8)), 200), 2e-5);
}

// The one-block-per-model algorithm (physics/kernels.hpp hd::block_rows, as block_frame_kernel runs it)
// against step(): 120 nodes dealt to 64 threads (two rows per thread, degree order), soft springs, a
// second load on the node; and in fp32.
template <class R>
double compare_block(const Model& m, const std::vector<PointLoad>& loads, int frames, int threads) {
  StepSettings s;
  State st = make_state(m, s);
  testing::BlockStepper<R> blk(m, loads, threads);
  double worst = 0, peak = 0;
  for (int f = 0; f < frames; ++f) {
    EXPECT_EQ(step(m, st, s, &loads).code, StepCode::Ok) << "frame " << f;
    blk.frame(s);
    worst = std::max({worst, relative_difference(blk.x, st.x), relative_difference(blk.v, st.v)});
    peak = std::max(peak, (st.x - m.x0).cwiseAbs().maxCoeff());
  }
  EXPECT_EQ(blk.substeps, static_cast<long>(st.substeps));
  EXPECT_EQ(blk.failures, 0);
  EXPECT_GT(peak, 0.05);  // the load moved the model (mm): not a trivial match
  ::testing::Test::RecordProperty(
      sizeof(R) == 8 ? "block_max_relative_difference_fp64" : "block_max_relative_difference_fp32",
      (std::ostringstream() << std::scientific << worst).str());
  return worst;
}

TEST(HdKernels, OneBlockPerModelEqualsEngineStepSoftTube) {
  const Model m = small_tube(true);
  EXPECT_LE(compare_block<double>(m, press(65, Vec3(0.3, 0, -0.6)), 300, 64), 1e-13);
}

TEST(HdKernels, OneBlockPerModelFp32WithinTheStatedTolerance) {
  const Model m = small_tube(false);
  EXPECT_LE(compare_block<float>(m, press(55, Vec3(0, 0, -0.8)), 200, 64), 2e-5);
}

// Heavy rows split (kernels_split.hpp) with chunks of 3 springs: every tube node (pinned ones included)
// is split, so phase 2 advances every free node from its chunks' partial sums; soft springs.
TEST(HdKernels, SplitRowsEqualEngineStepSoftTube) {
  const Model m = small_tube(true);
  const auto loads = press(65, Vec3(0.3, 0, -0.6));
  StepSettings s;
  State st = make_state(m, s);
  testing::SplitStepper<double> sp(m, loads, 64, 3);
  ASSERT_EQ(sp.S.heavy_node.size(), static_cast<std::size_t>(m.num_nodes()));
  double worst = 0, peak = 0;
  for (int f = 0; f < 300; ++f) {
    ASSERT_EQ(step(m, st, s, &loads).code, StepCode::Ok) << "frame " << f;
    sp.frame(s);
    worst = std::max({worst, relative_difference(sp.x, st.x), relative_difference(sp.v, st.v)});
    peak = std::max(peak, (st.x - m.x0).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(peak, 0.05);
  EXPECT_LE(worst, 1e-12);
  EXPECT_EQ(sp.substeps, static_cast<long>(st.substeps));
  EXPECT_NEAR(sp.stiffening, st.stiffening, 1e-9 * st.stiffening);
  ::testing::Test::RecordProperty("split_max_relative_difference_fp64",
                                  (std::ostringstream() << std::scientific << worst).str());
}

TEST(HdKernels, GridSplitRowsEqualEngineStepSoftTube) {
  const Model m = small_tube(true);
  const auto loads = press(65, Vec3(0.3, 0, -0.6));
  StepSettings s;
  State st = make_state(m, s);
  testing::GridSplitStepper<double> gp(m, loads, 3);  // every node split into chunks of at most 3
  ASSERT_EQ(gp.G.heavy_node.size(), static_cast<std::size_t>(m.num_nodes()));
  double worst = 0, peak = 0;
  for (int f = 0; f < 300; ++f) {
    ASSERT_EQ(step(m, st, s, &loads).code, StepCode::Ok) << "frame " << f;
    gp.frame(s);
    worst = std::max({worst, relative_difference(gp.x, st.x), relative_difference(gp.v, st.v)});
    peak = std::max(peak, (st.x - m.x0).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(peak, 0.05);
  EXPECT_LE(worst, 1e-12);
  EXPECT_EQ(gp.substeps, static_cast<long>(st.substeps));
  EXPECT_NEAR(gp.stiffening, st.stiffening, 1e-9 * st.stiffening);
  ::testing::Test::RecordProperty("grid_split_max_relative_difference_fp64",
                                  (std::ostringstream() << std::scientific << worst).str());
}

TEST(SpringTable, BalancedDealGivesEveryThreadAHeavyAndALightRowInTurn) {
  // Degrees 9, 8, ..., 1 dealt to 4 threads: rounds forward, backward, forward.
  const std::vector<int> degree{1, 2, 3, 4, 5, 6, 7, 8, 9};
  const std::vector<int> rows = table_row_order(degree, RowOrder::Balanced, 4);
  EXPECT_EQ(rows, (std::vector<int>{8, 7, 6, 5, 1, 2, 3, 4, 0}));
  // HeavyLast: only rows over kHeavyDegree and twice the median move, by decreasing degree.
  const std::vector<int> hybrid{6, 40, 6, 7, 30, 6, 5};
  EXPECT_EQ(table_row_order(hybrid, RowOrder::HeavyLast, 0), (std::vector<int>{0, 2, 3, 5, 6, 1, 4}));
  EXPECT_TRUE(table_row_order(hybrid, RowOrder::Nodes, 0).empty());
}

// Compact parameters (spring_table.hpp, docs/gpu.md): the table's (k, k', 1/k) and the nodes' (mass,
// damping, k_r) as 2-byte classes. The gather reads the same values, so the trajectory is bit for bit the
// one of the per-entry arrays, in fp64 and fp32, hard and soft springs.
template <class R>
void expect_compact_bit_identical(const Model& m, const std::vector<PointLoad>& loads, int frames) {
  StepSettings s;
  s.dt = 0.5;
  GatherStepper<R> full(m, loads), compact(m, loads, true);
  ASSERT_FALSE(compact.T.cls.empty());
  ASSERT_FALSE(compact.N.cls.empty());
  EXPECT_TRUE(compact.T.k.empty() && compact.T.kp.empty() && compact.T.ik.empty());
  EXPECT_TRUE(compact.N.mass.empty() && compact.N.damping.empty() && compact.N.kr.empty());
  double peak = 0;  // the load moved the model (mm): not a trivial match
  for (int f = 0; f < frames; ++f) {
    full.frame(s);
    compact.frame(s);
    for (std::size_t q = 0; q < full.x.size(); ++q)
      peak = std::max(peak, std::abs(static_cast<double>(full.x[q] - full.N.x0[q])));
  }
  EXPECT_GT(peak, 0.05);
  EXPECT_EQ(compact.x, full.x);
  EXPECT_EQ(compact.v, full.v);
  EXPECT_EQ(compact.stiffening, full.stiffening);
  EXPECT_EQ(compact.substeps, full.substeps);
}

TEST(SpringTable, CompactParametersGiveBitIdenticalSteps) {
  expect_compact_bit_identical<double>(small_tube(false), press(55, Vec3(0, 0, -0.8)), 200);
  expect_compact_bit_identical<double>(small_tube(true), press(55, Vec3(0.3, 0, -0.6)), 200);
  expect_compact_bit_identical<float>(small_tube(false), press(55, Vec3(0, 0, -0.8)), 200);
}

TEST(SpringTable, CompactClassesAreTheDistinctValues) {
  const Model m = small_tube(false);
  SpringTableArrays<double> T = make_spring_table<double>(m);
  const SpringTableArrays<double> full = T;
  ASSERT_TRUE(compact_spring_params(T));
  ASSERT_EQ(T.cls.size(), full.entries());
  for (std::size_t e = 0; e < T.entries(); ++e) {  // each entry's class holds its own values
    const auto c = T.cls[e];
    EXPECT_EQ(T.ck[c], full.k[e]);
    EXPECT_EQ(T.ckp[c], full.kp[e]);
    EXPECT_EQ(T.cik[c], full.ik[e]);
  }
  for (std::size_t c = 0; c < T.ck.size(); ++c)  // classes distinct
    for (std::size_t d = c + 1; d < T.ck.size(); ++d)
      EXPECT_FALSE(T.ck[c] == T.ck[d] && T.ckp[c] == T.ckp[d] && T.cik[c] == T.cik[d]);
  // A uniform tube: the padding class (0, 0, 0) and a few stiffnesses (the rule k ~ 1/L0 or constant).
  EXPECT_LE(T.ck.size(), 8u);
  EXPECT_TRUE(compact_spring_params(T));  // idempotent
  // A cap below the class count leaves the table untouched; an out-of-range cap is refused.
  SpringTableArrays<double> U = full;
  EXPECT_FALSE(compact_spring_params(U, 1));
  EXPECT_TRUE(U.cls.empty());
  EXPECT_EQ(U.k, full.k);
  EXPECT_THROW(compact_spring_params(U, 0), InvalidInput);
  EXPECT_THROW(compact_spring_params(U, 65537), InvalidInput);
  NodeArrayData<double> N = make_node_arrays<double>(m);
  const NodeArrayData<double> Nfull = N;
  ASSERT_TRUE(compact_node_params(N));
  for (std::size_t a = 0; a < N.cls.size(); ++a) {
    EXPECT_EQ(N.cmass[N.cls[a]], Nfull.mass[a]);
    EXPECT_EQ(N.cdamping[N.cls[a]], Nfull.damping[a]);
    EXPECT_EQ(N.ckr[N.cls[a]], Nfull.kr[a]);
  }
  ::testing::Test::RecordProperty("spring_classes", std::to_string(T.ck.size()));
  ::testing::Test::RecordProperty("node_classes", std::to_string(N.cmass.size()));
}

// The gather batch (gpu::Options::gather_batch, hd::gather_spring_forces<..., U>): U entries loaded before
// any force is formed, the forces added in entry order -- the same terms in the same order for U = 1, 2,
// 4, on every row of a table, hard and soft laws, with and without the stiffening measure, full and compact
// parameters, fp64 and fp32. Equal to rounding, not bit for bit: this CPU build (-march=native) may contract
// f += t e into an FMA in one variant and not in another (when it vectorises the batch). Positions
// displaced at random (a few % of a spring) so every law is active.
template <class R, bool Soft, bool Stiff>
void expect_gather_batches_equal(const Model& m, bool compact) {
  SpringTableArrays<R> T = make_spring_table<R>(m);
  if (compact) {
    ASSERT_TRUE(compact_spring_params(T, 65536));
  }
  const hd::SpringTable<R> view = T.view();
  std::vector<R> x(3 * static_cast<std::size_t>(m.num_nodes()));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  for (Index a = 0; a < m.num_nodes(); ++a)
    for (int c = 0; c < 3; ++c)
      x[static_cast<std::size_t>(3 * a + c)] = static_cast<R>(m.x0(a, c) + jitter(rng));
  const int rows = static_cast<int>(m.num_nodes());
  std::vector<R> f1(3 * static_cast<std::size_t>(rows), R(0)), f2 = f1, f4 = f1;
  R s1 = R(1), s2 = R(1), s4 = R(1);
  for (int r = 0; r < rows; ++r) {
    const int a = hd::row_node(view, r);
    hd::gather_spring_forces<Soft, Stiff, 1>(view, r, a, x.data(), s1, &f1[3 * static_cast<std::size_t>(r)]);
    hd::gather_spring_forces<Soft, Stiff, 2>(view, r, a, x.data(), s2, &f2[3 * static_cast<std::size_t>(r)]);
    hd::gather_spring_forces<Soft, Stiff, 4>(view, r, a, x.data(), s4, &f4[3 * static_cast<std::size_t>(r)]);
  }
  double scale = 0, d2 = 0, d4 = 0;
  int moved = 0;
  for (std::size_t q = 0; q < f1.size(); ++q) {
    scale = std::max(scale, std::abs(static_cast<double>(f1[q])));
    d2 = std::max(d2, std::abs(static_cast<double>(f2[q] - f1[q])));
    d4 = std::max(d4, std::abs(static_cast<double>(f4[q] - f1[q])));
    moved += f1[q] != R(0);
  }
  const double tol = (sizeof(R) == 8 ? 1e-13 : 1e-5) * scale;  // a wrong entry: ~ one spring's force
  EXPECT_LE(d2, tol) << m.name << (compact ? " compact" : "");
  EXPECT_LE(d4, tol) << m.name << (compact ? " compact" : "");
  EXPECT_EQ(s2, s1);  // a max: order-free
  EXPECT_EQ(s4, s1);
  EXPECT_GT(moved, rows);  // the springs were stretched: not a sum of zeros
}

TEST(HdKernels, GatherBatchesGiveTheSameForces) {
  const Model hard = small_tube(false), soft = small_tube(true);
  // A hub with 37 spokes and a ring of 37 (the kidney's atoms: widths not a multiple of 4), spread
  // stiffnesses.
  ModelBuilder b("hub");
  b.add_node(Vec3(0, 0, 0), 0.3, 0.15, 0.02);
  for (int i = 0; i < 37; ++i)
    b.add_node(Vec3(10 * std::cos(0.17 * i), 10 * std::sin(0.17 * i), 0.1 * i), 0.3, 0.15, 0.02, i % 9 == 0);
  for (int i = 0; i < 37; ++i) {
    b.add_spring(0, 1 + i, 0.05 + 0.001 * i, 0.002 * (i % 3), 10.0);
    b.add_spring(1 + i, 1 + (i + 1) % 37, 0.04 + 0.0005 * i, 0.0, 1.7);
  }
  const Model hub = b.build();
  for (const bool compact : {false, true}) {
    expect_gather_batches_equal<double, false, false>(hard, compact);
    expect_gather_batches_equal<double, false, true>(hard, compact);
    expect_gather_batches_equal<double, true, true>(soft, compact);
    expect_gather_batches_equal<float, true, false>(soft, compact);
    expect_gather_batches_equal<double, false, true>(hub, compact);
    expect_gather_batches_equal<float, false, false>(hub, compact);
  }
}

}  // namespace
}  // namespace medspring
