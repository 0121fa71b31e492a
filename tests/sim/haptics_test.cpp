#include "medspring/sim/haptics.hpp"

#include <gtest/gtest.h>

#include <sstream>

#include "medspring/core/error.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/physics/static_solve.hpp"

namespace medspring {
namespace {

constexpr Index kContact = 223;

std::shared_ptr<HybridKidney> kidney() {
  return std::make_shared<HybridKidney>(hybrid_kidney_phantom());
}

Vec3 inward(const HybridKidney& k) {
  return -(k.model().x0.row(kContact) - k.model().x0.row(k.atom_dof(21))).normalized().transpose();
}

// tool at the contact's rest position, pressed `depth` mm inwards over 100 ms, held to 800 ms
Trajectory press(const HybridKidney& k, double depth) {
  const Vec3 x0 = k.rest_surface().row(kContact).transpose();
  return {{0.0, x0}, {100.0, x0 + depth * inward(k)}, {800.0, x0 + depth * inward(k)}};
}

std::string message_of(const std::string& csv) {
  std::istringstream in(csv);
  try {
    read_trajectory(in, "path.csv");
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "no error";
}

TEST(Haptics, PressForceMatchesTheCoupledStaticSolveWithinOnePercent) {
  auto body = kidney();
  Simulation sim(body);
  HapticLoop loop(sim, kContact);
  EXPECT_EQ(loop.updates_per_tick(), 2);  // 1 ms tick = 2 frames of 0.5 ms
  const Trajectory path = press(*body, 3.0);
  const TickStats st = run_trajectory(loop, path);
  EXPECT_EQ(st.ticks, 800);
  const Vec3 F_dyn = loop.last().force;
  // static equilibrium of the model under the coupling spring: g(F) = F - k_vc (x_tool - x_c(F)) = 0,
  // x_c(F) from static_equilibrium; Newton on F with a central-difference Jacobian (the plain fixed
  // point diverges: the tangential compliance times k_vc exceeds 1)
  const Vec3 x_tool = path.back().x;
  const Model& m = body->model();
  const auto g = [&](const Vec3& force) {
    MatX3 f = MatX3::Zero(m.num_nodes(), 3);
    body->transfer_force(kContact, force, f);
    const MatX3 x = static_equilibrium(m, f).x;
    return Vec3(force - loop.settings().k_vc * (x_tool - x.row(kContact).transpose()));
  };
  Vec3 F = Vec3::Zero();
  for (int it = 0; it < 20; ++it) {
    const Vec3 r = g(F);
    if (r.norm() < 1e-12) break;
    Mat3 J;
    for (int c = 0; c < 3; ++c) {
      const Vec3 h = 1e-6 * Vec3::Unit(c);
      J.col(c) = (g(F + h) - g(F - h)) / 2e-6;
    }
    F -= J.lu().solve(r);
  }
  ASSERT_LT(g(F).norm(), 1e-9);
  ASSERT_GT(F.norm(), 0.05);
  EXPECT_LT((F_dyn - F).norm(), 0.01 * F.norm())
      << "dynamic " << F_dyn.transpose() << " static " << F.transpose();
  // and the reaction returned to the device is -F; the force pushes inwards
  EXPECT_GT(F_dyn.dot(inward(*body)), 0.0);
  EXPECT_FALSE(loop.last().saturated);
  EXPECT_NEAR((sim.applied_force() - F_dyn).norm(), 0.0, 1e-15);
}

TEST(Haptics, ForceIsSaturatedToTheDeviceMaximum) {
  auto body = kidney();
  Simulation sim(body);
  HapticSettings hs;
  hs.f_max = 0.05;
  HapticLoop loop(sim, kContact, hs);
  run_trajectory(loop, press(*body, 5.0), 400);
  EXPECT_TRUE(loop.last().saturated);
  EXPECT_NEAR(loop.last().force.norm(), 0.05, 1e-12);
  const Vec3 reaction = loop.tick(press(*body, 5.0).back().x);
  EXPECT_NEAR((reaction + loop.last().force).norm(), 0.0, 1e-15);
  for (const HapticSample& s : loop.samples()) EXPECT_LE(s.force.norm(), 0.05 + 1e-12);
}

TEST(Haptics, ReleaseLetsTheTissueReturnToRest) {
  auto body = kidney();
  Simulation sim(body);
  HapticLoop loop(sim, kContact);
  run_trajectory(loop, press(*body, 3.0), 300);
  EXPECT_GT(sim.displacement().rowwise().norm().maxCoeff(), 0.5);
  loop.release();
  EXPECT_EQ(sim.applied_force().norm(), 0.0);
  sim.advance(1000);
  EXPECT_LT(sim.displacement().rowwise().norm().maxCoeff(), 1e-3);
}

TEST(Haptics, WorksWithLocalDeformationOnTheContactPatch) {
  auto body = kidney();
  SimulationSettings ss;
  ss.local.enabled = true;
  Simulation sim(body, ss);
  HapticLoop loop(sim, kContact);
  run_trajectory(loop, press(*body, 3.0), 300);
  EXPECT_EQ(sim.local_nodes().size(), 25u);
  // the overlay deepens the displayed dent along the applied force
  const Vec3 U = (sim.surface().row(kContact) - sim.global_surface().row(kContact)).transpose();
  EXPECT_GT(U.dot(loop.last().force), 0.0);
}

TEST(Haptics, RejectsATickThatIsNotAMultipleOfTheStepAndBadSettings) {
  Simulation sim(kidney());
  HapticSettings hs;
  hs.tick = 0.75;
  EXPECT_THROW(HapticLoop(sim, kContact, hs), InvalidInput);
  EXPECT_THROW(HapticLoop(sim, 458, HapticSettings{}), InvalidInput);
  hs = {};
  hs.f_max = 0;
  EXPECT_THROW(HapticLoop(sim, kContact, hs), InvalidInput);
}

TEST(Haptics, TrajectoryReaderAcceptsHeaderCommentsAndInterpolates) {
  std::istringstream in("time_ms,x,y,z\n# comment\n\n0, 0, 0, 0\r\n10,1,2,3\n");
  const Trajectory p = read_trajectory(in);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_NEAR((trajectory_position(p, 5) - Vec3(0.5, 1, 1.5)).norm(), 0.0, 1e-15);
  EXPECT_EQ(trajectory_position(p, -1), Vec3(0, 0, 0));
  EXPECT_EQ(trajectory_position(p, 99), Vec3(1, 2, 3));
}

TEST(Haptics, MalformedTrajectoryErrorsNameTheLine) {
  EXPECT_EQ(message_of("0,0,0,0\n1,0,abc,0\n"), "path.csv:2: field 3 'abc' is not a finite number");
  EXPECT_EQ(message_of("t,x,y,z\n0,0,0\n"), "path.csv:2: expected 4 fields (time_ms, x, y, z), found 3");
  EXPECT_EQ(message_of("0,0,0,0\n1,0,0,0,5\n"), "path.csv:2: expected 4 fields (time_ms, x, y, z), found 5");
  EXPECT_EQ(message_of("0,0,0,0\n# c\n0,1,1,1\n"),
            "path.csv:3: time 0 ms is not after the previous row's 0 ms");
  EXPECT_EQ(message_of("0,0,0,0\n1,nan,0,0\n"), "path.csv:2: field 2 'nan' is not a finite number");
  EXPECT_EQ(message_of("0,0,0,0\nx,0,0,0\n"), "path.csv:2: field 1 'x' is not a finite number");
  EXPECT_EQ(message_of("time,x,y,z\n"), "path.csv: no trajectory rows (expected CSV: time_ms, x, y, z)");
  EXPECT_THROW(read_trajectory_file("/nonexistent/path.csv"), IoError);
}

}  // namespace
}  // namespace medspring
