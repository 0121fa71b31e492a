// Tools acting on a simulated body (the hybrid kidney phantom): the contact forces enter the update,
// the surface stays outside the probe, the reaction points back at the user, tool paths, the haptic
// loop with a tool, and bad input.
#include "medspring/sim/tool_sim.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "medspring/core/error.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"

namespace medspring {
namespace {

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "(no InvalidInput)";
}

struct Phantom {
  std::shared_ptr<HybridKidney> body = std::make_shared<HybridKidney>(hybrid_kidney_phantom());
  Index top = 0;
  Vec3 x_top;
  Phantom() {
    body->rest_surface().col(2).maxCoeff(&top);
    x_top = body->rest_surface().row(top).transpose();
  }
};

TEST(ToolSimulation, ProbePressKeepsTheSurfaceOutsideAndPushesBack) {
  Phantom ph;
  Simulation sim(ph.body);
  ToolSimulation tools(sim);
  const double R = 5.0;
  Pose pose;
  pose.position = ph.x_top + Vec3(0, 0, R + 1.0);
  const Index k = tools.add_tool(Tool::sphere(R), pose);
  // press 3 mm below the rest surface over 100 ms, then hold
  tools.set_path(k, {{0.0, pose}, {100.0, Pose{ph.x_top + Vec3(0, 0, R - 3.0), Quat::Identity()}}});
  while (sim.time() < 600) ASSERT_TRUE(tools.update().ok());
  const ToolState& st = tools.contact().state(k);
  EXPECT_GT(st.contacts, 0);
  EXPECT_GT(st.force.z(), 0.0);  // reaction on the tool points back up
  EXPECT_LT(st.force.normalized().z(), -0.0 + 1.0 + 1e-12);
  EXPECT_GT(st.force.normalized().z(), 0.9);
  EXPECT_LE(st.penetration, 0.05 * R);  // steady press: <= 5 % of the radius
  // every displayed node stays outside the sphere (up to the allowed penetration)
  const Vec3 c = st.pose.position;
  for (Index i = 0; i < sim.surface().rows(); ++i)
    EXPECT_GE((sim.global_surface().row(i).transpose() - c).norm(), R - 0.05 * R) << "node " << i;
  // the body felt the press: the top node moved down by most of the 3 mm indentation
  EXPECT_LT(sim.global_surface()(ph.top, 2) - ph.x_top.z(), -2.0);
  // action = reaction: the external force on the model is minus the force on the tool
  EXPECT_LT((sim.applied_force() + st.force).norm(), 1e-12 * st.force.norm());
  EXPECT_EQ(sim.state().warnings.total(), 0u);
}

TEST(ToolSimulation, LocalPatchFollowsTheContact) {
  Phantom ph;
  SimulationSettings s;
  s.local.enabled = true;
  Simulation sim(ph.body, s);
  ToolSimulation tools(sim);
  Pose pose;
  pose.position = ph.x_top + Vec3(0, 0, 3.0);
  tools.add_tool(Tool::sphere(5.0), pose);
  for (int i = 0; i < 20; ++i) tools.update();
  ASSERT_FALSE(sim.local_nodes().empty());
  EXPECT_EQ(tools.contact().forces().centre >= 0, true);
  EXPECT_NE(std::find(sim.local_nodes().begin(), sim.local_nodes().end(), tools.contact().forces().centre),
            sim.local_nodes().end());
  EXPECT_TRUE(sim.surface().allFinite());
}

TEST(ToolSimulation, ToolStartingInsideTheOrganIsRefused) {
  Phantom ph;
  Simulation sim(ph.body);
  ToolSimulation tools(sim);
  const Vec3 centre = ph.body->rest_surface().colwise().mean().transpose();
  const std::string m = message_of([&] {
    tools.add_tool(Tool::sphere(2.0), Pose{centre, Quat::Identity()});
  });
  EXPECT_NE(m.find("tools[0] starts inside the organ"), std::string::npos) << m;
  EXPECT_EQ(tools.contact().num_tools(), 0);
  EXPECT_THROW(tools.add_tool(Tool::sphere(0.0), Pose{ph.x_top + Vec3(0, 0, 9), Quat::Identity()}),
               InvalidInput);
}

TEST(ToolPath, ReadsPositionsQuaternionsAndOpenings) {
  std::istringstream in(
      "time_ms,x,y,z,qw,qx,qy,qz,opening_deg\n# comment\n0,1,2,3,1,0,0,0,30\n\n10,1,2,1,0,0,0,2,0\n");
  const ToolPath p = read_tool_path(in, "p.csv");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_NEAR(p[0].opening, std::numbers::pi / 6, 1e-15);
  EXPECT_NEAR(p[1].pose.rotation.z(), 1.0, 1e-15);  // normalised
  const ToolKeyframe mid = tool_path_at(p, 5.0);
  EXPECT_NEAR(mid.pose.position.z(), 2.0, 1e-12);
  EXPECT_NEAR(mid.opening, std::numbers::pi / 12, 1e-12);
  EXPECT_NEAR(mid.pose.rotation.angularDistance(Quat(Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitZ()))),
              0, 1e-12);
}

