// The threaded symplectic step (docs/threads.md): agreement with one thread, bit-identical reruns,
// the automatic single thread for small models and bad thread counts.
#include <gtest/gtest.h>

#include <cstring>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/parallel.hpp"

namespace medspring {
namespace {

// 150 x 120 tube: 18 000 nodes, 53 880 springs (two threads' worth), end rings anchored, nonlinear.
const Model& big_tube() {
  static const Model m = [] {
    SurfaceBodyParams p;
    constexpr Index rings = 150, spokes = 120;
    for (Index j = 0; j < spokes; ++j) {
      p.fixed.push_back(j);
      p.fixed.push_back((rings - 1) * spokes + j);
    }
    return make_surface_model(tube(rings, spokes, 2.5, 2.5 * spokes / 6.283185307179586), p, "big tube");
  }();
  return m;
}

State run(const Model& m, int threads, int frames, StepSettings s = {}) {
  s.threads = threads;
  State st = make_state(m);
  prepare_step(m, st, s);
  st.f_ext.row(75 * 120 + 30) = Vec3(0, 0, -2.0).transpose();
  st.f_ext.row(40 * 120 + 90) = Vec3(0.5, 1.0, 0).transpose();
  for (int i = 0; i < frames; ++i) EXPECT_TRUE(step(m, st, s).ok());
  return st;
}

double max_abs(const MatX3& a) {
  return a.cwiseAbs().maxCoeff();
}

TEST(ThreadedStep, BigModelUsesTheThreadsAskedFor) {
  StepSettings s;
  s.threads = 2;
  EXPECT_EQ(effective_threads(big_tube(), s), threads_supported() ? 2 : 1);
  s.threads = 8;  // 53 880 springs: at most 2 threads of 25 000
  EXPECT_EQ(effective_threads(big_tube(), s), threads_supported() ? 2 : 1);
  s.integrator = Integrator::ImplicitEuler;
  EXPECT_EQ(effective_threads(big_tube(), s), 1);
}

TEST(ThreadedStep, SmallModelRunsOnOneThread) {
  const Model m = make_surface_model(tube(40, 30, 2.5, 3.0), {}, "tube");
  StepSettings s;
  s.threads = 2;
  EXPECT_EQ(effective_threads(m, s), 1);
  State st = make_state(m);
  prepare_step(m, st, s);
  EXPECT_EQ(st.threaded.p, nullptr);  // no pool started for it
}

TEST(ThreadedStep, AgreesWithOneThreadTo1e12) {
  const Model& m = big_tube();
  const State a = run(m, 1, 40);
  const double disp = max_abs(a.x - m.x0);
  ASSERT_GT(disp, 1e-3);  // the loads moved the tube
  for (const int threads : {2, 3}) {
    const State b = run(m, threads, 40);
    EXPECT_EQ(a.substeps, b.substeps);
    EXPECT_NEAR(a.stiffening, b.stiffening, 1e-12 * a.stiffening);
    EXPECT_LE(max_abs(b.x - a.x), 1e-12 * max_abs(a.x)) << threads << " threads";
    EXPECT_LE(max_abs(b.x - a.x), 1e-12 * disp * 1e3) << threads << " threads";
    EXPECT_LE(max_abs(b.v - a.v), 1e-12 * max_abs(a.v)) << threads << " threads";
  }
}

TEST(ThreadedStep, RerunsAreBitIdentical) {
  const Model& m = big_tube();
  for (const int threads : {1, 2}) {
    const State a = run(m, threads, 15), b = run(m, threads, 15);
    EXPECT_EQ(std::memcmp(a.x.data(), b.x.data(), sizeof(double) * static_cast<std::size_t>(a.x.size())), 0);
    EXPECT_EQ(std::memcmp(a.v.data(), b.v.data(), sizeof(double) * static_cast<std::size_t>(a.v.size())), 0);
  }
}

TEST(ThreadedStep, RollbackRestoresLikeOneThread) {
  // A force far beyond v_max: both paths roll back, halve and finally report the frame failed, with
  // the same counters and positions that agree to rounding.
  const Model& m = big_tube();
  StepSettings s;
  s.v_max = 0.05;
  s.max_rollbacks = 2;
  auto go = [&](int threads) {
    s.threads = threads;
    State st = make_state(m);
    st.f_ext.row(75 * 120 + 30) = Vec3(0, 0, -500.0).transpose();
    const StepStatus r = step(m, st, s);
    EXPECT_EQ(r.code, StepCode::Failed);
    return st;
  };
  const State a = go(1), b = go(2);
  EXPECT_EQ(a.warnings.rollbacks, b.warnings.rollbacks);
  EXPECT_EQ(a.warnings.failed, b.warnings.failed);
  EXPECT_TRUE(b.x.allFinite());
  EXPECT_LE(max_abs(b.x - a.x), 1e-12 * max_abs(a.x));
}

TEST(ThreadedStep, CopiedStateGetsItsOwnPool) {
  const Model& m = big_tube();
  StepSettings s;
  s.threads = 2;
  State a = make_state(m);
  prepare_step(m, a, s);
  const State b = a;  // a checkpoint: no shared worker threads
  EXPECT_EQ(b.threaded.p, nullptr);
}

TEST(ThreadedStep, BadThreadCountsAreRefused) {
  const Model m = make_surface_model(tube(10, 8, 2.5, 3.0), {}, "tube");
  for (const int bad : {0, -1, -100, kMaxThreads + 1, 1000000}) {
    StepSettings s;
    s.threads = bad;
    try {
      validate_step_settings(m, s);
      ADD_FAILURE() << "accepted threads = " << bad;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("step.threads: must be an integer in 1..256"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_THROW(WorkerPool(0), InvalidInput);
}

TEST(WorkerPool, RunsEveryThreadIndexOnce) {
  WorkerPool pool(3);
  std::vector<int> hits(3, 0);
  for (int rep = 0; rep < 200; ++rep) {
    auto f = [&](int t) { ++hits[static_cast<std::size_t>(t)]; };
    pool.run(f);
  }
  const int expected = threads_supported() ? 200 : 0;
  EXPECT_EQ(hits[0], 200);
  if (threads_supported()) {
    EXPECT_EQ(hits[1], expected);
    EXPECT_EQ(hits[2], expected);
  }
}

}  // namespace
}  // namespace medspring
