// Tools on the real kidney (hybrid model built from kidney_left_hubmap_vhm.obj, /work/shared/data):
// a steady press of a sphere (penetration <= 5 % of the radius, the surface outside the sphere), the
// static solve with the same contact against the dynamic run at rest (1 %), and grasping.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "medspring/builders/kidney_build.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/models/tissue.hpp"
#include "medspring/physics/static_solve.hpp"
#include "medspring/sim/tool_sim.hpp"
#include "sweep_episodes.hpp"
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

// Contact at the substep rate (docs/tools.md): the calibrated real kidney ("material": "kidney", stiff
// centerline springs) sub-steps every frame (41 substeps of 12 us). The normal penalty re-evaluated at every
// substep settles the reaction faster after the press and gives the same force at rest.
struct SteadyPress {
  double settle_spread = 0;     // N: max - min of the reaction along the normal over 250-450 ms
  double mean = 0, spread = 0;  // N: mean and max - min over 1500-1700 ms
  double penetration = 0;       // mm: deepest node inside the sphere at the end
  double max_speed = 0;         // mm/ms at the end
  int substeps = 0;             // of the last frame
};

SteadyPress calibrated_press(bool substep) {
  const HybridKidney& kid = *real_kidney().model;
  HybridSettings hs = kid.settings();
  apply_tissue(tissue_preset("kidney"), TissueOrgan::RealKidney, hs);
  const MatX3 atoms = kid.model().x0.bottomRows(kid.num_atoms());
  const auto body = std::make_shared<HybridKidney>(SurfaceMesh{kid.rest_surface(), kid.faces()}, atoms, hs,
                                                   "calibrated kidney");
  Index n0 = 0;
  Vec3 nrm;
  pick_node(kid, n0, nrm);
  const Vec3 x0 = kid.rest_surface().row(n0).transpose();
  Simulation sim(body, {.normals = false});
  ContactSettings cs;
  cs.substep = substep;
  ToolSimulation tools(sim, cs);
  const double R = 12.0, press = 4.0;
  const Pose start{x0 + (R + 1.0) * nrm, Quat::Identity()};
  const Pose end{x0 + (R - press) * nrm, Quat::Identity()};
  const Index probe = tools.add_tool(Tool::sphere(R), start);
  tools.set_path(probe, {{0.0, start}, {250.0, end}});  // 0.02 mm/ms, then held
  StepStatus last;
  // MEDSPRING_TOOLS_TRACE_DIR=D writes D/calibrated_press_{held,substep}.csv: the trace of every update
  std::FILE* trace = nullptr;
  if (const char* dir = std::getenv("MEDSPRING_TOOLS_TRACE_DIR")) {
    const std::string file = cat(dir, "/calibrated_press_", substep ? "substep" : "held", ".csv");
    trace = std::fopen(file.c_str(), "w");
    if (trace) std::fprintf(trace, "t_ms,force_N,penetration_mm,contacts,substeps\n");
  }
  auto update = [&] {
    last = tools.update();
    const ToolState& st = tools.contact().state(probe);
    if (trace)
      std::fprintf(trace, "%.1f,%.9f,%.6f,%ld,%d\n", sim.time(), st.force.dot(nrm), st.penetration,
                   static_cast<long>(st.contacts), last.substeps);
  };
  auto window = [&](double from, double to, double& mean, double& spread) {
    while (sim.time() < from) update();
    double lo = INFINITY, hi = -INFINITY, sum = 0;
    long n = 0;
    while (sim.time() < to) {
      update();
      const double f = tools.contact().state(probe).force.dot(nrm);
      lo = std::min(lo, f), hi = std::max(hi, f), sum += f, ++n;
    }
    mean = sum / static_cast<double>(n);
    spread = hi - lo;
  };
  SteadyPress r;
  double settle_mean = 0;
  window(250, 450, settle_mean, r.settle_spread);
  window(1500, 1700, r.mean, r.spread);
  r.penetration = tools.contact().state(probe).penetration;
  r.max_speed = sim.state().v.cwiseAbs().maxCoeff();
  r.substeps = last.substeps;
  if (trace) std::fclose(trace);
  EXPECT_EQ(sim.state().warnings.total(), 0u);
  return r;
}

