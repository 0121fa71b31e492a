// Tool shapes, the surface BVH and the contact model on analytic geometry (a flat plate of triangles):
// contact points, normals, depths and barycentric weights, force and torque bookkeeping, the friction
// cone, the stable penalty and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/tools/contact.hpp"

namespace medspring {
namespace {

// n x n squares of size h in z = 0, two triangles each, counter-clockwise seen from +z (outside).
struct Plate {
  MatX3 V;
  MatX3i F;
};
Plate plate(int n, double h) {
  Plate p;
  p.V.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) p.V.row(j * (n + 1) + i) << (i - 0.5 * n) * h, (j - 0.5 * n) * h, 0.0;
  p.F.resize(2 * n * n, 3);
  int t = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      p.F.row(t++) << a, b, d;
      p.F.row(t++) << a, d, c;
    }
  return p;
}

// A closed plate "box" is not needed: the plate's volume sign is 0, so orientation defaults to +1
// (counter-clockwise = outside = +z), which is what these tests use.

TEST(Tool, ValidatesSizes) {
  EXPECT_THROW(validate_tool(Tool::sphere(0), "t"), InvalidInput);
  EXPECT_THROW(validate_tool(Tool::sphere(-1), "t"), InvalidInput);
  EXPECT_THROW(validate_tool(Tool::sphere(std::nan("")), "t"), InvalidInput);
  EXPECT_THROW(validate_tool(Tool::capsule(1, -2), "t"), InvalidInput);
  EXPECT_THROW(validate_tool(Tool::grasper(1, 0, 0.5), "t"), InvalidInput);
  EXPECT_THROW(validate_tool(Tool::grasper(1, 10, 4.0), "t"), InvalidInput);
  EXPECT_NO_THROW(validate_tool(Tool::grasper(1, 10, 0.5), "t"));
  try {
    validate_tool(Tool::sphere(-1), "tools[2]");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("tools[2].radius"), std::string::npos) << e.what();
  }
}

TEST(Tool, ParsesCommandLineShapes) {
  const Tool s = parse_tool("sphere:4.5");
  EXPECT_EQ(s.kind, ToolKind::Sphere);
  EXPECT_DOUBLE_EQ(s.radius, 4.5);
  const Tool g = parse_tool("grasper:1.5:12:30");
  EXPECT_EQ(g.kind, ToolKind::Grasper);
  EXPECT_NEAR(g.opening, std::numbers::pi / 6, 1e-15);
  for (const char* bad : {"sphere", "sphere:0", "sphere:-2", "sphere:x", "cube:3", "capsule:1", "sphere:nan"})
    EXPECT_THROW(parse_tool(bad), InvalidInput) << bad;
}

TEST(Tool, NanPoseIsRefused) {
  Pose p;
  p.position = Vec3(0, std::nan(""), 0);
  EXPECT_THROW(checked_pose(p, "pose"), InvalidInput);
  Pose q;
  q.rotation = Quat(0, 0, 0, 0);
  EXPECT_THROW(checked_pose(q, "pose"), InvalidInput);
  const Plate pl = plate(4, 1.0);
  ContactModel cm(pl.F, pl.V);
  EXPECT_THROW(cm.add_tool(Tool::sphere(1), p), InvalidInput);
  const Index k = cm.add_tool(Tool::sphere(1), Pose{});
  EXPECT_THROW(cm.set_pose(k, p), InvalidInput);
  EXPECT_THROW(cm.set_opening(k, 0.1), InvalidInput);  // not a grasper
}

TEST(Tool, GrasperJawsSpanTheOpeningAngle) {
  Pose pose;
  pose.position = Vec3(1, 2, 3);
  pose.rotation = Quat(Eigen::AngleAxisd(0.7, Vec3(0, 0, 1)));
  Capsule c[2];
  ASSERT_EQ(primitives(Tool::grasper(1, 10, 0.8), pose, c), 2);
  const Vec3 d0 = (c[0].b - c[0].a).normalized(), d1 = (c[1].b - c[1].a).normalized();
  EXPECT_NEAR(std::acos(d0.dot(d1)), 0.8, 1e-12);
  EXPECT_NEAR((c[0].b - c[0].a).norm(), 10, 1e-12);
  EXPECT_TRUE(c[0].a.isApprox(pose.position));
  EXPECT_NEAR(d0.z(), -std::cos(0.4), 1e-12);  // jaws point down the tool's -z
  ASSERT_EQ(primitives(Tool::sphere(2), pose, c), 1);
  EXPECT_TRUE(c[0].a.isApprox(c[0].b));
}

