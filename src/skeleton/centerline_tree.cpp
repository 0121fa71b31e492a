// The tree skeleton (docs/vessels.md, "Trees from a mesh or a segmentation"): §3 distance mapping with
// every endpoint, grown as one tree from the root (paths end where they meet it: the junctions).
#include "medspring/skeleton/centerline_tree.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "centerline_stages.hpp"
#include "medspring/core/check.hpp"
#include "medspring/skeleton/distance_transform.hpp"

namespace medspring {

using namespace skeleton_detail;

namespace {

// Multi-source Dijkstra over the voxel graph, grown incrementally: add() puts nodes at distance 0 and
// relaxes (distances only decrease). `step(w)` is the cost factor of entering w (1: geodesic length).
struct Field {
  const Graph* g = nullptr;
  std::vector<double> dist;
  std::vector<Index> parent;  // towards the nearest source (-1 at a source)
  std::vector<Index> source;  // the nearest source
  template <class Step>
  void add(const std::vector<Index>& src, Step step) {
    if (dist.empty()) {
      dist.assign(static_cast<std::size_t>(g->size()), kInf);
      parent.assign(dist.size(), -1);
      source.assign(dist.size(), -1);
    }
    DistQueue q;
    for (Index v : src) {
      dist[v] = 0.0;
      parent[v] = -1;
      source[v] = v;
      q.push(0.0, v);
    }
    while (!q.empty()) {
      const DistQueue::Entry e = q.pop();
      if (e.dist != dist[e.id]) continue;
      const Index wv = g->widx[e.id];
      for (const Offset& o : g->offsets) {
        const Index w = g->gid[wv + o.d];
        if (w < 0) continue;
        const double nd = e.dist + o.len * step(w);
        if (nd < dist[w]) {
          dist[w] = nd;
          parent[w] = e.id;
          source[w] = source[e.id];
          q.push(nd, w);
        }
      }
    }
  }
};

struct Grown {
  std::vector<Index> parent;  // skeleton voxels: the next voxel towards R (-1 at R and off the skeleton)
  std::vector<char> on;       // skeleton voxels
  std::vector<Index> leaves;  // accepted endpoints, in the order picked
  Index dropped = 0;
};

// The skeleton tree grown from R (docs/vessels.md, "Trees from a mesh or a segmentation"). Every new path
// runs from its endpoint down the medial ridge (step cost |step| (DFB_max / DFB)^p) to the NEAREST voxel
// already on the skeleton, so two outlets share the trunk by construction (a path ends where it meets
// it). The endpoint is the uncovered voxel farthest (geodesic length) from the skeleton; a path whose
// reach beyond the wall of the skeleton where it attaches is below branch_scale x its own radius is a
// spur (a bump of the wall, a cap's rim): dropped and its neighbourhood covered.
Grown grow_tree(const Graph& g, const std::vector<double>& dfb, double dfb_max, const Vec3& h_vec,
                const TreeSkeletonSettings& s, Index R) {
  const double h_max = h_vec.maxCoeff(), h_min = h_vec.minCoeff();
  const Index V = g.size();
  std::vector<double> ridge(V);
  for (Index v = 0; v < V; ++v) ridge[v] = std::pow(dfb_max / std::max(dfb[v], 1e-3 * h_min), s.ridge_power);
  Field cost, len;
  cost.g = &g;
  len.g = &g;
  const auto by_ridge = [&](Index w) { return ridge[w]; };
  const auto by_length = [](Index) { return 1.0; };
  Grown out;
  out.parent.assign(V, -1);
  out.on.assign(V, 0);
  out.on[R] = 1;
  cost.add({R}, by_ridge);
  len.add({R}, by_length);
  std::vector<char> covered(V, 0);
  // geodesic balls of radius ball_scale x DFB + 2 h around the voxels of a path
  std::vector<double> bd(V, kInf), brad(V, 0.0);
  std::vector<Index> touched;
  auto cover = [&](const std::vector<Index>& src) {
    DistQueue q;
    for (Index v : src) {
      bd[v] = 0.0;
      brad[v] = s.ball_scale * dfb[v] + 2.0 * h_max;
      touched.push_back(v);
      q.push(0.0, v);
    }
    while (!q.empty()) {
      const DistQueue::Entry e = q.pop();
      if (e.dist != bd[e.id]) continue;
      covered[e.id] = 1;
      const Index wv = g.widx[e.id];
      for (const Offset& o : g.offsets) {
        const Index w = g.gid[wv + o.d];
        if (w < 0) continue;
        const double nd = e.dist + o.len;
        if (nd <= brad[e.id] && nd < bd[w]) {
          bd[w] = nd;
          brad[w] = brad[e.id];
          touched.push_back(w);
          q.push(nd, w);
        }
      }
    }
    for (Index v : touched) bd[v] = kInf;
    touched.clear();
  };
  cover({R});
  for (;;) {
    Index E = -1;
    for (Index v = 0; v < V; ++v)
      if (!covered[v] && std::isfinite(len.dist[v]) && (E < 0 || len.dist[v] > len.dist[E])) E = v;
    if (E < 0) break;
    std::vector<Index> part;  // E up to (not including) the skeleton voxel J where it attaches
    Index J = E;
    for (; !out.on[J]; J = cost.parent[J]) part.push_back(J);
    const auto cj = g.ijk(J);
    auto dist_to_J = [&](Index v) {
      const auto c = g.ijk(v);
      return Vec3(h_vec[0] * static_cast<double>(c[0] - cj[0]), h_vec[1] * static_cast<double>(c[1] - cj[1]),
                  h_vec[2] * static_cast<double>(c[2] - cj[2]))
          .norm();
    };
    double r_part = 0.0;  // the path's own radius: its largest DFB outside J's ball
    for (Index p : part)
      if (dist_to_J(p) > dfb[J]) r_part = std::max(r_part, dfb[p]);
    const double beyond = len.dist[E] - dfb[len.source[E]];  // reach beyond the skeleton's wall
    const bool first = out.leaves.empty();
    // the local radius: the path's own or the skeleton's where it attaches, whichever is larger
    const double r_local = std::max({r_part, dfb[J], 2.0 * h_max});
    const bool accepted = first || beyond > s.branch_scale * r_local;
    if (accepted) {
      require(static_cast<Index>(out.leaves.size()) < s.max_endpoints, "mask: more than ", s.max_endpoints,
              " endpoints (a noisy or non-tubular object; smooth the mask)");
      out.leaves.push_back(E);
      Index below = J;
      for (auto it = part.rbegin(); it != part.rend(); ++it) {
        out.parent[*it] = below;
        out.on[*it] = 1;
        below = *it;
      }
      cost.add(part, by_ridge);
      len.add(part, by_length);
    } else {
      ++out.dropped;
    }
    cover(part);
  }
  return out;
}

// Re-roots the skeleton tree at `r` (reverses the parent links on the path from r to the old root).
void reroot(std::vector<Index>& parent, Index r) {
  Index prev = -1;
  for (Index v = r; v >= 0;) {
    const Index next = parent[v];
    parent[v] = prev;
    prev = v;
    v = next;
  }
}

// Ends extended to the input's caps (docs/vessels.md, "Trees from a mesh or a segmentation", step 5): from
// every end of the cut tree (the root's start, shared by every line; every leaf's end) straight on along
// the end's direction (the chord over the last max(r, 4 h) of the line) with the end's radius, in steps
// of h/4, as long as the axis point is inside the object and at least half of 16 points on the ring of
// kRingFraction x the end radius about it (in the plane normal to the direction) are: a flat cap (a scan's
// cut) is reached exactly, at an oblique cut the axis stops at the cut's centre, and a rounded tip is
// reached where a tube of the end radius fits it best (0.76 r beyond the base of a hemisphere: 0.24 r short
// of the apex, its rim 0.26 r outside). Object = the nearest voxel of the padded working grid (the
// isosurface at 0.5 on a flat face). At most 4 radii.
constexpr double kRingFraction = 0.65;

void extend_ends(TreeSkeleton& out, const MaskVolume& mask, const MaskVolume& work, Index pad) {
  const double step = out.h_min / 4;
  auto inside = [&](const Vec3& world) {
    const Vec3 c = mask.to_index(world) + Vec3::Constant(static_cast<double>(pad));
    const Index i = static_cast<Index>(std::lround(c.x())), j = static_cast<Index>(std::lround(c.y())),
                k = static_cast<Index>(std::lround(c.z()));
    if (i < 0 || j < 0 || k < 0 || i >= work.dims[0] || j >= work.dims[1] || k >= work.dims[2]) return false;
    return work.at(i, j, k) != 0;
  };
  // the extension of line c at its start (at_end false) or end: the points to add, tip last
  auto extension = [&](const Centerline& c, bool at_end, double& length) {
    length = 0.0;
    std::vector<Vec3> add;
    const Index n = c.size();
    if (n < 2) return add;
    const Index e = at_end ? n - 1 : 0, dir = at_end ? -1 : 1;
    const Vec3 q = c.points.row(e).transpose();
    const double r = c.radii[e];
    // the end's direction: the principal axis of the line's last max(2 r, 8 h) (at most half the line),
    // pointing out of the end (a short chord follows the smoothed voxel path's wiggle)
    const double span = std::max(2.0 * r, 8.0 * out.h_min);
    const double half = 0.5 * c.length();
    std::vector<Vec3> pts{q};
    double sa = 0.0;
    for (Index k = e; k + dir >= 0 && k + dir < n;) {
      sa += (c.points.row(k + dir) - c.points.row(k)).norm();
      k += dir;
      if (sa > std::min(span, half)) break;
      pts.push_back(c.points.row(k).transpose());
    }
    if (pts.size() < 3) return add;
    Vec3 mean = Vec3::Zero();
    for (const Vec3& p : pts) mean += p;
    mean /= static_cast<double>(pts.size());
    Mat3 cov = Mat3::Zero();
    for (const Vec3& p : pts) cov += (p - mean) * (p - mean).transpose();
    Vec3 t = Eigen::SelfAdjointEigenSolver<Mat3>(cov).eigenvectors().col(2);
    if (t.dot(q - pts.back()) < 0) t = -t;
    const Vec3 o = mean + (q - mean).dot(t) * t;  // the extension runs on the fitted axis, from q's foot
    const Vec3 u = t.unitOrthogonal(), v = t.cross(u);
    double s_ok = 0.0;
    for (double sv = step; sv <= 4.0 * r + step; sv += step) {
      const Vec3 p = o + sv * t;
      if (!inside(p)) break;
      int in = 0;
      for (int a = 0; a < 16; ++a) {
        const double phi = 2.0 * std::numbers::pi * a / 16.0;
        in += inside(p + kRingFraction * r * (std::cos(phi) * u + std::sin(phi) * v)) ? 1 : 0;
      }
      if (in < 8) break;
      s_ok = sv;
    }
    if (s_ok <= 0) return add;
    length = s_ok;
    const Index m = std::max<Index>(1, static_cast<Index>(std::ceil(s_ok / (out.h_min / 2) - 1e-9)));
    for (Index q2 = 1; q2 <= m; ++q2) add.push_back(o + (s_ok * static_cast<double>(q2) / m) * t);
    return add;
  };
  auto with = [](const Centerline& c, const std::vector<Vec3>& add, double r, bool at_end) {
    const Index n = c.size(), m = static_cast<Index>(add.size());
    Centerline x;
    x.name = c.name;
    x.points.resize(n + m, 3);
    x.radii.resize(n + m);
    const Index off = at_end ? 0 : m;
    x.points.middleRows(off, n) = c.points;
    x.radii.segment(off, n) = c.radii;
    for (Index q = 0; q < m; ++q) {
      const Index row = at_end ? n + q : m - 1 - q;  // at the start: the tip first
      x.points.row(row) = add[static_cast<std::size_t>(q)].transpose();
      x.radii[row] = r;
    }
    return x;
  };
  double len0 = 0.0;
  const std::vector<Vec3> root = extension(out.lines.front(), false, len0);
  const double r0 = out.lines.front().radii[0];
  double leaf_min = std::numeric_limits<double>::infinity(), leaf_max = 0.0;
  for (Centerline& c : out.lines) {
    double len = 0.0;
    const std::vector<Vec3> tip = extension(c, true, len);
    const double r_tip = c.radii[c.size() - 1];
    c = with(with(c, tip, r_tip, true), root, r0, false);
    leaf_min = std::min(leaf_min, len);
    leaf_max = std::max(leaf_max, len);
  }
  out.extended_root_mm = len0;
  out.extended_leaf_min_mm = leaf_min;
  out.extended_leaf_max_mm = leaf_max;
  out.notes.push_back(cat("ends extended to the input's caps with the end radius: the root by ", len0,
                          " mm, the leaves by ", leaf_min, "..", leaf_max, " mm"));
}

}  // namespace

TreeSkeleton extract_centerline_tree(const MaskVolume& mask, const TreeSkeletonSettings& s) {
  require_valid_volume(mask, "mask");
  require(
      s.ridge_power >= 0 && s.ball_scale > 0 && s.branch_scale >= 0 && s.max_endpoints >= 1 &&
          s.smoothing_sigma >= 0,
      "tree skeleton: bad settings (ridge_power >= 0, ball_scale > 0, branch_scale >= 0, max_endpoints >= 1, "
      "sigma >= 0)");
  TreeSkeleton out;
  const Vec3 h = mask.spacing;
  out.h_min = h.minCoeff();
  // padded working grid: 2 background voxels on every side
  constexpr Index P = 2;
  MaskVolume work;
  work.dims = {mask.dims[0] + 2 * P, mask.dims[1] + 2 * P, mask.dims[2] + 2 * P};
  work.spacing = h;
  work.direction = mask.direction;
  work.origin = mask.to_world(Vec3(-P, -P, -P));
  work.data.assign(work.size(), 0);
  for (Index k = 0; k < mask.dims[2]; ++k)
    for (Index j = 0; j < mask.dims[1]; ++j)
      for (Index i = 0; i < mask.dims[0]; ++i)
        if (mask.at(i, j, k) != 0) {
          work.at(i + P, j + P, k + P) = 1;
          ++out.object_voxels;
        }
  require(out.object_voxels > 0, "mask: no object voxels");
  Graph g;
  g.dims = work.dims;
  g.lo = {-P, -P, -P};
  g.offsets = make_offsets(26, h, g.dims);
  // the largest 26-connected component (ties: the first in raster order)
  std::vector<Index> comp(work.size(), -1);
  std::vector<Index> sizes;
  {
    std::vector<Index> stack;
    for (std::size_t w0 = 0; w0 < work.size(); ++w0) {
      if (!work.data[w0] || comp[w0] >= 0) continue;
      const Index c = static_cast<Index>(sizes.size());
      sizes.push_back(0);
      stack.push_back(static_cast<Index>(w0));
      comp[w0] = c;
      while (!stack.empty()) {
        const Index w = stack.back();
        stack.pop_back();
        ++sizes[static_cast<std::size_t>(c)];
        for (const Offset& o : g.offsets) {
          const Index u = w + o.d;
          if (work.data[static_cast<std::size_t>(u)] && comp[static_cast<std::size_t>(u)] < 0) {
            comp[static_cast<std::size_t>(u)] = c;
            stack.push_back(u);
          }
        }
      }
    }
  }
  out.components = static_cast<Index>(sizes.size());
  const Index keep = static_cast<Index>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
  if (out.components > 1)
    out.notes.push_back(
        cat("used the largest of ", out.components, " components (", sizes[keep], " voxels)"));
  for (std::size_t w = 0; w < work.size(); ++w)
    if (work.data[w] && comp[w] != keep) work.data[w] = 0;
  const DistanceField df = distance_from_boundary(work);
  g.gid.assign(work.size(), -1);
  for (std::size_t w = 0; w < work.size(); ++w)
    if (work.data[w]) {
      g.gid[w] = g.size();
      g.widx.push_back(static_cast<Index>(w));
    }
  const Index V = g.size();
  std::vector<double> dfb(V);
  for (Index v = 0; v < V; ++v) dfb[v] = df.dfb.data[static_cast<std::size_t>(g.widx[v])];
  const double dfb_max = *std::max_element(dfb.begin(), dfb.end());

  // §3.3 root: the far end of a double sweep; the tree grown from it; then re-rooted at the widest end
  // (the inlet of a vessel tree)
  std::vector<double> dfs;
  dijkstra(g, 0, dfs);
  Index R = argmax(dfs);
  Grown grown = grow_tree(g, dfb, dfb_max, h, s, R);
  std::vector<Index>& parent = grown.parent;
  if (!grown.leaves.empty()) {
    // the width of an end: the largest DFB on its path within 3 of its own (smallest) radii of the tip
    auto width = [&](Index e, bool from_root) {
      std::vector<Index> path;
      for (Index v = e; v >= 0; v = parent[v]) path.push_back(v);
      if (from_root) std::reverse(path.begin(), path.end());
      double l = 0.0, w = 0.0;
      for (std::size_t k = 0; k < path.size() && l <= 3.0 * std::max(w, out.h_min); ++k) {
        w = std::max(w, dfb[path[k]]);
        if (k + 1 < path.size()) l += std::sqrt(g.edge_len2(path[k], path[k + 1]));
      }
      return w;
    };
    Index widest = R;
    double best = width(grown.leaves.front(), true);  // R's end, walked from R
    for (Index e : grown.leaves) {
      const double w = width(e, false);
      if (w > best * (1.0 + 1e-9)) {
        best = w;
        widest = e;
      }
    }
    if (widest != R) {
      reroot(parent, widest);
      std::replace(grown.leaves.begin(), grown.leaves.end(), widest, R);
      R = widest;
    }
  }
  out.dropped = grown.dropped;

  // the skeleton's branches: voxel runs between the root, junctions (>= 2 children) and leaves
  std::vector<Index> children(V, 0);
  std::vector<char> on(V, 0);
  for (Index e : grown.leaves)
    for (Index v = e; v >= 0 && !on[v]; v = parent[v]) on[v] = 1;
  for (Index v = 0; v < V; ++v)
    if (on[v] && parent[v] >= 0) ++children[parent[v]];
  auto local_of = [&](Index v) {
    const auto c = g.ijk(v);  // input-grid index (may be -1.. at the padding)
    return Vec3(h[0] * static_cast<double>(c[0]), h[1] * static_cast<double>(c[1]),
                h[2] * static_cast<double>(c[2]));
  };
  // DFB at a local physical point (input grid): the largest of its cell's 8 voxel centres. The DFB peaks
  // on the medial ridge, so a trilinear value between ridge voxels falls up to half a voxel short.
  auto dfb_at = [&](const Vec3& p) {
    const Vec3 c = p.cwiseQuotient(h) + Vec3(P, P, P);
    double best = 0.0;
    for (int dk = 0; dk < 2; ++dk)
      for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di) {
          const Index i = std::clamp<Index>(static_cast<Index>(std::floor(c.x())) + di, 0, work.dims[0] - 1);
          const Index j = std::clamp<Index>(static_cast<Index>(std::floor(c.y())) + dj, 0, work.dims[1] - 1);
          const Index k = std::clamp<Index>(static_cast<Index>(std::floor(c.z())) + dk, 0, work.dims[2] - 1);
          best = std::max(best, df.dfb.at(i, j, k));
        }
    return best;
  };
  const double sigma = s.smoothing_sigma > 0 ? s.smoothing_sigma : 2.0 * out.h_min;
  // every root-to-leaf path cut into segments at the junctions; a segment is smoothed once (cache by its
  // lower end voxel), its two ends fixed, so shared prefixes stay identical
  std::vector<Curve> seg_curve;
  std::vector<Index> seg_of(V, -1);
  auto segment = [&](Index lo_end, Index hi_end) -> const Curve& {  // voxels lo_end (far) .. hi_end (near R)
    if (seg_of[lo_end] < 0) {
      Curve c;
      for (Index v = lo_end;; v = parent[v]) {
        c.push_back(local_of(v));
        if (v == hi_end) break;
      }
      std::reverse(c.begin(), c.end());
      double step = 0.0;
      if (c.size() >= 2) {
        c = resample_uniform(c, out.h_min / 2, step);
        c = smooth_gaussian(c, step, sigma);
      }
      seg_of[lo_end] = static_cast<Index>(seg_curve.size());
      seg_curve.push_back(std::move(c));
    }
    return seg_curve[static_cast<std::size_t>(seg_of[lo_end])];
  };
  for (Index e : grown.leaves) {
    std::vector<Index> stops{e};  // junctions and R on the way, leaf first
    for (Index v = parent[e]; v >= 0; v = parent[v])
      if (v == R || children[v] >= 2) stops.push_back(v);
    Curve line;
    for (std::size_t k = stops.size() - 1; k >= 1; --k) {
      const Curve& c = segment(stops[k - 1], stops[k]);
      line.insert(line.end(), line.empty() ? c.begin() : c.begin() + 1, c.end());
    }
    Centerline cl;
    cl.name = cat("path ", out.lines.size());
    cl.points.resize(static_cast<Index>(line.size()), 3);
    cl.radii.resize(static_cast<Index>(line.size()));
    for (std::size_t k = 0; k < line.size(); ++k) {
      cl.points.row(static_cast<Index>(k)) = (mask.origin + mask.direction * line[k]).transpose();
      cl.radii[static_cast<Index>(k)] = std::max(dfb_at(line[k]) - out.h_min / 2, out.h_min / 2);
    }
    out.lines.push_back(std::move(cl));
  }
  // Ends (D-8, adapted): the path's last voxels run off the axis to the farthest voxel of the tip, where
  // the DFB is that of the tip's wall. Both ends of the tree (the root's start, every leaf's end) are cut
  // one radius of the vessel short of the tip: r_ref = the 75th percentile of the radii on the end's half
  // of the line, the cut at the first point (walking inwards) at least r_ref from the tip along the line.
  // The root's cut is the same on every line (shared prefix).
  auto cut_index = [&](const Centerline& c, bool at_end) {
    const Index n = c.size();
    VecX sa = VecX::Zero(n);  // arc length from the end
    for (Index k = 1; k < n; ++k) {
      const Index a = at_end ? n - k : k - 1, b = at_end ? n - 1 - k : k;
      sa[b] = sa[a] + (c.points.row(b) - c.points.row(a)).norm();
    }
    const double half = 0.5 * (at_end ? sa[0] : sa[n - 1]);
    std::vector<double> rr;
    for (Index k = 0; k < n; ++k)
      if (sa[k] <= half) rr.push_back(c.radii[k]);
    std::sort(rr.begin(), rr.end());
    const double r_ref =
        rr.empty() ? 0.0 : rr[(3 * rr.size()) / 4 < rr.size() ? (3 * rr.size()) / 4 : rr.size() - 1];
    for (Index k = 0; k < n; ++k) {
      const Index b = at_end ? n - 1 - k : k;
      const double cut = r_ref + out.h_min;
      if ((sa[b] >= cut && (c.radii[b] >= 0.9 * r_ref || sa[b] >= 2.0 * cut)) || sa[b] >= half) return b;
    }
    return at_end ? n - 1 : Index{0};
  };
  if (!out.lines.empty()) {
    // the root's cut stays before the first junction: within the prefix every line shares
    Index common = out.lines.front().size() - 1;
    for (const Centerline& c : out.lines) {
      Index k = 0;
      while (k < std::min(c.size(), out.lines.front().size()) &&
             c.points.row(k) == out.lines.front().points.row(k))
        ++k;
      common = std::min(common, k - 1);
    }
    const Index r0 = std::max<Index>(0, std::min(cut_index(out.lines.front(), false), common - 1));
    for (Centerline& c : out.lines) {
      const Index e0 = std::max(cut_index(c, true), r0 + 1);
      Centerline t;
      t.name = c.name;
      t.points = c.points.middleRows(r0, e0 - r0 + 1);
      t.radii = c.radii.segment(r0, e0 - r0 + 1);
      c = std::move(t);
    }
    if (s.extend_ends) extend_ends(out, mask, work, P);
  }
  out.endpoints = static_cast<Index>(out.lines.size());
  {  // a vessel is longer than it is wide: a skeleton shorter than its own diameter is only a spur
    double longest = 0.0, r_max = 0.0;
    for (const Centerline& c : out.lines) {
      longest = std::max(longest, c.length());
      r_max = std::max(r_max, c.radii.maxCoeff());
    }
    require(longest >= 2.0 * r_max, "mask: the skeleton is only a spur (", longest, " mm long, radius ",
            r_max, " mm): the object (", out.object_voxels, " voxels) is a blob, not a vessel");
  }
  out.notes.push_back(cat(out.endpoints, " endpoint(s) from the root; ", out.dropped,
                          " side path(s) dropped as spurs (reaching less than ", s.branch_scale,
                          " x their radius beyond the wall)"));
  return out;
}

}  // namespace medspring
