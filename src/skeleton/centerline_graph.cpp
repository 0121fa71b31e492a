// The voxel graph stage of the centerline (centerline_stages.hpp): neighbour offsets, geodesic distance
// (§3.3), the maximum spanning tree path of D-7 and the penalised-Dijkstra option (§3.4).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "centerline_stages.hpp"

namespace medspring::skeleton_detail {

/// Neighbour offsets for 6/18/26-connectivity in raster order (k, j, i), lengths with spacing h.
std::vector<Offset> make_offsets(int connectivity, const Vec3& h, const std::array<Index, 3>& dims) {
  const int max_l1 = connectivity == 6 ? 1 : connectivity == 18 ? 2 : 3;
  std::vector<Offset> out;
  for (int dk = -1; dk <= 1; ++dk)
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        const int l1 = std::abs(di) + std::abs(dj) + std::abs(dk);
        if (l1 == 0 || l1 > max_l1) continue;
        Offset o;
        o.di = di;
        o.dj = dj;
        o.dk = dk;
        o.d = di + dims[0] * (dj + dims[1] * dk);
        o.len2 = di * di * h[0] * h[0] + dj * dj * h[1] * h[1] + dk * dk * h[2] * h[2];
        o.len = std::sqrt(o.len2);
        out.push_back(o);
      }
  return out;
}

/// DFS: geodesic distance (mm) inside the object from `src` (§3.3); Dijkstra, ties by node id.
void dijkstra(const Graph& g, Index src, std::vector<double>& dist) {
  dist.assign(g.size(), kInf);
  dist[src] = 0.0;
  DistQueue queue;
  queue.push(0.0, src);
  while (!queue.empty()) {
    const DistQueue::Entry e = queue.pop();
    if (e.dist != dist[e.id]) continue;  // stale
    const Index wv = g.widx[e.id];
    for (const Offset& o : g.offsets) {
      const Index w = g.gid[wv + o.d];
      if (w < 0) continue;
      const double nd = e.dist + o.len;  // never below a final distance: lengths are positive
      if (nd < dist[w]) {
        dist[w] = nd;
        queue.push(nd, w);
      }
    }
  }
}

/// argmax of dist, ties by smallest id (D-6).
Index argmax(const std::vector<double>& dist) {
  Index best = 0;
  for (Index v = 1; v < static_cast<Index>(dist.size()); ++v)
    if (dist[v] > dist[best]) best = v;
  return best;
}

/// D-7: Prim's maximum spanning tree of w(u,v) = min(DFB(u), DFB(v)) from R, with the documented
/// tie rules; stops once E joins the tree (its tree path is final then). `level` holds dense ranks
/// 0..levels-1 of the exact DFB order.
std::vector<Index> prim_path(const Graph& g, const std::vector<Index>& level, Index levels,
                             const std::vector<double>& dfs, Index R, Index E) {
  const Index V = g.size();
  const Index inf = levels;  // key of R: +inf
  struct Node {              // one cache-friendly record per node
    Index level = 0;
    Index key = -1;  // -1 = -inf
    Index parent = -1;
    Index in_tree = 0;
  };
  std::vector<Node> node(V);
  for (Index v = 0; v < V; ++v) node[v].level = level[v];
  PrimQueue queue(levels + 1);
  node[R].key = inf;
  queue.push(inf, dfs[R], R);
  // better(v, p, w): DFB[v] > DFB[p]; else |v-w| < |p-w|; else index(v) < index(p)
  auto better = [&](Index v, Index p, Index w, double len2_vw) {
    if (node[v].level != node[p].level) return node[v].level > node[p].level;
    const double len2_pw = g.edge_len2(p, w);
    if (len2_vw != len2_pw) return len2_vw < len2_pw;
    return v < p;
  };
  Index rank = 0, v = 0;
  while (queue.pop(rank, v)) {
    Node& nv = node[v];
    if (nv.in_tree || rank != nv.key) continue;  // stale entry
    nv.in_tree = 1;
    if (v == E) break;
    const Index wv = g.widx[v];
    for (const Offset& o : g.offsets) {
      const Index w = g.gid[wv + o.d];
      if (w < 0) continue;
      Node& nw = node[w];
      if (nw.in_tree) continue;
      const Index s = std::min(nv.level, nw.level);
      if (s > nw.key || (s == nw.key && better(v, nw.parent, w, o.len2))) {
        const bool raised = s > nw.key;
        nw.key = s;
        nw.parent = v;
        if (raised) queue.push(s, dfs[w], w);
      }
    }
  }
  std::vector<Index> path;
  for (Index u = E; u >= 0; u = node[u].parent) path.push_back(u);
  std::reverse(path.begin(), path.end());
  return path;
}

/// Option PenalizedDijkstra (§3.4): step cost |step| (1 + lambda (1 - DFB(w)/DFB_max)^p).
std::vector<Index> penalized_path(const Graph& g, const std::vector<double>& dfb, double dfb_max,
                                  double lambda, double power, Index R, Index E) {
  const Index V = g.size();
  std::vector<double> dist(V, kInf);
  std::vector<Index> parent(V, -1);
  std::vector<double> penalty(V);
  for (Index v = 0; v < V; ++v) penalty[v] = 1.0 + lambda * std::pow(1.0 - dfb[v] / dfb_max, power);
  dist[R] = 0.0;
  DistQueue queue;
  queue.push(0.0, R);
  while (!queue.empty()) {
    const DistQueue::Entry e = queue.pop();
    if (e.dist != dist[e.id]) continue;  // stale
    if (e.id == E) break;
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
  std::vector<Index> path;
  for (Index v = E; v >= 0; v = parent[v]) path.push_back(v);
  std::reverse(path.begin(), path.end());
  return path;
}

}  // namespace medspring::skeleton_detail
