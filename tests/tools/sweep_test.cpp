// No tunnelling (docs/tools.md): 10^4 seeded randomised presses and slides of a sphere on the real
// kidney, the tool moving at most its radius per update. After every update the sphere's centre must
// be outside the deformed surface (generalized winding number < 1/2), and whenever any surface point
// is within the sphere the contact set must not be empty. Label `long`.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "medspring/builders/kidney_build.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/sim/tool_sim.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

double winding(const MatX3& S, const MatX3i& F, const Vec3& q) {
  double w = 0;
  for (Index t = 0; t < F.rows(); ++t) {
    const Vec3 a = S.row(F(t, 0)).transpose() - q, b = S.row(F(t, 1)).transpose() - q,
               c = S.row(F(t, 2)).transpose() - q;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    w += 2 * std::atan2(a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb);
  }
  return w / (4 * std::numbers::pi);
}

TEST(ToolSweep, TenThousandRandomPressesAndSlidesNeverTunnel) {
  const KidneyBuild k =
      build_kidney_model({.source = {.mesh = testing::require_data_file("kidney_left_hubmap_vhm.obj"),
                                     .unit = LengthUnit::Metre}});
  const HybridKidney& kid = *k.model;
  MatX3 N;
  vertex_normals(kid.rest_surface(), kid.faces(), N);
  const double orient =
      winding(kid.rest_surface(), kid.faces(), kid.rest_surface().colwise().mean()) > 0 ? 1 : -1;
  Simulation sim(k.model, {.normals = false});
  ToolSimulation tools(sim, {.friction = 0.2});
  std::mt19937 rng(20261125);
  std::uniform_real_distribution<double> u(0, 1);
  std::uniform_int_distribution<Index> pick(0, kid.num_surface_nodes() - 1);
  const double R = 6.0;
  const Index probe = tools.add_tool(Tool::sphere(R), Pose{Vec3(1e4, 0, 0), Quat::Identity()});
  long updates = 0, inside = 0, missed = 0, episodes = 0;
  for (int e = 0; e < 10000; ++e) {
    const Index n = pick(rng);
    const Vec3 x = kid.rest_surface().row(n).transpose(), nrm = orient * N.row(n).transpose().normalized();
    Vec3 t1 = nrm.unitOrthogonal(), t2 = nrm.cross(t1);
    const double phi = 2 * std::numbers::pi * u(rng);
    const Vec3 slide_dir = std::cos(phi) * t1 + std::sin(phi) * t2;
    const Vec3 start = x + (R + 0.5 + 2 * u(rng)) * nrm;
    const Vec3 pressed = x + (R - 1.0 * R * u(rng)) * nrm;  // down to the centre on the rest surface
    const Vec3 slid = pressed + 3 * R * u(rng) * slide_dir;
    const double step = R * (0.05 + 0.95 * u(rng));  // mm per update, <= R
    tools.set_pose(probe, Pose{start, Quat::Identity()});
    tools.reset();
    // skip starts that overlap another part of the organ (a concave region): the tool must start outside
    if (winding(sim.global_surface(), kid.faces(), start) * orient >= 0.5) continue;
    ++episodes;
    const Vec3 legs[3] = {pressed, slid, start};
    Vec3 at = start;
    for (const Vec3& target : legs) {
      const int n_up = std::max(1, static_cast<int>(std::ceil((target - at).norm() / step)));
      const Vec3 from = at;
      for (int i = 1; i <= n_up + 2; ++i) {
        at = from + std::min(1.0, static_cast<double>(i) / n_up) * (target - from);
        tools.set_pose(probe, Pose{at, Quat::Identity()});
        ASSERT_TRUE(tools.update().ok()) << "episode " << e;
        ++updates;
        const double w = orient * winding(sim.global_surface(), kid.faces(), at);
        if (w >= 0.5) ++inside;
        double nearest = 1e300;
        for (Index j = 0; j < sim.global_surface().rows(); ++j)
          nearest = std::min(nearest, (sim.global_surface().row(j).transpose() - at).norm());
        if (nearest < R && tools.contact().state(probe).contacts == 0) ++missed;
      }
    }
  }
  std::printf("%ld episodes, %ld updates: centre inside %ld times, missed contacts %ld\n", episodes, updates,
              inside, missed);
  EXPECT_GT(episodes, 9000);
  EXPECT_EQ(inside, 0);
  EXPECT_EQ(missed, 0);
  EXPECT_EQ(sim.state().warnings.total(), 0u);
}

}  // namespace
}  // namespace medspring
