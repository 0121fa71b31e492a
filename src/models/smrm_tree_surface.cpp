// The closed path tubes of a vessel tree, whose union is its watertight junction surface (issue 17,
// docs/vessels.md). Engine layers only: the union itself is made by the builders (CGAL, meshing layer).
#include <algorithm>
#include <cmath>
#include <numbers>

#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/medial/frames.hpp"
#include "medspring/models/smrm_tree.hpp"

namespace medspring {

namespace {

// Unit direction of a line over its first (start) or last (end) `span` mm of arc.
Vec3 end_direction(const Centerline& c, bool at_end, double span) {
  const VecX s = c.arc_length();
  const Index n = c.size();
  if (at_end) {
    Index k = n - 2;
    while (k > 0 && s[n - 1] - s[k] < span) --k;
    return (c.points.row(n - 1) - c.points.row(k)).normalized().transpose();
  }
  Index k = 1;
  while (k < n - 1 && s[k] < span) ++k;
  return (c.points.row(k) - c.points.row(0)).normalized().transpose();
}

}  // namespace

std::vector<SurfaceMesh> tree_path_tubes(const CenterlineTree& tree, Index spokes, double spacing,
                                         std::vector<std::vector<Index>>* path_branches) {
  require(std::isfinite(spacing) && spacing > 0, "vessel tree tubes: spacing must be > 0 mm (got ", spacing,
          ")");
  require(spokes >= 3, "vessel tree tubes: spokes must be >= 3 (got ", spokes, ")");
  const Index nb = static_cast<Index>(tree.branches.size());
  require(nb >= 1, "vessel tree tubes: the tree has no branches");
  std::vector<std::vector<Index>> kids(static_cast<std::size_t>(nb));
  for (Index b = 1; b < nb; ++b) {
    const Index p = tree.branches[static_cast<std::size_t>(b)].parent;
    require(p >= 0 && p < b, "vessel tree tubes: branch ", b, ": parent ", p, " must be an earlier branch");
    kids[static_cast<std::size_t>(p)].push_back(b);
  }
  // Paths: from a start branch, follow the best-aligned child at every junction.
  std::vector<std::vector<Index>> paths;
  std::vector<Index> starts{0};
  for (std::size_t q = 0; q < starts.size(); ++q) {
    std::vector<Index> path{starts[q]};
    for (;;) {
      const Index b = path.back();
      const auto& ks = kids[static_cast<std::size_t>(b)];
      if (ks.empty()) break;
      const Centerline& pl = tree.branches[static_cast<std::size_t>(b)].line;
      const double span = pl.radii[pl.size() - 1];
      const Vec3 te = end_direction(pl, true, span);
      Index best = ks.front();
      double best_dot = -2.0;
      for (Index c : ks) {
        const double d = te.dot(end_direction(tree.branches[static_cast<std::size_t>(c)].line, false, span));
        if (d > best_dot) {
          best_dot = d;
          best = c;
        }
      }
      for (Index c : ks)
        if (c != best) starts.push_back(c);
      path.push_back(best);
    }
    paths.push_back(std::move(path));
  }
  std::vector<SurfaceMesh> tubes;
  for (const std::vector<Index>& path : paths) {
    // The path's centerline: its branches end to end (a child starts at its parent's last point).
    Index np = 0;
    for (std::size_t k = 0; k < path.size(); ++k)
      np += tree.branches[static_cast<std::size_t>(path[k])].line.size() - (k > 0 ? 1 : 0);
    Centerline line;
    line.points.resize(np, 3);
    line.radii.resize(np);
    Index o = 0;
    for (std::size_t k = 0; k < path.size(); ++k) {
      const Centerline& c = tree.branches[static_cast<std::size_t>(path[k])].line;
      const Index first = k > 0 ? 1 : 0, cnt = c.size() - first;
      line.points.middleRows(o, cnt) = c.points.middleRows(first, cnt);
      line.radii.segment(o, cnt) = c.radii.segment(first, cnt);
      o += cnt;
    }
    line = deduplicate(line, 1e-3);
    const double L = line.length();
    const Index rings = std::max<Index>(3, static_cast<Index>(std::lround(L / spacing)) + 1);
    Centerline c = resample(line, rings);
    if (tree.branches[static_cast<std::size_t>(path.front())].parent >= 0) {
      // Starts at a junction: narrow the part inside the parent (within the junction radius of the start).
      const double rj = c.radii[0];
      const VecX s = c.arc_length();
      Index k = 0;
      while (k + 1 < rings && s[k] < rj) ++k;
      const double r_out = c.radii[k];
      for (Index i = 0; i < k; ++i) c.radii[i] = std::min(c.radii[i], r_out);
    }
    const FrameReference ref = make_frame_reference(c.points, FrameSettings{});
    const Index M = spokes;
    SurfaceMesh t;
    t.V.resize(rings * M + 2, 3);
    for (Index i = 0; i < rings; ++i)
      for (Index j = 0; j < M; ++j) {
        const double th = 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(M);
        t.V.row(i * M + j) =
            c.points.row(i) + c.radii[i] * (std::cos(th) * ref.F0.u.row(i) + std::sin(th) * ref.F0.v.row(i));
      }
    const Index c0 = rings * M, c1 = c0 + 1;
    t.V.row(c0) = c.points.row(0);
    t.V.row(c1) = c.points.row(rings - 1);
    const MatX3i G = tube_grid_faces(rings, M);
    t.F.resize(G.rows() + 2 * M, 3);
    t.F.topRows(G.rows()) = G;
    Index f = static_cast<Index>(G.rows());
    const Index last = (rings - 1) * M;
    for (Index j = 0; j < M; ++j) {  // caps, opposite to the tube's traversal of the end rings
      t.F.row(f++) << c0, (j + 1) % M, j;
      t.F.row(f++) << c1, last + j, last + (j + 1) % M;
    }
    if (signed_volume(t.V, t.F) < 0.0) t.F.col(1).swap(t.F.col(2));
    tubes.push_back(std::move(t));
  }
  if (path_branches) *path_branches = paths;
  return tubes;
}

}  // namespace medspring