TEST(SurfaceBvh, QueryFindsEveryOverlappingTriangleAfterRefit) {
  Plate p = plate(12, 1.0);
  SurfaceBvh bvh(p.F, p.V);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-7, 7);
  for (Index i = 0; i < p.V.rows(); ++i) p.V(i, 2) = 0.3 * std::sin(p.V(i, 0)) * std::cos(p.V(i, 1));
  bvh.refit(p.V);
  std::vector<Index> found;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 c(u(rng), u(rng), 0.3 * u(rng) / 7);
    const Vec3 lo = c.array() - 0.8, hi = c.array() + 0.8;
    found.clear();
    bvh.query(lo, hi, found);
    for (Index t = 0; t < p.F.rows(); ++t) {
      Vec3 tlo = Vec3::Constant(1e9), thi = Vec3::Constant(-1e9);
      for (int k = 0; k < 3; ++k) {
        tlo = tlo.cwiseMin(p.V.row(p.F(t, k)).transpose());
        thi = thi.cwiseMax(p.V.row(p.F(t, k)).transpose());
      }
      const bool overlap = (tlo.array() <= hi.array()).all() && (thi.array() >= lo.array()).all();
      const bool listed = std::find(found.begin(), found.end(), t) != found.end();
      if (overlap) {
        EXPECT_TRUE(listed) << "trial " << trial << " triangle " << t;  // leaves: a superset
      }
    }
  }
}

TEST(Contact, SpherePressingAPlateHasUpwardNormalsAndTheRightDepth) {
  const Plate p = plate(10, 1.0);
  ContactModel cm(p.F, p.V, {.min_mass = 0.3, .dt = 0.5});
  Pose pose;
  pose.position = Vec3(0.23, -0.31, 1.5);  // radius 2: 0.5 mm deep
  const Index k = cm.add_tool(Tool::sphere(2.0), pose);
  cm.update(p.V);
  ASSERT_GT(cm.contacts().size(), 4u);
  double deepest = 0;
  for (const Contact& c : cm.contacts()) {
    EXPECT_NEAR(c.bary.sum(), 1.0, 1e-12);
    EXPECT_GE(c.bary.minCoeff(), -1e-12);
    Vec3 x = Vec3::Zero();
    for (int j = 0; j < 3; ++j) x += c.bary[j] * p.V.row(p.F(c.triangle, j)).transpose();
    EXPECT_LT((x - c.point).norm(), 1e-12);  // the weights reproduce the contact point
    EXPECT_NEAR(c.point.z(), 0, 1e-12);
    EXPECT_NEAR(c.depth, 2.0 - (pose.position - c.point).norm(), 1e-12);
    EXPECT_LE((c.normal - (pose.position - c.point).normalized()).norm(), 1e-12);
    EXPECT_LT(c.force.z(), 0);  // the tissue is pushed down, away from the tool
    deepest = std::max(deepest, c.depth);
  }
  EXPECT_NEAR(deepest, 0.5, 1e-12);
  EXPECT_NEAR(cm.state(k).triangle_penetration, 0.5, 1e-12);
  EXPECT_GT(cm.state(k).force.z(), 0);  // the tool is pushed back up
}

TEST(Contact, ForceAndTorqueOnTheToolBalanceTheNodeForces) {
  const Plate p = plate(10, 1.0);
  for (const double multiplier : {0.0, 0.25}) {
    SCOPED_TRACE(multiplier);
    ContactModel cm(p.F, p.V, {.min_mass = 0.3, .dt = 0.5, .multiplier = multiplier, .friction = 0.4});
    Pose pose;
    pose.position = Vec3(-3, 0.4, 0.6);
    pose.rotation = Quat(Eigen::AngleAxisd(std::numbers::pi / 2 + 0.05, Vec3(0.1, 1, 0).normalized()));
    const Index k = cm.add_tool(Tool::capsule(1.0, 7.0), pose);  // shaft lying almost flat on the plate
    cm.update(p.V);
    Pose moved = pose;
    moved.position += Vec3(0.05, 0.02, -0.02);  // slide and press: friction and damping act
    cm.set_pose(k, moved);
    cm.update(p.V);
    ASSERT_GT(cm.contacts().size(), 3u);
    Vec3 sum = Vec3::Zero(), torque = Vec3::Zero();
    for (const Contact& c : cm.contacts()) {
      sum += c.force;
      torque += (c.point - moved.position).cross(-c.force);
    }
    // every force on the tissue, at the nodes it acts on (contacts by barycentric weights, multipliers)
    Vec3 nodes = Vec3::Zero(), node_torque = Vec3::Zero();
    for (const Index n : cm.forces().nodes) {
      const Vec3 f = cm.forces().force.row(n).transpose();
      nodes += f;
      node_torque += (p.V.row(n).transpose() - moved.position).cross(-f);
    }
    const double scale = nodes.norm();
    ASSERT_GT(scale, 0);
    EXPECT_LT((cm.state(k).force + nodes).norm(), 1e-12 * scale);  // force on the tool = -sum f
    EXPECT_LT((cm.forces().total - nodes).norm(), 1e-12 * scale);
    EXPECT_LT((cm.state(k).torque - node_torque).norm(), 1e-11 * scale);  // torque = sum r x f
    EXPECT_GT(cm.state(k).torque.norm(), 1e-3 * scale);
    if (multiplier == 0) {  // pure penalty: the contacts carry everything; the weights keep the moment
      EXPECT_LT((nodes - sum).norm(), 1e-12 * scale);
      EXPECT_LT((node_torque - torque).norm(), 1e-11 * scale);
    } else {  // multipliers add to the normal push
      EXPECT_GT(-cm.forces().total.z(), -sum.z());
    }
  }
}

