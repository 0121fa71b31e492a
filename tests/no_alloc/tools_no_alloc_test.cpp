// Collision and contact response must not touch the heap after warm-up (DESIGN.md: no allocation in
// the update loop). Counting wrappers around glibc's malloc family, as in tests/local/no_alloc_test.cpp.
// Not built under AddressSanitizer, which owns malloc itself.
#include <gtest/gtest.h>

#include <algorithm>

#include "alloc_counter.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/sim/tool_sim.hpp"

namespace medspring {
namespace {

TEST(ToolNoAllocation, PressSlideAndGraspUpdatesDoNotAllocate) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
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
  const long before = testing::heap_allocations();
  for (int i = 0; i < 200; ++i) {
    probe.position += Vec3(0.02, 0.01, -0.01);
    tools.set_pose(k, probe);
    tools.set_opening(g, i < 100 ? 0.8 : 0.05);
    tools.update();
  }
  EXPECT_EQ(testing::heap_allocations() - before, 0);
  EXPECT_GT(tools.contact().state(k).contacts, 0);
}

TEST(ToolNoAllocation, ContactAtTheSubstepRateDoesNotAllocate) {
  // a 4 ms frame sub-steps the phantom: the contact's normal force is re-evaluated at every substep
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  auto body = std::make_shared<HybridKidney>(hybrid_kidney_phantom());
  SimulationSettings ss;
  ss.step.dt = 4.0;
  Simulation sim(body, ss);
  ToolSimulation tools(sim, {.friction = 0.3, .substep = true});
  Index top = 0;
  body->rest_surface().col(2).maxCoeff(&top);
  Pose probe;
  probe.position = body->rest_surface().row(top).transpose() + Vec3(0, 0, 4.0);
  const Index k = tools.add_tool(Tool::sphere(5.0), probe);
  for (int i = 0; i < 5; ++i) tools.update();
  const long before = testing::heap_allocations();
  int substeps = 0;
  for (int i = 0; i < 100; ++i) {
    probe.position += Vec3(0.02, 0.01, -0.01);
    tools.set_pose(k, probe);
    substeps = std::max(substeps, tools.update().substeps);
  }
  EXPECT_EQ(testing::heap_allocations() - before, 0);
  EXPECT_GT(substeps, 1);
  EXPECT_GT(tools.contact().state(k).contacts, 0);
  EXPECT_TRUE(tools.contact().state(k).force.allFinite());
}

}  // namespace
}  // namespace medspring
