#include "medspring/sim/simulation.hpp"

#include <gtest/gtest.h>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/sim/tool_sim.hpp"

namespace medspring {
namespace {

TEST(Simulation, PressAndReleaseWithLocalOverlay) {
  SimulationSettings st;
  st.local.enabled = true;
  Simulation sim(std::make_shared<HybridKidney>(hybrid_kidney_phantom()), st);
  const Vec3 F(0, 0, -1.0);
  sim.set_loads({{.node = 223, .force = F, .t_ramp = 20, .t_release = 100}});
  sim.advance(199);  // t = 99.5 ms: the force still acts
  EXPECT_NEAR(sim.time(), 99.5, 1e-9);
  EXPECT_EQ(sim.local_nodes().size(), 25u);
  // the overlay adds U (parallel to F, Isotropic) to the global surface on the patch only
  const MatX3 diff = sim.surface() - sim.global_surface();
  EXPECT_GT(diff.row(223).norm(), 0.0);
  EXPECT_NEAR(diff.row(223).normalized().dot(F.normalized()), 1.0, 1e-12);
  EXPECT_EQ(diff.row(0).norm(), 0.0);
  EXPECT_GT((sim.global_surface().row(223) - sim.body().rest_surface().row(223)).norm(), 1.0);
  EXPECT_NEAR((sim.applied_force() - F).norm(), 0.0, 1e-12);
  sim.update();  // released: U = 0 at once (§6.5)
  EXPECT_TRUE(sim.local_nodes().empty());
  EXPECT_EQ((sim.surface() - sim.global_surface()).norm(), 0.0);
  sim.advance(400);
  EXPECT_LT(sim.displacement().rowwise().norm().maxCoeff(), 1e-3);
  EXPECT_EQ(sim.normals().rows(), 458);
  sim.reset();
  EXPECT_EQ(sim.time(), 0.0);
  EXPECT_EQ(sim.displacement().norm(), 0.0);
}

TEST(Simulation, RejectsBadLoadsAndSettings) {
  Simulation sim(std::make_shared<SurfaceBody>(tube(10, 12), SurfaceBodyParams{}));
  EXPECT_THROW(sim.set_loads({{.node = 120}}), InvalidInput);
  SimulationSettings st;
  st.step.dt = -1;
  EXPECT_THROW(sim.set_settings(st), InvalidInput);
  EXPECT_THROW(Simulation(nullptr), InvalidInput);
}

TEST(Simulation, SurfaceBodyIsTheIdentityMap) {
  Simulation sim(std::make_shared<SurfaceBody>(kidney_phantom(), SurfaceBodyParams{}));
  sim.set_loads({{.node = 10, .force = Vec3(1, 0, 0)}});
  sim.advance(10);
  EXPECT_EQ(sim.surface(), sim.state().x);
}

// The quasi-static linear response (docs/linear-response.md) on the hybrid kidney: a held tool force gives
// x0 + K0^-1 f at once (the same at every frame), and a ToolSimulation refuses the integrator (its penalty
// contact needs inertia), naming it.
TEST(Simulation, LinearStaticHoldsTheResponseAndRefusesTools) {
  SimulationSettings st;
  st.step.integrator = Integrator::LinearStatic;
  Simulation sim(std::make_shared<HybridKidney>(hybrid_kidney_phantom()), st);
  sim.set_tool_force(223, Vec3(0, 0, -0.5));
  sim.update();
  const MatX3 first = sim.state().x;
  sim.advance(5);
  EXPECT_EQ(sim.state().x, first);
  EXPECT_GT((first - sim.model().x0).rowwise().norm().maxCoeff(), 0.1);
  EXPECT_EQ(sim.state().substeps, 6u);
  try {
    ToolSimulation tools(sim);
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("linear_static"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace medspring