TEST(Contact, FrictionStaysInsideTheConeAndDragsTheTissueAlong) {
  const Plate p = plate(10, 1.0);
  const double mu = 0.3;
  ContactModel cm(p.F, p.V, {.min_mass = 0.3, .dt = 0.5, .friction = mu});
  Pose pose;
  pose.position = Vec3(0, 0, 1.7);
  const Index k = cm.add_tool(Tool::sphere(2.0), pose);
  cm.update(p.V);
  for (int i = 1; i <= 5; ++i) {  // slide along +x at 0.2 mm/ms (surface fixed)
    pose.position.x() += 0.1;
    cm.set_pose(k, pose);
    cm.update(p.V);
  }
  ASSERT_FALSE(cm.contacts().empty());
  double ft_total = 0;
  for (const Contact& c : cm.contacts()) {
    const double fn = -c.force.dot(c.normal);
    const Vec3 ft = c.force + fn * c.normal;
    EXPECT_GE(fn, 0);
    EXPECT_LE(ft.norm(), mu * fn * (1 + 1e-12));
    EXPECT_GE(ft.x(), 0);  // the tissue is dragged along the motion
    ft_total += ft.x();
  }
  EXPECT_GT(ft_total, 0);
  EXPECT_LT(cm.state(k).force.x(), 0);  // the tool feels the drag against its motion
}

TEST(Contact, AutomaticPenaltyRespectsTheStableStep) {
  const Plate p = plate(6, 2.0);
  ContactModel cm(p.F, p.V, {.min_mass = 0.3, .dt = 0.5});
  // largest node area sum: an interior node with 6 triangles of 2 mm^2 = 12 mm^2, x 1.5 margin
  const double a_max = 1.5 * 12.0;
  EXPECT_NEAR(cm.stiffness_limit(), 4 * 0.3 / (0.25 * a_max), 1e-12);
  EXPECT_NEAR(cm.stiffness(), cm.stiffness_limit() / 4, 1e-12);
  EXPECT_THROW(ContactModel(p.F, p.V, {.min_mass = 0.3, .dt = 0.5, .stiffness = 2 * cm.stiffness_limit()}),
               InvalidInput);
  EXPECT_THROW(ContactModel(p.F, p.V, {.dt = -1}), InvalidInput);
  EXPECT_THROW(ContactModel(p.F, p.V, {.friction = std::nan("")}), InvalidInput);
}

TEST(Contact, ATriangleTheCentreCrossedInOneStepIsStillInContact) {
  // a sphere that moved by its radius through the plate in one update: the centre is behind the plate
  // (signed distance -0.9 R), the contact is found with depth 1.9 R and a normal pointing back up.
  const Plate p = plate(10, 1.0);
  ContactModel cm(p.F, p.V, {.min_mass = 0.3, .dt = 0.5});
  Pose pose;
  pose.position = Vec3(0.1, 0.2, 0.1);
  const Index k = cm.add_tool(Tool::sphere(1.0), pose);
  cm.update(p.V);
  pose.position.z() = -0.9;
  cm.set_pose(k, pose);
  cm.update(p.V);
  ASSERT_FALSE(cm.contacts().empty());
  EXPECT_NEAR(cm.state(k).triangle_penetration, 1.9, 1e-12);
  EXPECT_GT(cm.state(k).force.z(), 0);  // the tool is pushed back out, the tissue down past it
  for (const Contact& c : cm.contacts()) EXPECT_GT(c.normal.z(), 0.99);
}

