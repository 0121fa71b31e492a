// The tree skeleton (docs/vessels.md, "Trees from a mesh or a segmentation"): §3 distance mapping with
// every endpoint and junctions where the paths meet.
#include "medspring/skeleton/centerline_tree.hpp"

#include <algorithm>
#include <cmath>

#include "centerline_stages.hpp"
#include "medspring/core/check.hpp"
#include "medspring/skeleton/distance_transform.hpp"

namespace medspring {

using namespace skeleton_detail;

namespace {

// Penalised Dijkstra from R over the whole graph (§3.4 PenalizedDijkstra): the parent of every node.
std::vector<Index> penalized_parents(const Graph& g, const std::vector<double>& dfb, double dfb_max,
                                     const TreeSkeletonSettings& s, Index R) {
  const Index V = g.size();
  std::vector<double> dist(V, kInf), penalty(V);
  std::vector<Index> parent(V, -1);
  for (Index v = 0; v < V; ++v)
    penalty[v] = 1.0 + s.penalty_lambda * std::pow(1.0 - dfb[v] / dfb_max, s.penalty_power);
  dist[R] = 0.0;
  DistQueue queue;
  queue.push(0.0, R);
  while (!queue.empty()) {
    const DistQueue::Entry e = queue.pop();
    if (e.dist != dist[e.id]) continue;
    const Index wv = g.widx[e.id];
    for (const Offset& o : g.offsets) {
      const Index w = g.gid[wv + o.d];
      if (w < 0) continue;
      const double nd = e.dist + o.len * penalty[w];
      if (nd < dist[w]) {
        dist[w] = nd;
        parent[w] = e.id;
        queue.push(nd, w);
      }
    }
  }
  return parent;
}

struct Picked {
  std::vector<Index> leaves;  // accepted endpoints, in the order picked
  Index dropped = 0;
};

// TEASAR endpoints: the farthest uncovered node, its path to the skeleton, the ball around it covered.
Picked pick_endpoints(const Graph& g, const std::vector<double>& dfb, const std::vector<double>& dfs,
                      std::vector<Index>& parent, const Vec3& h_vec, const TreeSkeletonSettings& s, Index R) {
  const double h_max = h_vec.maxCoeff();
  const Index V = g.size();
  std::vector<char> covered(V, 0), on_tree(V, 0);
  std::vector<double> dist(V, kInf), rad(V, 0.0);
  std::vector<Index> src_of(V, -1);
  std::vector<Index> touched;
  on_tree[R] = 1;
  std::vector<Index> tree_nodes{R};
  Picked out;
  std::vector<Index> owner(V, -1);  // the skeleton voxel whose ball covers a voxel (accepted paths only)
  auto cover = [&](const std::vector<Index>& src, bool attach) {  // geodesic balls: ball_scale DFB + h
    DistQueue q;
    for (Index v : src) {
      dist[v] = 0.0;
      rad[v] = s.ball_scale * dfb[v] + 2.0 * h_max;
      src_of[v] = v;
      touched.push_back(v);
      q.push(0.0, v);
    }
    while (!q.empty()) {
      const DistQueue::Entry e = q.pop();
      if (e.dist != dist[e.id]) continue;
      covered[e.id] = 1;
      if (attach && owner[e.id] < 0) owner[e.id] = src_of[e.id];
      const Index wv = g.widx[e.id];
      for (const Offset& o : g.offsets) {
        const Index w = g.gid[wv + o.d];
        if (w < 0) continue;
        const double nd = e.dist + o.len;
        if (nd <= rad[e.id] && nd < dist[w]) {
          dist[w] = nd;
          rad[w] = rad[e.id];
          src_of[w] = src_of[e.id];
          touched.push_back(w);
          q.push(nd, w);
        }
      }
    }
    for (Index v : touched) dist[v] = kInf;
    touched.clear();
  };
  cover({R}, true);
  for (;;) {
    Index E = -1;
    for (Index v = 0; v < V; ++v)
      if (!covered[v] && std::isfinite(dfs[v]) && (E < 0 || dfs[v] > dfs[E])) E = v;
    if (E < 0) break;
    std::vector<Index> part;  // E up to (not including) the first node already on the skeleton
    Index v = E;
    // up to the skeleton, or into the ball of a skeleton voxel (then straight to that voxel: penalised
    // paths to two branches can run side by side along a wide trunk before they meet)
    for (; v >= 0 && !on_tree[v] && owner[v] < 0; v = parent[v]) part.push_back(v);
    if (v >= 0 && !on_tree[v]) v = owner[v];
    const Index junction = v;
    double r_part = 0.0;
    for (Index p : part) r_part = std::max(r_part, dfb[p]);
    // How far the new path reaches beyond the skeleton's wall: the straight distance from E to the
    // nearest skeleton voxel minus that voxel's DFB (a path length would count the long parallel runs
    // that penalised paths to two neighbouring tip voxels can take before they meet).
    const bool first = out.leaves.empty();
    double beyond = kInf;
    if (!first) {
      const auto ce = g.ijk(E);
      for (Index t : tree_nodes) {
        const auto ct = g.ijk(t);
        const Vec3 d(h_vec[0] * static_cast<double>(ce[0] - ct[0]),
                     h_vec[1] * static_cast<double>(ce[1] - ct[1]),
                     h_vec[2] * static_cast<double>(ce[2] - ct[2]));
        beyond = std::min(beyond, d.norm() - dfb[t]);
      }
    }
    (void)junction;
    const bool accepted = first || beyond > s.branch_scale * std::max(r_part, 2.0 * h_max);
    if (accepted) {
      require(static_cast<Index>(out.leaves.size()) < s.max_endpoints, "mask: more than ", s.max_endpoints,
              " endpoints (a noisy or non-tubular object; smooth the mask)");
      out.leaves.push_back(E);
      if (!part.empty() && v >= 0) parent[part.back()] = v;  // joins the skeleton at v
      for (Index p : part) {
        on_tree[p] = 1;
        tree_nodes.push_back(p);
      }
    } else {
      ++out.dropped;
    }
    cover(part, accepted);
  }
  return out;
}

}  // namespace

TreeSkeleton extract_centerline_tree(const MaskVolume& mask, const TreeSkeletonSettings& s) {
  require_valid_volume(mask, "mask");
  require(s.ball_scale > 0 && s.branch_scale >= 0 && s.max_endpoints >= 1 && s.smoothing_sigma >= 0,
          "tree skeleton: bad settings (ball_scale > 0, branch_scale >= 0, max_endpoints >= 1, sigma >= 0)");
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

  // §3.3 root: double sweep; then the endpoint of the widest end (the inlet of a vessel tree)
  std::vector<double> dfs;
  dijkstra(g, 0, dfs);
  Index R = argmax(dfs);
  Picked picked;
  std::vector<Index> parent;
  for (int pass = 0; pass < 2; ++pass) {
    dijkstra(g, R, dfs);
    parent = penalized_parents(g, dfb, dfb_max, s, R);
    picked = pick_endpoints(g, dfb, dfs, parent, h, s, R);
    if (pass == 1) break;
    // the width of an end: the largest DFB on its path within 3 of its own (smallest) radii of the tip
    auto width = [&](Index e, bool from_root) {
      std::vector<Index> path;
      for (Index v = e; v >= 0; v = parent[v]) path.push_back(v);
      if (from_root) std::reverse(path.begin(), path.end());
      double len = 0.0, w = 0.0;
      for (std::size_t k = 0; k < path.size() && len <= 3.0 * std::max(w, out.h_min); ++k) {
        w = std::max(w, dfb[path[k]]);
        if (k + 1 < path.size()) len += std::sqrt(g.edge_len2(path[k], path[k + 1]));
      }
      return w;
    };
    const Index first_leaf = picked.leaves.front();
    Index widest = R;
    double best = width(first_leaf, true);  // R's end, walked from R
    for (Index e : picked.leaves) {
      const double w = width(e, false);
      if (w > best * (1.0 + 1e-9)) {
        best = w;
        widest = e;
      }
    }
    if (widest == R) break;
    R = widest;
  }
  out.dropped = picked.dropped;

  // the skeleton's branches: voxel runs between the root, junctions (>= 2 children) and leaves
  std::vector<Index> children(V, 0);
  std::vector<char> on(V, 0);
  for (Index e : picked.leaves)
    for (Index v = e; v >= 0 && !on[v]; v = parent[v]) on[v] = 1;
  for (Index v = 0; v < V; ++v)
    if (on[v] && parent[v] >= 0) ++children[parent[v]];
  auto local_of = [&](Index v) {
    const auto c = g.ijk(v);  // input-grid index (may be -1.. at the padding)
    return Vec3(h[0] * static_cast<double>(c[0]), h[1] * static_cast<double>(c[1]),
                h[2] * static_cast<double>(c[2]));
  };
  auto dfb_at = [&](const Vec3& p) {  // trilinear DFB at a local physical point (input grid)
    return trilinear(df.dfb, p.cwiseQuotient(h) + Vec3(P, P, P));
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
  for (Index e : picked.leaves) {
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
  auto cut_index = [](const Centerline& c, bool at_end) {
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
      if (sa[b] >= r_ref || sa[b] >= half) return b;
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
  }
  out.endpoints = static_cast<Index>(out.lines.size());
  out.notes.push_back(cat(out.endpoints, " endpoint(s) from the root; ", out.dropped,
                          " side path(s) dropped as bumps (shorter beyond the parent's wall than ",
                          s.branch_scale, " x their radius)"));
  return out;
}

}  // namespace medspring
