// The gather pass of the serial symplectic step (src/physics/spring_gather.cpp, docs/physics.md): the
// same node sums as the scatter pass (same terms, same order), so a model stepped through it equals the
// same model stepped through the scatter pass (its SpringGather cleared) to rounding, through rollbacks
// and failures too. Not bit for bit: the compiler contracts multiply-adds into FMAs differently in the
// vectorised and the scalar loop (measured: 1e-16 relative after a few frames).
#include <gtest/gtest.h>

#include <cmath>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/integrators.hpp"

namespace medspring {
namespace {

// A copy of m that the step runs through the scatter pass.
Model without_gather(const Model& m) {
  Model s = m;
  s.gather = SpringGather{};
  return s;
}

// Every node of a ring-ordered tube has degree 6 but the ends: a second, irregular graph with nodes of
// many degrees (a fan of 40 springs on node 0) checks the overflow rows.
Model fan_model(bool nonlinear) {
  ModelBuilder b("fan");
  const NodeParams p{0.3, 0.5, 0.02};
  for (Index i = 0; i < 60; ++i)
    b.add_node(Vec3(std::cos(0.3 * i) * (5 + 0.1 * i), std::sin(0.3 * i) * (5 + 0.1 * i), 0.05 * i * i), p);
  const DuffingSettings d = nonlinear ? DuffingSettings{} : DuffingSettings{.mode = DuffingMode::Linear};
  for (Index i = 1; i < 41; ++i) b.add_spring(0, i, 0.05, d);
  for (Index i = 1; i + 1 < 60; ++i) b.add_spring(i, i + 1, 0.1, d);
  for (Index i = 1; i + 7 < 60; i += 3) b.add_spring(i + 7, i, 0.03, d);  // ends j < i as well
  b.set_fixed(59);
  return b.build();
}

void expect_identical_runs(const Model& m, std::vector<PointLoad> loads, StepSettings s, int frames) {
  ASSERT_FALSE(m.gather.empty());
  const Model ms = without_gather(m);
  State a = make_state(m, s), b = make_state(ms, s);
  for (int f = 0; f < frames; ++f) {
    const StepStatus sa = step(m, a, s, &loads), sb = step(ms, b, s, &loads);
    ASSERT_EQ(sa.code, sb.code) << "frame " << f;
    ASSERT_EQ(sa.substeps, sb.substeps) << "frame " << f;
  }
  const double scale = 1.0 + m.x0.cwiseAbs().maxCoeff();
  EXPECT_LE((a.x - b.x).cwiseAbs().maxCoeff(), 1e-12 * scale);
  EXPECT_LE((a.v - b.v).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + b.v.cwiseAbs().maxCoeff()));
  if (a.warnings.rollbacks == 0) {  // after a failed substep f is scratch (the gather pass stops at the node)
    EXPECT_LE((a.f - b.f).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + b.f.cwiseAbs().maxCoeff()));
  }
  EXPECT_NEAR(a.stiffening, b.stiffening, 1e-12 * b.stiffening);
  EXPECT_EQ(a.substeps, b.substeps);
  EXPECT_EQ(a.warnings.rollbacks, b.warnings.rollbacks);
  EXPECT_EQ(a.warnings.failed, b.warnings.failed);
}

TEST(GatherPass, TubeEqualsTheScatterPass) {
  SurfaceBodyParams p;
  for (Index j = 0; j < 30; ++j) p.fixed.push_back(j);
  const Model m = make_surface_model(tube(40, 30, 2.5, 3.0), p, "tube");
  EXPECT_EQ(m.gather.width, 6);
  PointLoad L;
  L.node = 20 * 30 + 4;
  L.force = Vec3(0, -0.5, 0.2);
  L.t_ramp = 5;
  L.t_release = 60;
  expect_identical_runs(m, {L}, StepSettings{}, 200);
}

TEST(GatherPass, IrregularDegreesUseTheOverflowRows) {
  for (const bool nonlinear : {false, true}) {
    const Model m = fan_model(nonlinear);
    ASSERT_FALSE(m.gather.empty());
    EXPECT_FALSE(m.gather.extra.empty());  // node 0 has 41 springs
    // every spring end listed once, in increasing spring index per node
    std::vector<int> seen(static_cast<std::size_t>(2 * m.num_springs()), 0);
    for (Index a = 0; a < m.num_nodes(); ++a) {
      Index last = -1;
      auto visit = [&](Index offset) {
        const Index slot = offset / static_cast<Index>(4 * sizeof(double));  // rows hold byte offsets
        EXPECT_EQ(offset, slot * static_cast<Index>(4 * sizeof(double)));
        if (slot == 2 * m.num_springs()) return;  // padding
        ++seen[static_cast<std::size_t>(slot)];
        const Index s = slot < m.num_springs() ? slot : slot - m.num_springs();
        EXPECT_EQ(slot < m.num_springs() ? m.springs.i[s] : m.springs.j[s], a);
        EXPECT_GT(s, last);
        last = s;
      };
      for (int k = 0; k < m.gather.width; ++k)
        visit(m.gather.row[static_cast<std::size_t>(a * m.gather.width + k)]);
      for (Index e = m.gather.extra_begin[a]; e < m.gather.extra_begin[a + 1]; ++e) visit(m.gather.extra[e]);
    }
    for (const int c : seen) EXPECT_EQ(c, 1);
    PointLoad L;
    L.node = 20;
    L.force = Vec3(0.3, -0.4, 0.5);
    expect_identical_runs(m, {L}, StepSettings{}, 300);
  }
}

TEST(GatherPass, RollbacksAndFailedFramesMatchTheScatterPass) {
  const Model m = fan_model(true);
  PointLoad L;
  L.node = 0;
  L.force = Vec3(0, 0, 1e4);  // far beyond v_max: every frame rolls back, then fails
  StepSettings s;
  s.dt = 0.5;
  expect_identical_runs(m, {L}, s, 5);
  StepSettings nog = s;
  nog.guard = false;  // unguarded: the same non-finite or huge states
  const Model ms = without_gather(m);
  State a = make_state(m, nog), b = make_state(ms, nog);
  const std::vector<PointLoad> loads{L};
  for (int f = 0; f < 3; ++f) {
    step(m, a, nog, &loads);
    step(ms, b, nog, &loads);
  }
  EXPECT_EQ(a.x.allFinite(), b.x.allFinite());
  if (a.x.allFinite()) {
    EXPECT_LE((a.x - b.x).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + b.x.cwiseAbs().maxCoeff()));
  }
}

TEST(GatherPass, NotBuiltWhereItDoesNotApply) {
  SurfaceBodyParams soft;
  soft.duffing.soft = true;
  EXPECT_TRUE(make_surface_model(tube(10, 8, 2.5, 3.0), soft, "soft").gather.empty());
  ModelBuilder b("chain");
  for (Index i = 0; i < 5; ++i) b.add_node(Vec3(2.0 * i, 0, 0), NodeParams{});
  for (Index i = 0; i + 1 < 5; ++i) b.add_spring(i, i + 1, 0.1, DuffingSettings{});
  b.add_bending(0, 1, 2, 0.01);
  EXPECT_TRUE(b.build().gather.empty());
}

}  // namespace
}  // namespace medspring