TEST(Contact, ASphereThatPassedThroughTheSurfaceKeepsItsContactUntilItIsOutside) {
  // Persistent contact (docs/tools.md, "No tunnelling"): a sphere touching a closed ball of tissue that
  // gets 2 r behind the surface in one update finds no triangle within r; the winding number says it is
  // inside, so the contacts are kept from the nearest surface, capped at 2 r deep, and push it back out.
  const SurfaceMesh ball = icosphere(3, 20.0);
  const double r = 1.0;
  ContactModel cm(ball.F, ball.V, {.min_mass = 0.3, .dt = 0.5});
  Pose pose;
  pose.position = Vec3(0, 0, 20.5);
  const Index k = cm.add_tool(Tool::sphere(r), pose);
  cm.update(ball.V);
  ASSERT_GT(cm.state(k).contacts, 0);
  EXPECT_FALSE(cm.state(k).inside);
  // the checkpoint of the history carries the touch (a resumed run keeps the contact too)
  ContactModel resumed(ball.F, ball.V, {.min_mass = 0.3, .dt = 0.5});
  resumed.add_tool(Tool::sphere(r), pose);
  resumed.restore_history(cm.save_history());
  pose.position = Vec3(0.3, -0.2, 17.0);  // 3 r below the surface
  for (ContactModel* m : {&cm, &resumed}) {
    m->set_pose(k, pose);
    m->update(ball.V);
    const ToolState& st = m->state(k);
    EXPECT_TRUE(st.inside);
    ASSERT_GT(st.contacts, 0);
    EXPECT_GT(st.force.z(), 0.9 * st.force.norm());  // pushed back out along the outward normal
    for (const Contact& c : m->contacts()) {
      EXPECT_LE(c.depth, 2 * r + 1e-12);
      EXPECT_GT(c.normal.z(), 0.9);
    }
  }
  EXPECT_EQ(resumed.state(k).force, cm.state(k).force);
  // still inside at the next update: still in contact
  cm.update(ball.V);
  EXPECT_TRUE(cm.state(k).inside);
  EXPECT_GT(cm.state(k).contacts, 0);
  // out again: released
  pose.position = Vec3(0, 0, 25.0);
  cm.set_pose(k, pose);
  cm.update(ball.V);
  EXPECT_EQ(cm.state(k).contacts, 0);
  EXPECT_FALSE(cm.state(k).inside);
  // a sphere that never touched the surface is not searched for (the check costs O(#F)): placed inside
  // directly, it is refused by ToolSimulation::add_tool (check_outside) instead
  pose.position = Vec3(0, 0, 17.0);
  cm.set_pose(k, pose);
  cm.update(ball.V);
  EXPECT_EQ(cm.state(k).contacts, 0);
  EXPECT_FALSE(cm.state(k).inside);
}

TEST(Contact, CapsuleThroughThePlateReportsTheCrossing) {
  const Plate p = plate(10, 1.0);
  ContactModel cm(p.F, p.V, {.min_mass = 0.3, .dt = 0.5});
  Pose pose;
  pose.position = Vec3(0.3, 0.3, -0.4);  // tip 0.4 below the plate, shaft up through it
  cm.add_tool(Tool::capsule(0.5, 5.0), pose);
  cm.update(p.V);
  ASSERT_FALSE(cm.contacts().empty());
  bool crossing = false;
  for (const Contact& c : cm.contacts())
    if (std::abs(c.depth - 0.9) < 1e-9) crossing = true;  // r + depth of the tip below the plane
  EXPECT_TRUE(crossing);
}

TEST(Contact, GrasperHoldsWhatItsJawsTouchUntilItOpens) {
  // a vertical fin (two triangles in x = 0) between the jaws
  MatX3 V(4, 3);
  V << 0, -2, -6, 0, 2, -6, 0, 2, -1, 0, -2, -1;
  MatX3i F(2, 3);
  F << 0, 1, 2, 0, 2, 3;
  ContactModel cm(F, V, {.min_mass = 0.3, .dt = 0.5, .grasp_angle = 0.2});
  Pose pose;  // hinge at the origin, jaws down to z = -8
  const Index k = cm.add_tool(Tool::grasper(0.5, 8.0, 0.6), pose);
  cm.update(V);
  EXPECT_FALSE(cm.state(k).grasping);
  cm.set_opening(k, 0.05);  // closed: jaws (radius 0.5) reach the fin at x = 0
  cm.update(V);
  EXPECT_TRUE(cm.state(k).grasping);
  EXPECT_GT(cm.state(k).attached, 0);
  pose.position.z() += 0.5;  // pull up: the held points pull the tool down, the tissue up
  cm.set_pose(k, pose);
  cm.update(V);
  EXPECT_LT(cm.state(k).grasp_force.z(), 0);
  EXPECT_GT(cm.forces().total.z(), 0);
  cm.set_opening(k, 0.6);  // open: released
  cm.update(V);
  EXPECT_FALSE(cm.state(k).grasping);
  EXPECT_EQ(cm.state(k).attached, 0);
  EXPECT_EQ(cm.state(k).grasp_force.norm(), 0);
}

}  // namespace
}  // namespace medspring