TEST(RealKidneyTool, CalibratedKidneySettlesUnderASteadyPressWithContactAtTheSubstepRate) {
  const SteadyPress held = calibrated_press(false), sub = calibrated_press(true);
  for (const auto& [name, p] : {std::pair{"held over the frame", held}, std::pair{"every substep", sub}})
    std::printf(
        "calibrated kidney, R 12 mm pressed 4 mm, contact %s: %d substeps per frame; reaction spread "
        "%.2e N over 250-450 ms; at 1500-1700 ms %.6f N, spread %.2e N, penetration %.4f mm (%.2f %% "
        "of R), max |v| %.2e mm/ms\n",
        name, p.substeps, p.settle_spread, p.mean, p.spread, p.penetration, 100 * p.penetration / 12.0,
        p.max_speed);
  EXPECT_GT(sub.substeps, 1);  // the case sub-steps
  EXPECT_LE(sub.penetration, 0.05 * 12.0);
  // No assertion that the substep evaluation settles faster: it does in the GCC release build (1.6e-2 vs
  // 1.8e-2 N over 250-450 ms) but not in the clang -O1 sanitizer build, whose balloon mesh differs (rest
  // force 0.397 N; 1.9e-2 vs 1.5e-2 N). docs/tools.md reports both; the option is opt-in.
  EXPECT_LT(sub.spread, 1e-9);  // at rest
  EXPECT_LT(sub.max_speed, 1e-6);
  EXPECT_NEAR(sub.mean, held.mean, 1e-6 * held.mean);  // the same equilibrium
}

// Regressions of the no-tunnelling sweep (tools_sweep_tests, docs/tools.md): before the persistent contact,
// episodes 1112 and 2021 -- a deep press (centre ~1 mm above the rest surface), then a slide at 0.75-1 R per
// update -- ended with the whole 6 mm sphere inside the organ and no contact after the 8 ms hold. Now the
// contact is kept from the nearest surface while the centre is inside, and the tissue is pushed back out.
void replay_sweep_episode(int number) {
  testing::KidneySweep sweep(real_kidney());
  const testing::SweepEpisode ep = sweep.draw_episode(number);
  testing::SweepCounts c;
  long inside_without_contact = 0;
  double deepest_node = 0;
  ASSERT_TRUE(sweep.run(ep, c, [&](int leg, const Vec3& at) {
    const ToolState& st = sweep.tools().contact().state(sweep.probe());
    std::printf(
        "  inside after the hold of leg %d: w %.3f, %ld contacts, deepest node %.3f mm, deepest "
        "triangle point %.3f mm, reaction %.3f N\n",
        leg, sweep.inside(at), static_cast<long>(st.contacts), st.penetration, st.triangle_penetration,
        st.force.norm());
    if (st.contacts == 0) ++inside_without_contact;
    deepest_node = std::max(deepest_node, st.penetration);
  }));
  std::printf(
      "episode %d: node %ld, step %.2f mm, %ld updates, %ld with the contact kept from inside, %ld "
      "inside after a hold, largest reaction %.3f N\n",
      number, static_cast<long>(ep.node), ep.step, c.updates, c.persistent, c.inside_after_hold, c.max_force);
  EXPECT_GT(ep.step, 0.7 * testing::KidneySweep::R);  // the fast slide that used to tunnel
  EXPECT_GT(c.persistent, 0);                         // the sphere did get inside between two updates
  EXPECT_EQ(c.lost, 0);                               // but never without contact
  EXPECT_EQ(inside_without_contact, 0);
  // At most the "tent" state of docs/tools.md: the sphere's centre behind stretched triangles while the
  // nodes stay near its surface (the 10^4 sweep's deepest such node is 3.3 mm).
  EXPECT_LE(deepest_node, 0.6 * testing::KidneySweep::R);
  EXPECT_LE(c.max_force, 20.0);  // the kept contacts push with a depth of at most 2 R: no blow-up
  EXPECT_EQ(c.missed, 0);
  EXPECT_EQ(sweep.failed_updates(), 0);
  EXPECT_EQ(sweep.sim().state().warnings.total(), 0u);
  // lifted back to the start: the sphere is outside the organ again
  EXPECT_LT(sweep.inside(ep.start), 0.5);
}

TEST(RealKidneyTool, SweepEpisode1112DeepPressThenFastSlideDoesNotTunnel) {
  replay_sweep_episode(1112);
}

TEST(RealKidneyTool, SweepEpisode2021DeepPressThenFastSlideDoesNotTunnel) {
  replay_sweep_episode(2021);
}

}  // namespace
}  // namespace medspring
