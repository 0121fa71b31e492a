// The per-update patch solve must not touch the heap (DESIGN.md: no allocation inside the update
// loop), counted by the shared counter of tests/support/alloc_counter.hpp.
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "local_fixtures.hpp"
#include "medspring/local/deformer.hpp"
#include "medspring/local/overlay.hpp"
#include "medspring/local/solver.hpp"

namespace medspring {
namespace {

TEST(LocalNoAllocation, CountingWrapperSeesEigenAllocations) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  const long before = testing::heap_allocations();
  VecX v(1000);
  v.setZero();
  EXPECT_GT(testing::heap_allocations(), before);
}

TEST(LocalNoAllocation, PerUpdateSolveDoesNotAllocate) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  const SurfaceMesh tb = tube(40, 30), kid = kidney_phantom();
  const Adjacency kadj = testing::mesh_adjacency(kid);
  struct Case {
    LocalPatch patch;
    const MatX3* X;
    LocalSettings settings;
  };
  const std::vector<Case> cases = {
      {structured_window_patch(40, 30, GridNode{20, 7}), &tb.V, {}},
      {bfs_local_patch(kadj, kid.V, 223, {.count = 150}), &kid.V, {}},  // sparse Cholesky path
      {structured_window_patch(40, 30, GridNode{20, 7}), &tb.V, {.stiffness = LocalStiffness::Linearized}},
      {structured_window_patch(40, 30, GridNode{20, 7}), &tb.V, {.stiffness = LocalStiffness::AxisProjected}},
      {structured_window_patch(40, 30, GridNode{20, 7}), &tb.V, {.stiffness = LocalStiffness::PaperLiteral}},
      {structured_window_patch(40, 30, GridNode{20, 7}), &tb.V, {.boundary = BoundaryMethod::RowReplacement}},
      {structured_window_patch(40, 30, GridNode{20, 7}),
       &tb.V,
       {.stiffness = LocalStiffness::Linearized, .boundary = BoundaryMethod::RowReplacement}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(::testing::Message() << to_string(c.settings.stiffness) << " "
                                      << to_string(c.settings.boundary) << " P = " << c.patch.size());
    LocalSolver solver;
    solver.precompute(c.patch, *c.X, c.settings);
    MatX3 U(c.patch.size(), 3);
    MatX3 surface = c.X->rows() == tb.V.rows() ? tb.V : kid.V;
    const long before = testing::heap_allocations();
    for (int t = 0; t < 10; ++t) {
      solver.solve(Vec3(0.01 * t, -0.02, 0.05), U);
      apply_local_overlay(c.patch, U, surface);
    }
    EXPECT_EQ(testing::heap_allocations() - before, 0);
    EXPECT_GT(U.cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(LocalNoAllocation, CachedDeformerUpdateDoesNotAllocate) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  LocalDeformer d = LocalDeformer::tube(40, 30);
  MatX3 U;
  d.compute(607, Vec3(0, 0, -0.05), U);  // selects, factors and sizes U
  const long before = testing::heap_allocations();
  for (int t = 0; t < 10; ++t) d.compute(607, Vec3(0, 0, -0.01 * t), U);
  EXPECT_EQ(testing::heap_allocations() - before, 0);
}

}  // namespace
}  // namespace medspring
