// The fused node-range step of large models (src/physics/threaded_step.cpp, docs/threads.md): one
// sweep per thread initialises, scatters and advances every node. Checked against the two-pass
// reference step (the scatter pass of forces.cpp, then the node pass), which a model with a bending term
// takes: a copy of the model with one bending term of stiffness 0 (its force is exactly 0) runs that
// path with the same arithmetic otherwise.
#include <gtest/gtest.h>

#include <cstring>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/parallel.hpp"

namespace medspring {
namespace {

// 150 x 120 tube: 18 000 nodes, 53 880 springs (beyond the gather pass; two threads' worth), end rings
// anchored, nonlinear.
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

// A copy of m that step() runs through the two-pass reference path: one bending term with k_b = 0.
Model reference_of(const Model& m) {
  Model r = m;
  r.bending.a = {0};
  r.bending.b = {1};
  r.bending.c = {2};
  r.bending.kb = VecX::Zero(1);
  r.bending.D0 = MatX3::Zero(1, 3);
  return r;
}

struct Outcome {
  State st;
  std::vector<StepStatus> status;
};

Outcome run(const Model& m, int threads, int frames, StepSettings s = {}, double load = -2.0) {
  s.threads = threads;
  Outcome r{make_state(m, s), {}};
  r.st.f_ext.row(75 * 120 + 30) = Vec3(0, 0, load).transpose();
  r.st.f_ext.row(40 * 120 + 90) = Vec3(0.5, 1.0, 0).transpose();
  for (int i = 0; i < frames; ++i) r.status.push_back(step(m, r.st, s));
  return r;
}

double max_abs(const MatX3& a) {
  return a.cwiseAbs().maxCoeff();
}

void expect_agree(const Outcome& a, const Outcome& ref, const char* what) {
  ASSERT_EQ(a.status.size(), ref.status.size());
  for (std::size_t f = 0; f < a.status.size(); ++f) {
    EXPECT_EQ(a.status[f].code, ref.status[f].code) << what << " frame " << f;
    EXPECT_EQ(a.status[f].substeps, ref.status[f].substeps) << what << " frame " << f;
  }
  EXPECT_EQ(a.st.substeps, ref.st.substeps) << what;
  EXPECT_EQ(a.st.warnings.rollbacks, ref.st.warnings.rollbacks) << what;
  EXPECT_EQ(a.st.warnings.failed, ref.st.warnings.failed) << what;
  EXPECT_NEAR(a.st.stiffening, ref.st.stiffening, 1e-12 * ref.st.stiffening) << what;
  EXPECT_LE(max_abs(a.st.x - ref.st.x), 1e-12 * max_abs(ref.st.x)) << what;
  EXPECT_LE(max_abs(a.st.v - ref.st.v), 1e-12 * (1.0 + max_abs(ref.st.v))) << what;
}

TEST(FusedStep, BigTubeTakesItOnOneAndTwoThreads) {
  const Model& m = big_tube();
  EXPECT_TRUE(m.gather.empty());  // beyond the gather pass
  const Model ref = reference_of(m);
  for (const int threads : {1, 2}) {
    StepSettings s;
    s.threads = threads;
    State a = make_state(m, s), b = make_state(ref, s);
    EXPECT_NE(a.threaded.p, nullptr) << threads;  // the fused step's partition
    EXPECT_EQ(b.threaded.p, nullptr) << threads;  // the reference path has none
  }
}

TEST(FusedStep, AgreesWithTheTwoPassStepTo1e12) {
  const Model& m = big_tube();
  const Outcome ref = run(reference_of(m), 1, 40);
  ASSERT_GT(max_abs(ref.st.x - m.x0), 1e-3);  // the loads moved the tube
  for (const int threads : {1, 2, 3}) expect_agree(run(m, threads, 40), ref, "tube");
}

TEST(FusedStep, ForcesAfterTheStepAreTheReferenceForces) {
  const Model& m = big_tube();
  const Outcome a = run(m, 2, 5), ref = run(reference_of(m), 1, 5);
  EXPECT_LE(max_abs(a.st.f - ref.st.f), 1e-12 * (1.0 + max_abs(ref.st.f)));
}

TEST(FusedStep, RerunsAreBitIdentical) {
  const Model& m = big_tube();
  for (const int threads : {1, 2, 3}) {
    const Outcome a = run(m, threads, 12), b = run(m, threads, 12);
    const auto bytes = sizeof(double) * static_cast<std::size_t>(a.st.x.size());
    EXPECT_EQ(std::memcmp(a.st.x.data(), b.st.x.data(), bytes), 0) << threads;
    EXPECT_EQ(std::memcmp(a.st.v.data(), b.st.v.data(), bytes), 0) << threads;
  }
}

TEST(FusedStep, RollbacksAndFailuresMatchTheTwoPassStep) {
  // v_max low enough that the first substeps fail and roll back (and the frame finally fails): the nodes
  // advanced before the failing one, on every thread, are restored as in the reference
  const Model& m = big_tube();
  StepSettings s;
  s.v_max = 0.05;
  s.max_rollbacks = 2;
  const Outcome ref = run(reference_of(m), 1, 3, s, -500.0);
  ASSERT_GT(ref.st.warnings.rollbacks, 0u);
  for (const int threads : {1, 2, 3}) {
    const Outcome a = run(m, threads, 3, s, -500.0);
    expect_agree(a, ref, "rollbacks");
    EXPECT_TRUE(a.st.x.allFinite());
  }
  s.v_max = 2.0;  // a milder limit: rollbacks that recover
  const Outcome ref2 = run(reference_of(m), 1, 6, s, -60.0);
  for (const int threads : {1, 2}) expect_agree(run(m, threads, 6, s, -60.0), ref2, "recovering");
}

TEST(FusedStep, ShuffledSpringOrderAndSoftSprings) {
  // springs in an order unrelated to the nodes (many short chunks, nodes ready late) and soft springs
  // (the scalar spring law of the fused sweep)
  const Model& base = big_tube();
  for (const bool soft : {false, true}) {
    ModelBuilder b("shuffled");
    for (Index a = 0; a < base.num_nodes(); ++a)
      b.add_node(base.x0.row(a).transpose(), base.mass[a], base.damping[a], base.kr[a],
                 base.fixed[static_cast<std::size_t>(a)] != 0);
    const Index ns = base.num_springs();
    for (Index k = 0; k < ns; ++k) {
      const Index s =
          static_cast<Index>((static_cast<long long>(k) * 7919) % ns);  // 7919 prime, ns not a multiple
      const double kp = soft && s % 5 == 0 ? -base.springs.kp[s] : base.springs.kp[s];
      b.add_spring(base.springs.i[s], base.springs.j[s], base.springs.k[s], kp, base.springs.L0[s]);
    }
    const Model m = b.build();
    ASSERT_EQ(m.has_soft_springs, soft);
    const Outcome ref = run(reference_of(m), 1, 15);
    for (const int threads : {1, 2}) expect_agree(run(m, threads, 15), ref, soft ? "soft" : "shuffled");
  }
}

}  // namespace
}  // namespace medspring
