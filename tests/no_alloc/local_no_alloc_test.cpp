// The per-update patch solve must not touch the heap (DESIGN.md: no allocation inside the update
// loop), counted by the shared counter of tests/support/alloc_counter.hpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "alloc_counter.hpp"
#include "local_fixtures.hpp"
#include "medspring/local/deformer.hpp"
#include "medspring/local/distributed_overlay.hpp"
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

// The distributed load's patch (local/distributed_overlay.hpp): after reserve() for the largest patch, a
// loaded set that changes on every call (select + factor + solve) and one that stays (solve only) allocate
// nothing.
TEST(LocalNoAllocation, DistributedOverlayDoesNotAllocateWithinItsCapacity) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  const SurfaceMesh kid = kidney_phantom();
  DistributedOverlay d(testing::mesh_adjacency(kid), 0.05);
  std::vector<std::vector<Index>> sets;
  for (Index c : {40, 223, 301})
    for (double r : {3.0, 9.0}) {
      sets.emplace_back();
      for (Index i = 0; i < kid.num_vertices(); ++i)
        if ((kid.V.row(i) - kid.V.row(c)).norm() < r) sets.back().push_back(i);
    }
  Index largest = 0;
  for (const auto& s : sets) largest = std::max(largest, d.patch_size_of(s));
  d.reserve(largest);
  MatX3 F = MatX3::Constant(kid.num_vertices(), 3, -0.01), surface = kid.V;
  const long before = testing::heap_allocations();
  for (int t = 0; t < 60; ++t) {
    const auto& s = sets[static_cast<std::size_t>(t / 2) % sets.size()];  // each set twice: factor, reuse
    ASSERT_TRUE(d.prepare(s));
    d.solve(F);
    for (Index a = 0; a < d.size(); ++a) surface.row(d.nodes()[a]) += d.displacement().row(a);
  }
  EXPECT_EQ(testing::heap_allocations() - before, 0);
  EXPECT_EQ(d.growths(), 0);
  EXPECT_GT(d.displacement().cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace medspring
