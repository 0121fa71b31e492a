// The seeded presses and slides of a sphere on the real kidney (docs/tools.md, "No tunnelling"), shared by
// the 10^4-episode sweep (sweep_test.cpp, label long) and the regression tests of single episodes
// (kidney_tool_test.cpp). Episode e draws its site, direction, depths and step from the same seeded
// generator whatever episodes run before it, so an episode found by the sweep replays alone.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <vector>

#include "medspring/builders/kidney_build.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/sim/tool_sim.hpp"

namespace medspring::testing {

inline double winding(const MatX3& S, const MatX3i& F, const Vec3& q) {
  double w = 0;
  for (Index t = 0; t < F.rows(); ++t) {
    const Vec3 a = S.row(F(t, 0)).transpose() - q, b = S.row(F(t, 1)).transpose() - q,
               c = S.row(F(t, 2)).transpose() - q;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    w += 2 * std::atan2(a.dot(b.cross(c)), la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb);
  }
  return w / (4 * std::numbers::pi);
}

struct SweepEpisode {
  Index node = 0;
  Vec3 x, normal, start, pressed, slid;
  double step = 0;  // mm per update
};

struct SweepCounts {
  long updates = 0, transient_inside = 0, inside_after_hold = 0, lost = 0, missed = 0, in_contact = 0;
  long persistent = 0;   // updates whose contacts were kept from the nearest surface (ToolState::inside)
  double max_force = 0;  // largest reaction on the tool (N)
};

// The sweep: a 6 mm sphere, friction 0.2, on the hybrid kidney; episodes drawn from seed 20261125.
class KidneySweep {
 public:
  static constexpr double R = 6.0;

  explicit KidneySweep(const KidneyBuild& k)
      : kid_(*k.model), sim_(k.model, {.normals = false}), tools_(sim_, {.friction = 0.2}), rng_(20261125) {
    vertex_normals(kid_.rest_surface(), kid_.faces(), N_);
    orient_ = winding(kid_.rest_surface(), kid_.faces(), kid_.rest_surface().colwise().mean()) > 0 ? 1 : -1;
    probe_ = tools_.add_tool(Tool::sphere(R), Pose{Vec3(1e4, 0, 0), Quat::Identity()});
  }

  // Draws the next episode (episode number = episodes drawn before it).
  SweepEpisode draw() {
    std::uniform_real_distribution<double> u(0, 1);
    std::uniform_int_distribution<Index> pick(0, kid_.num_surface_nodes() - 1);
    SweepEpisode e;
    e.node = pick(rng_);
    e.x = kid_.rest_surface().row(e.node).transpose();
    e.normal = orient_ * N_.row(e.node).transpose().normalized();
    const Vec3 t1 = e.normal.unitOrthogonal(), t2 = e.normal.cross(t1);
    const double phi = 2 * std::numbers::pi * u(rng_);
    const Vec3 slide_dir = std::cos(phi) * t1 + std::sin(phi) * t2;
    e.start = e.x + (R + 0.5 + 2 * u(rng_)) * e.normal;
    e.pressed = e.x + (R - 1.0 * R * u(rng_)) * e.normal;  // down to the centre on the rest surface
    e.slid = e.pressed + 3 * R * u(rng_) * slide_dir;
    e.step = R * (0.05 + 0.95 * u(rng_));  // mm per update, <= R
    return e;
  }
  // Draws episodes up to and including number `e`; returns that one.
  SweepEpisode draw_episode(int e) {
    SweepEpisode ep;
    for (int i = 0; i <= e; ++i) ep = draw();
    return ep;
  }

  double inside(const Vec3& q) const { return orient_ * winding(sim_.global_surface(), kid_.faces(), q); }

  // Runs one episode from rest: press, slide, lift (each move split into updates of at most `step`), an
  // 8 ms hold after the press and after the slide. Returns false when the start overlaps the organ
  // (skipped). `verbose(leg)` is called when the centre is inside the deformed surface after a hold.
  template <class OnInside>
  bool run(const SweepEpisode& ep, SweepCounts& c, OnInside&& on_inside_after_hold) {
    tools_.set_pose(probe_, Pose{ep.start, Quat::Identity()});
    tools_.reset();
    // skip starts that overlap another part of the organ (a concave region): the tool must start outside
    if (inside(ep.start) >= 0.5) return false;
    const Vec3 legs[3] = {ep.pressed, ep.slid, ep.start};
    Vec3 at = ep.start;
    for (int leg = 0; leg < 3; ++leg) {
      const Vec3 target = legs[leg];
      const int moves = std::max(1, static_cast<int>(std::ceil((target - at).norm() / ep.step)));
      const Vec3 from = at;
      const int hold = leg < 2 ? 16 : 2;  // 8 ms for the tissue to catch up with the tool
      for (int i = 1; i <= moves + hold; ++i) {
        at = from + std::min(1.0, static_cast<double>(i) / moves) * (target - from);
        tools_.set_pose(probe_, Pose{at, Quat::Identity()});
        const bool touching = nearest_node(at) < R;  // a surface node inside the tool at the update's start
        if (!tools_.update().ok()) ++failed_;
        ++c.updates;
        const ToolState& st = tools_.contact().state(probe_);
        if (touching && st.contacts == 0) ++c.missed;  // detection failed
        if (st.contacts > 0) ++c.in_contact;
        if (st.inside) ++c.persistent;
        c.max_force = std::max(c.max_force, st.force.norm());
        if (std::getenv("MEDSPRING_SWEEP_TRACE"))
          std::printf("leg %d i %d contacts %ld inside %d force %.3f pen %.3f tri %.3f\n", leg, i,
                      (long)st.contacts, (int)st.inside, st.force.norm(), st.penetration,
                      st.triangle_penetration);
        if (i == moves && inside(at) >= 0.5) ++c.transient_inside;
      }
      // after the hold, the tool must be on the outside of the deformed surface
      if (leg < 2 && inside(at) >= 0.5) {
        ++c.inside_after_hold;
        if (tools_.contact().state(probe_).contacts == 0) ++c.lost;  // inside and no contact: tunnelled
        on_inside_after_hold(leg, at);
      }
    }
    return true;
  }

  const Simulation& sim() const { return sim_; }
  const ToolSimulation& tools() const { return tools_; }
  Index probe() const { return probe_; }
  long failed_updates() const { return failed_; }

 private:
  double nearest_node(const Vec3& c) const {
    double d = 1e300;
    for (Index j = 0; j < sim_.global_surface().rows(); ++j)
      d = std::min(d, (sim_.global_surface().row(j).transpose() - c).norm());
    return d;
  }

  const HybridKidney& kid_;
  Simulation sim_;
  ToolSimulation tools_;
  std::mt19937 rng_;
  MatX3 N_;
  double orient_ = 1;
  Index probe_ = 0;
  long failed_ = 0;
};

}  // namespace medspring::testing
