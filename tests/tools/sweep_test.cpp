// No tunnelling (docs/tools.md): 10^4 seeded randomised presses and slides of a sphere on the real
// kidney, the tool moving at most its radius per update. Whenever a surface node lies inside the
// sphere at the start of an update, the contact set of that update must not be empty (detection never
// misses), and after each press and slide (plus an 8 ms hold) a sphere whose centre is inside the
// deformed surface (generalized winding number >= 1/2) must still be in contact: the contact is never
// lost, so the response keeps acting (see docs/tools.md for the rare inside-with-contact states), and
// never a sphere inside with no contact (tunnelled; the persistent contact of docs/tools.md).
// Transient states where a fast tool outruns the tissue are counted and printed. Label `long`.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "sweep_episodes.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

TEST(ToolSweep, TenThousandRandomPressesAndSlidesNeverTunnel) {
  const KidneyBuild k =
      build_kidney_model({.source = {.mesh = testing::require_data_file("kidney_left_hubmap_vhm.obj"),
                                     .unit = LengthUnit::Metre}});
  testing::KidneySweep sweep(k);
  testing::SweepCounts c;
  long episodes = 0;
  const bool verbose = std::getenv("MEDSPRING_SWEEP_VERBOSE") != nullptr;
  for (int e = 0; e < 10000; ++e) {
    const testing::SweepEpisode ep = sweep.draw();
    const bool ran = sweep.run(ep, c, [&](int leg, const Vec3& at) {
      const ToolState& st = sweep.tools().contact().state(sweep.probe());
      if (verbose)
        std::printf(
            "episode %d leg %d node %d step %.2f depth %.2f pen %.3f tri %.3f contacts %ld inside %d w "
            "%.3f\n",
            e, leg, static_cast<int>(ep.node), ep.step,
            (ep.x + testing::KidneySweep::R * ep.normal - ep.pressed).norm(), st.penetration,
            st.triangle_penetration, static_cast<long>(st.contacts), st.inside ? 1 : 0, sweep.inside(at));
    });
    if (ran) ++episodes;
  }
  std::printf(
      "%ld episodes, %ld updates (%ld in contact): centre inside the surface at the end of a move %ld times, "
      "after the 8 ms hold %ld times (%ld of them without contact); missed contacts %ld; contact kept from "
      "inside in %ld updates\n",
      episodes, c.updates, c.in_contact, c.transient_inside, c.inside_after_hold, c.lost, c.missed,
      c.persistent);
  EXPECT_EQ(sweep.failed_updates(), 0);
  EXPECT_GT(episodes, 9000);
  EXPECT_GT(c.in_contact, c.updates / 4);
  EXPECT_EQ(c.missed, 0);
  // No tunnelling: never a sphere inside the organ without contact. Before the persistent contact
  // (docs/tools.md), episodes 1112 and 2021 -- a deep press then a slide at 0.75-1 R per update -- ended
  // so; kidney_tool_test.cpp replays both.
  EXPECT_EQ(c.lost, 0);
  // a centre inside the surface while in contact: deep indentations (concave regions, slides along the
  // tangent plane) stretch the coarse triangles into flat tents that cut the sphere although every
  // node stays outside it (docs/tools.md); rare, and never with the contact lost
  EXPECT_LT(c.inside_after_hold, episodes / 100);
  EXPECT_EQ(sweep.sim().state().warnings.total(), 0u);
}

}  // namespace
}  // namespace medspring
