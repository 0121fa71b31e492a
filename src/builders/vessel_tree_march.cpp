// The watertight surface of a vessel tree from a mesh or a mask marched to the input's wall
// (docs/vessels.md).
#include "vessel_tree_march.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/geometry/polyline.hpp"
#include "medspring/meshing/mesh_repair.hpp"
#include "medspring/meshing/mesh_union.hpp"
#include "medspring/meshing/surface_distance.hpp"
#include "medspring/models/smrm_vessel.hpp"

namespace medspring::builders_detail {

// --blend from a mesh or a mask: the watertight surface's nodes marched to the input's wall (the §5.6
// spokes of the single vessel). A node moves along the ray from the closest point of the nearest branch
// axis through it, to the first hit within 4 local radii; end-cap nodes (a ray within 72.5 degrees of
// the axis) and misses stay. Null when the marched surface would intersect itself (then the circles
// stay, with a warning).
std::shared_ptr<SmrmTree> marched_tree(const CenterlineTree& ct, const SmrmTreeSettings& ts,
                                       const SmrmTree& tree, const SurfaceMesh& input, VesselSummary& s,
                                       bool refine) {
  SurfaceMesh m{tree.rest_surface(), tree.faces()};
  Index moved = 0, missed = 0, caps = 0;
  for (Index k = 0; k < m.num_vertices(); ++k) {
    const Vec3 p = m.V.row(k).transpose();
    double best = std::numeric_limits<double>::infinity();
    Vec3 a = Vec3::Zero(), t = Vec3::UnitX();
    double r_loc = 0.0;
    for (Index b = 0; b < tree.num_branches(); ++b) {
      const SmrmVessel& v = tree.branch_vessel(b);
      const MatX3& C = v.rest_atoms();
      const PolylinePoint q = closest_point_on_polyline(C, p);
      if (q.distance >= best) continue;
      const Index i = std::min<Index>(q.segment, static_cast<Index>(C.rows()) - 2);
      const double lam = q.segment > i ? 1.0 : q.lambda;
      best = q.distance;
      const Vec3 c0 = C.row(i).transpose(), c1 = C.row(i + 1).transpose();
      a = (1.0 - lam) * c0 + lam * c1;
      t = (c1 - c0).normalized();
      r_loc = (1.0 - lam) * v.atom_radius()[i] + lam * v.atom_radius()[i + 1];
    }
    const Vec3 d = p - a;
    if (d.norm() < 1e-9 || std::abs(d.normalized().dot(t)) > 0.3) {
      ++caps;
      continue;
    }
    const Vec3 w = d.normalized();
    const double hit = first_ray_hit(input, a, w, 4.0 * r_loc);
    if (std::isfinite(hit)) {
      m.V.row(k) = (a + hit * w).transpose();
      ++moved;
    } else {
      ++missed;
    }
  }
  // Where the marched surface crosses itself (a junction's crotch; at a tight bend of a wiggly axis, where
  // long rays of two tilted rings cross), the nodes of the crossing faces take, in turn: the input's
  // nearest point to their circle position (the wall next to them rather than the far wall the ray
  // reached), then halfway back towards the circle, a few rounds, then the circle itself (the union's
  // surface). A step that leaves a zero-area triangle (two nodes on one place) is undone.
  const MatX3& circle = tree.rest_surface();
  Index to_nearest = 0, halved = 0, kept = 0, self = 0;
  std::vector<char> stage(static_cast<std::size_t>(m.num_vertices()), 0);  // 0 marched, 1 nearest, 2 halved
  auto crossing = [&](std::vector<Index>& bad) {                           // false: a degenerate triangle
    try {
      bad = self_intersecting_faces(m, "marched vessel tree surface");
      return true;
    } catch (const InvalidInput&) {
      return false;
    }
  };
  MatX3 target = m.V;  // a node part of the way: the crossing place it comes from
  std::vector<Index> bad;
  bool ok = crossing(bad);
  for (int round = 0; ok && !bad.empty() && round < 24; ++round) {
    std::vector<Index> nodes;
    for (Index f : bad)
      for (int c = 0; c < 3; ++c)
        if (m.V.row(m.F(f, c)) != circle.row(m.F(f, c))) nodes.push_back(m.F(f, c));
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    if (nodes.empty()) break;
    const MatX3 before = m.V;
    const bool last = round >= 16;  // the old rule at the end: back to the circle
    std::vector<Index> first;
    for (Index v : nodes)
      if (stage[static_cast<std::size_t>(v)] == 0 && !last) first.push_back(v);
    MatX3 P(static_cast<Index>(first.size()), 3);
    for (std::size_t q = 0; q < first.size(); ++q) P.row(static_cast<Index>(q)) = circle.row(first[q]);
    const MatX3 near = first.empty() ? MatX3() : closest_points_on_surface(P, input);
    std::size_t q = 0;
    for (Index v : nodes) {
      char& st = stage[static_cast<std::size_t>(v)];
      if (last) {
        m.V.row(v) = circle.row(v);
      } else if (st == 0) {
        m.V.row(v) = near.row(static_cast<Index>(q++));
        st = 1;
      } else {
        target.row(v) = m.V.row(v);
        m.V.row(v) = circle.row(v) + 0.5 * (m.V.row(v) - circle.row(v));
        st = 2;
      }
    }
    if (!first.empty()) {  // nodes that took one place (the nearest point of two is a vertex or an edge):
                           // halfway from the circle to their marched hit instead
      for (Index f = 0; f < m.num_faces(); ++f) {
        const Vec3 a = m.V.row(m.F(f, 0)).transpose(), b = m.V.row(m.F(f, 1)).transpose(),
                   c = m.V.row(m.F(f, 2)).transpose();
        const double e2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
        if ((b - a).cross(c - a).norm() > 1e-6 * e2) continue;
        for (int k = 0; k < 3; ++k) {
          const Index v = m.F(f, k);
          if (stage[static_cast<std::size_t>(v)] != 1 || before.row(v) == m.V.row(v)) continue;
          target.row(v) = before.row(v);
          m.V.row(v) = circle.row(v) + 0.5 * (before.row(v) - circle.row(v));
          stage[static_cast<std::size_t>(v)] = 2;
        }
      }
    }
    ok = crossing(bad);
    if (!ok) {  // two nodes on one place: undo this round, and take the circle for these nodes
      m.V = before;
      for (Index v : nodes) m.V.row(v) = circle.row(v);
      ok = crossing(bad);
    }
  }
  // the nodes part of the way: bisected towards their target, as far as the surface stays simple
  for (int round = 0; ok && bad.empty() && round < 6; ++round) {
    const MatX3 safe = m.V;
    std::vector<Index> part;
    for (Index v = 0; v < m.num_vertices(); ++v)
      if (stage[static_cast<std::size_t>(v)] == 2 && m.V.row(v) != circle.row(v)) {
        part.push_back(v);
        m.V.row(v) = 0.5 * (m.V.row(v) + target.row(v));
      }
    if (part.empty()) break;
    std::vector<Index> cross;
    for (int pass = 0; pass < 4; ++pass) {  // the nodes of crossing faces go back to their safe place
      if (!crossing(cross)) {
        for (Index v : part) m.V.row(v) = safe.row(v);
        cross.clear();
        break;
      }
      if (cross.empty()) break;
      for (Index f : cross)
        for (int c = 0; c < 3; ++c) {
          const Index v = m.F(f, c);
          if (m.V.row(v) != safe.row(v)) {
            target.row(v) = m.V.row(v);
            m.V.row(v) = safe.row(v);
          }
        }
    }
    if (!crossing(cross) || !cross.empty()) m.V = safe;
  }
  for (Index v = 0; v < m.num_vertices(); ++v) {
    if (stage[static_cast<std::size_t>(v)] == 0) continue;
    if (m.V.row(v) == circle.row(v))
      ++kept;
    else if (stage[static_cast<std::size_t>(v)] == 1)
      ++to_nearest;
    else
      ++halved;
  }
  if (!ok) {
    s.warnings.push_back(
        "the watertight surface was not marched to the input's wall (marched nodes on one place: a "
        "zero-area triangle); it keeps the skeleton's circular cross-sections");
    return nullptr;
  }
  self = static_cast<Index>(bad.size());
  if (self > 0) {
    s.warnings.push_back(
        cat("the watertight surface was not marched to the input's wall: it would intersect "
            "itself (",
            self, " triangles); it keeps the skeleton's circular cross-sections"));
    return nullptr;
  }
  moved -= kept + to_nearest + halved;
  s.notes.push_back(cat("watertight surface marched to the input's wall: ", moved,
                        " nodes moved along their ray, ", missed, " without a hit within 4 radii, ", caps,
                        " on the end caps; where the marched "
                        "surface crossed itself ",
                        to_nearest, " took the input's nearest point, ", halved, " went part of the way, ",
                        kept, " kept the circle"));
  // the nodes evened out along the wall and put on it (the marched rays of an off-centre axis leave the
  // wall between them uncovered at a bulge, and the nodes that stopped part of the way off it)
  const WallFit fit = fit_to_wall(m, input, 8);
  s.notes.push_back(cat("watertight surface fitted to the input's wall: ", fit.rounds,
                        " rounds of a tangential umbrella step and the closest wall point; ", fit.held,
                        " nodes held back in the last round (their faces would cross or fold); ", fit.pulled,
                        " nodes pulled onto input vertices the surface missed by more than 0.5 mm"));
  // then finer where the rings are far apart (the wall bulges between them): every edge longer than the
  // spoke spacing at the mean atom radius, x 1.5, split and fitted again
  if (refine) {
    double rsum = 0.0;
    Index ra = 0;
    for (Index b = 0; b < tree.num_branches(); ++b) {
      rsum += tree.branch_vessel(b).atom_radius().sum();
      ra += static_cast<Index>(tree.branch_vessel(b).atom_radius().size());
    }
    const double max_edge = 1.5 * 2.0 * std::numbers::pi * (rsum / static_cast<double>(ra)) /
                            static_cast<double>(ts.vessel.spokes);
    const Index added = refine_long_edges(m, max_edge);
    const WallFit fine = fit_to_wall(m, input, 8);
    s.notes.push_back(cat("edges longer than ", max_edge, " mm split (", added,
                          " nodes added) and fitted again: ", fine.rounds, " rounds, ", fine.held,
                          " nodes held back, ", fine.pulled, " pulled onto input vertices"));
  }
  s.surface_volume_mm3 = signed_volume(m.V, m.F);
  return std::make_shared<SmrmTree>(ct, ts, m);
}

}  // namespace medspring::builders_detail
