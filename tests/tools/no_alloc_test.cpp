// Collision and contact response must not touch the heap after warm-up (DESIGN.md: no allocation in
// the update loop). Counting wrappers around glibc's malloc family, as in tests/local/no_alloc_test.cpp.
// Not built under AddressSanitizer, which owns malloc itself.
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

#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/sim/tool_sim.hpp"

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

TEST(ToolNoAllocation, PressSlideAndGraspUpdatesDoNotAllocate) {
  auto body = std::make_shared<HybridKidney>(hybrid_kidney_phantom());
  Simulation sim(body);
  ToolSimulation tools(sim, {.friction = 0.3});
  Index top = 0;
  body->rest_surface().col(2).maxCoeff(&top);
  const Vec3 x_top = body->rest_surface().row(top).transpose();
  Pose probe;
  probe.position = x_top + Vec3(0, 0, 4.0);
  const Index k = tools.add_tool(Tool::sphere(5.0), probe);
  Pose jaws;
  jaws.position = x_top + Vec3(20, 0, 40);
  const Index g = tools.add_tool(Tool::grasper(1.0, 10.0, 0.8), jaws);
  for (int i = 0; i < 5; ++i) tools.update();  // warm-up: velocity history
  const long before = g_heap_calls.load();
  for (int i = 0; i < 200; ++i) {
    probe.position += Vec3(0.02, 0.01, -0.01);
    tools.set_pose(k, probe);
    tools.set_opening(g, i < 100 ? 0.8 : 0.05);
    tools.update();
  }
  EXPECT_EQ(g_heap_calls.load() - before, 0);
  EXPECT_GT(tools.contact().state(k).contacts, 0);
}

}  // namespace
}  // namespace medspring

#endif  // MEDSPRING_COUNT_MALLOC
