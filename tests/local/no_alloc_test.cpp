// The per-update patch solve must not touch the heap (DESIGN.md: no allocation inside the update
// loop). Every heap allocation of this process goes through malloc / calloc / realloc (operator new
// and Eigen both use them), so this test interposes them with counting wrappers around glibc's
// implementation. Not built under AddressSanitizer, which owns malloc itself.
#include <cstdlib>  // defines __GLIBC__

#if defined(__SANITIZE_ADDRESS__)
#define MEDSPRING_COUNT_MALLOC 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MEDSPRING_COUNT_MALLOC 0
#endif
#endif
#ifndef MEDSPRING_COUNT_MALLOC
#if defined(__GLIBC__)
#define MEDSPRING_COUNT_MALLOC 1
#else
#define MEDSPRING_COUNT_MALLOC 0
#endif
#endif

#if MEDSPRING_COUNT_MALLOC

#include <gtest/gtest.h>

#include <atomic>

#include "local_fixtures.hpp"
#include "medspring/local/deformer.hpp"
#include "medspring/local/overlay.hpp"
#include "medspring/local/solver.hpp"

namespace {
std::atomic<long> g_heap_calls{0};
}  // namespace

extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t n, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);

void* malloc(std::size_t size) noexcept {
  g_heap_calls.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) noexcept {
  g_heap_calls.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) noexcept {
  g_heap_calls.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, size);
}
}

namespace medspring {
namespace {

TEST(LocalNoAllocation, CountingWrapperSeesEigenAllocations) {
  const long before = g_heap_calls.load();
  VecX v(1000);
  v.setZero();
  EXPECT_GT(g_heap_calls.load(), before);
}

TEST(LocalNoAllocation, PerUpdateSolveDoesNotAllocate) {
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
    const long before = g_heap_calls.load();
    for (int t = 0; t < 10; ++t) {
      solver.solve(Vec3(0.01 * t, -0.02, 0.05), U);
      apply_local_overlay(c.patch, U, surface);
    }
    EXPECT_EQ(g_heap_calls.load() - before, 0);
    EXPECT_GT(U.cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(LocalNoAllocation, CachedDeformerUpdateDoesNotAllocate) {
  LocalDeformer d = LocalDeformer::tube(40, 30);
  MatX3 U;
  d.compute(607, Vec3(0, 0, -0.05), U);  // selects, factors and sizes U
  const long before = g_heap_calls.load();
  for (int t = 0; t < 10; ++t) d.compute(607, Vec3(0, 0, -0.01 * t), U);
  EXPECT_EQ(g_heap_calls.load() - before, 0);
}

}  // namespace
}  // namespace medspring

#endif  // MEDSPRING_COUNT_MALLOC
