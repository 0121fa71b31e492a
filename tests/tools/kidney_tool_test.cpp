// Tools on the real kidney (hybrid model built from kidney_left_hubmap_vhm.obj, /work/shared/data):
// a steady press of a sphere (penetration <= 5 % of the radius, the surface outside the sphere), the
// static solve with the same contact against the dynamic run at rest (1 %), and grasping.
#include <gtest/gtest.h>

#include <cmath>

#include "medspring/builders/kidney_build.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/physics/static_solve.hpp"
#include "medspring/sim/tool_sim.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

const KidneyBuild& real_kidney() {
  static const KidneyBuild k =
      build_kidney_model({.source = {.mesh = testing::require_data_file("kidney_left_hubmap_vhm.obj"),
                                     .unit = LengthUnit::Metre}});
  return k;
}

// A surface node on the convex side (largest distance from the centroid) and its outward normal.
void pick_node(const HybridKidney& kidney, Index& node, Vec3& normal) {
  MatX3 N;
  vertex_normals(kidney.rest_surface(), kidney.faces(), N);
  const Vec3 c = kidney.rest_surface().colwise().mean().transpose();
  double best = -1;
  for (Index i = 0; i < kidney.num_surface_nodes(); ++i) {
    const Vec3 x = kidney.rest_surface().row(i).transpose();
    // a point on a flank (largest extent in the second principal direction is fine: use y)
    const double score = (x - c).y() * N(i, 1);
    if (score > best) best = score, node = i;
  }
  normal = N.row(node).transpose().normalized();
  // the normals may point inwards if the faces are clockwise: make it point away from the centroid
  if (normal.dot(kidney.rest_surface().row(node).transpose() - c) < 0) normal = -normal;
}

TEST(RealKidneyTool, SteadyPressPenetrationAndStaticAgreement) {
  const KidneyBuild& k = real_kidney();
  Index n0 = 0;
  Vec3 nrm;
  pick_node(*k.model, n0, nrm);
  const Vec3 x0 = k.model->rest_surface().row(n0).transpose();
  Simulation sim(k.model);
  ToolSimulation tools(sim);
  const double R = 12.0, press = 4.0;
  const Pose start{x0 + (R + 2.0) * nrm, Quat::Identity()};
  const Pose end{x0 + (R - press) * nrm, Quat::Identity()};
  const Index probe = tools.add_tool(Tool::sphere(R), start);
  tools.set_path(probe, {{0.0, start}, {100.0, end}});
  while (sim.time() < 1500) ASSERT_TRUE(tools.update().ok());
  const ToolState& st = tools.contact().state(probe);
  RecordProperty("contacts", static_cast<int>(st.contacts));
  std::printf("steady press R %.1f mm: %ld contacts, penetration %.4f mm (%.2f %% of R), force %.4f N\n", R,
              static_cast<long>(st.contacts), st.penetration, 100 * st.penetration / R, st.force.norm());
  EXPECT_GE(st.contacts, 10);
  EXPECT_LE(st.penetration, 0.05 * R);
  EXPECT_GT(st.force.dot(nrm), 0.9 * st.force.norm());  // the reaction points back out of the organ
  for (Index i = 0; i < sim.global_surface().rows(); ++i)
    EXPECT_GE((sim.global_surface().row(i).transpose() - st.pose.position).norm(), 0.95 * R) << i;
  EXPECT_EQ(sim.state().warnings.total(), 0u);
  // at rest
  EXPECT_LT(sim.state().v.cwiseAbs().maxCoeff(), 1e-5);

  // static solve with the same contact forces (held): the same equilibrium within 1 %
  const Model& m = sim.model();
  const StaticResult stat = static_equilibrium(m, sim.state().f_ext, {.tolerance = 1e-9});  // from rest
  const double disp = (sim.state().x - m.x0).rowwise().norm().maxCoeff();
  const double diff = (stat.x - sim.state().x).rowwise().norm().maxCoeff();
  std::printf("static vs dynamic: max displacement %.4f mm, max difference %.2e mm (%d Newton iterations)\n",
              disp, diff, stat.iterations);
  EXPECT_GT(stat.iterations, 0);
  EXPECT_GT(disp, 1.0);
  EXPECT_LE(diff, 0.01 * disp);
  // and the contact evaluated on the static configuration gives the same force within 1 %
  ContactModel again = tools.contact();
  MatX3 S;
  State s_static = sim.state();
  s_static.x = stat.x;
  k.model->map_to_surface(s_static, S);
  again.update(S);
  const Vec3 f_dyn = st.force, f_stat = again.state(probe).force;
  EXPECT_LE((f_stat - f_dyn).norm(), 0.01 * f_dyn.norm())
      << f_stat.transpose() << " vs " << f_dyn.transpose();
}

TEST(RealKidneyTool, GrasperHoldsStretchesAndReleasesTheTissue) {
  const KidneyBuild& k = real_kidney();
  Index n0 = 0;
  Vec3 nrm;
  pick_node(*k.model, n0, nrm);
  const Vec3 x0 = k.model->rest_surface().row(n0).transpose();
  Simulation sim(k.model);
  ToolSimulation tools(sim);
  const double L = 12.0, r = 1.5, open = 60 * std::numbers::pi / 180;
  const Quat q = Quat::FromTwoVectors(Vec3::UnitZ(), nrm);  // the tool's -z points into the organ
  const double reach = L * std::cos(open / 2);
  const Pose above{x0 + (reach + r - 1.5) * nrm, q};  // jaw tips 1.5 mm into the surface
  const Pose pulled{above.position + 8.0 * nrm, q};
  ToolPath path;
  path.push_back({0.0, above, open});
  path.push_back({50.0, above, open});
  path.push_back({150.0, above, 0.0});    // close
  path.push_back({300.0, pulled, 0.0});   // pull 8 mm out
  path.push_back({500.0, pulled, 0.0});   // hold
  path.push_back({550.0, pulled, open});  // open: release
  const Index g = tools.add_tool(Tool::grasper(r, L, open), above);
  tools.set_path(g, path);
  while (sim.time() < 149) ASSERT_TRUE(tools.update().ok());
  while (sim.time() < 500) ASSERT_TRUE(tools.update().ok());
  const ToolState& st = tools.contact().state(g);
  ASSERT_TRUE(st.grasping);
  EXPECT_GT(st.attached, 0);
  const double lift = (sim.global_surface().row(n0).transpose() - x0).dot(nrm);
  std::printf("grasp: %ld points held, node lifted %.3f mm, grasp force %.4f N\n",
              static_cast<long>(st.attached), lift, st.grasp_force.norm());
  EXPECT_GT(lift, 3.0);                     // the held tissue is stretched out of the organ
  EXPECT_LT(st.grasp_force.dot(nrm), 0.0);  // and pulls the jaws back towards it
  EXPECT_GT(st.grasp_force.norm(), 1e-3);
  while (sim.time() < 1500) ASSERT_TRUE(tools.update().ok());
  EXPECT_FALSE(tools.contact().state(g).grasping);
  EXPECT_EQ(tools.contact().state(g).attached, 0);
  const double after = (sim.global_surface().row(n0).transpose() - x0).dot(nrm);
  EXPECT_LT(std::abs(after), 0.5 * lift);  // released: the tissue springs back
  EXPECT_EQ(sim.state().warnings.total(), 0u);
}

}  // namespace
}  // namespace medspring