TEST(ToolPath, BadRowsAreNamedByLine) {
  auto msg = [](const std::string& text) {
    return message_of([&] {
      std::istringstream in(text);
      read_tool_path(in, "p.csv");
    });
  };
  EXPECT_NE(msg("0,1,2,3\n1,1,2\n").find("p.csv:2: expected 4, 8 or 9 fields"), std::string::npos);
  EXPECT_NE(msg("0,1,2,3\n1,1,nan,3\n").find("p.csv:2: field 3 'nan' is not a finite number"),
            std::string::npos);
  EXPECT_NE(msg("t,x,y,z\n5,1,2,3\n4,1,2,3\n").find("p.csv:3: time 4 ms is not after"), std::string::npos);
  EXPECT_NE(msg("0,1,2,3,0,0,0,0\n").find("p.csv:1: the quaternion is zero"), std::string::npos);
  EXPECT_NE(msg("0,1,2,3,1,0,0,0,200\n").find("p.csv:1: opening 200 degrees"), std::string::npos);
  EXPECT_NE(msg("# nothing\n").find("p.csv: no rows"), std::string::npos);
  EXPECT_THROW(read_tool_path_file("/nonexistent/path.csv"), IoError);
  Phantom ph;
  Simulation sim(ph.body);
  ToolSimulation tools(sim);
  const Index k = tools.add_tool(Tool::sphere(1.0), Pose{ph.x_top + Vec3(0, 0, 5), Quat::Identity()});
  ToolPath bad = {{0, Pose{ph.x_top, Quat::Identity()}},
                  {1, Pose{Vec3(0, std::nan(""), 0), Quat::Identity()}}};
  EXPECT_NE(message_of([&] { tools.set_path(k, bad); }).find("tools[0].path[1].pose"), std::string::npos);
}

TEST(ToolHaptics, ReactionPointsBackAtTheUser) {
  Phantom ph;
  SimulationSettings s;
  s.normals = false;
  Simulation sim(ph.body, s);
  ToolSimulation tools(sim);
  const Index k = tools.add_tool(Tool::sphere(4.0), Pose{ph.x_top + Vec3(0, 0, 6), Quat::Identity()});
  ToolHapticLoop loop(tools, k, {.f_max = 3.0});
  const Trajectory path = {{0.0, ph.x_top + Vec3(0, 0, 6)}, {200.0, ph.x_top + Vec3(0, 0, 1.5)}};
  const TickStats st = run_tool_trajectory(loop, path, 300.0);
  EXPECT_EQ(st.ticks, 300);
  const Vec3 device = -loop.last().force;
  EXPECT_GT(device.z(), 0);  // pushes the hand back up, out of the tissue
  EXPECT_LE(device.norm(), 3.0 + 1e-12);
  EXPECT_EQ(sim.state().warnings.total(), 0u);
  EXPECT_THROW(ToolHapticLoop(tools, 3), InvalidInput);
}

}  // namespace
}  // namespace medspring

namespace medspring {
namespace {

// SMRM: the contact forces reach the atoms through the model's own map (D-14), as point loads do.
TEST(ToolSimulation, ProbeOnTheSmrmVesselPushesItsAtoms) {
  auto body = std::make_shared<SmrmVessel>(smrm_phantom(VesselPath::Arc, CrossSectionShape::Circular));
  Simulation sim(body);
  ToolSimulation tools(sim);
  Index top = 0;
  body->rest_surface().col(2).maxCoeff(&top);
  const Vec3 x = body->rest_surface().row(top).transpose();
  const double R = 3.0;
  const Index k = tools.add_tool(Tool::sphere(R), Pose{x + Vec3(0, 0, R + 0.5), Quat::Identity()});
  tools.set_path(k, {{0.0, Pose{x + Vec3(0, 0, R + 0.5), Quat::Identity()}},
                     {100.0, Pose{x + Vec3(0, 0, R - 1.5), Quat::Identity()}}});
  while (sim.time() < 400) ASSERT_TRUE(tools.update().ok());
  const ToolState& st = tools.contact().state(k);
  EXPECT_GT(st.contacts, 0);
  EXPECT_GT(st.force.z(), 0);
  EXPECT_GT((sim.state().x - sim.model().x0).rowwise().norm().maxCoeff(), 0.5);  // the atoms moved
  EXPECT_LT((sim.applied_force() + st.force).norm(), 1e-12 * st.force.norm());
  EXPECT_EQ(sim.state().warnings.total(), 0u);
}

}  // namespace
}  // namespace medspring
