// Private to the skeleton layer: the stages of the distance-mapping centerline (ALGORITHMS.md §3) that
// centerline_extraction.cpp runs: the voxel graph and its queues, geodesic distances, the Prim / penalised
// paths (centerline_graph.cpp), and the polyline operations in local physical coordinates
// (centerline_curves.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/core/types.hpp"

namespace medspring::skeleton_detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// A neighbour offset of the voxel graph: grid steps, and its physical length (mm).
struct Offset {
  int di = 0, dj = 0, dk = 0;
  Index d = 0;        // linear-index difference on the grid it was made for
  double len = 0.0;   // mm
  double len2 = 0.0;  // mm^2
};

/// Neighbour offsets for 6/18/26-connectivity in raster order (k, j, i), lengths with spacing h.
std::vector<Offset> make_offsets(int connectivity, const Vec3& h, const std::array<Index, 3>& dims);

/// Dijkstra's queue: smaller distance first, ties by node id. An entry is pushed on every decrease;
/// a popped entry whose distance is no longer the node's is stale and skipped (lazy deletion).
class DistQueue {
 public:
  struct Entry {
    double dist;
    Index id;
  };
  void push(double dist, Index id) {
    heap_.push_back({dist, id});
    std::push_heap(heap_.begin(), heap_.end(), Later());
  }
  bool empty() const { return heap_.empty(); }
  Entry pop() {
    std::pop_heap(heap_.begin(), heap_.end(), Later());
    const Entry e = heap_.back();
    heap_.pop_back();
    return e;
  }

 private:
  struct Later {  // a is popped after b
    bool operator()(const Entry& a, const Entry& b) const {
      return a.dist > b.dist || (a.dist == b.dist && a.id > b.id);
    }
  };
  std::vector<Entry> heap_;
};

/// Prim's queue (D-7): pops the largest key; ties: smaller DFS_R, then smaller linear index (node
/// id). Keys are dense ranks of the DFB order, so the queue is one bucket per key, each a binary heap
/// on (DFS_R, id); entries whose key has since risen are skipped when popped (lazy deletion, as the
/// pseudo-code of §3.4 pushes a node again on every raise).
class PrimQueue {
 public:
  struct Entry {
    double dfs;
    Index id;
  };
  explicit PrimQueue(Index ranks) : buckets_(ranks) {}
  void push(Index rank, double dfs, Index id) {
    auto& b = buckets_[rank];
    b.push_back({dfs, id});
    std::push_heap(b.begin(), b.end(), Later());
    top_ = std::max(top_, rank);
  }
  /// The best entry; false when the queue is empty.
  bool pop(Index& rank, Index& id) {
    while (top_ >= 0 && buckets_[top_].empty()) --top_;
    if (top_ < 0) return false;
    auto& b = buckets_[top_];
    std::pop_heap(b.begin(), b.end(), Later());
    rank = top_;
    id = b.back().id;
    b.pop_back();
    return true;
  }

 private:
  struct Later {  // a is popped after b
    bool operator()(const Entry& a, const Entry& b) const {
      return a.dfs > b.dfs || (a.dfs == b.dfs && a.id > b.id);
    }
  };
  std::vector<std::vector<Entry>> buckets_;
  Index top_ = -1;
};

/// The object voxels of the component used, as graph nodes on the padded working grid. Node ids
/// follow the raster order, so comparing ids compares linear indices in the input mask.
struct Graph {
  std::array<Index, 3> dims{};  // working grid
  std::array<Index, 3> lo{};    // input-grid index of working voxel (0,0,0)
  std::vector<Index> gid;       // working grid -> node id, -1 when not a node
  std::vector<Index> widx;      // node id -> working linear index
  std::vector<Offset> offsets;  // neighbour offsets on the working grid
  Index size() const { return static_cast<Index>(widx.size()); }
  std::array<Index, 3> ijk(Index v) const {  // input-grid index of node v
    const Index w = widx[v];
    return {w % dims[0] + lo[0], (w / dims[0]) % dims[1] + lo[1], w / (dims[0] * dims[1]) + lo[2]};
  }
  /// Squared physical length of the edge between neighbours a and b.
  double edge_len2(Index a, Index b) const {
    const Index d = widx[b] - widx[a];
    for (const Offset& o : offsets)
      if (o.d == d) return o.len2;
    return kInf;
  }
};

/// DFS: geodesic distance (mm) inside the object from `src` (§3.3); Dijkstra, ties by node id.
void dijkstra(const Graph& g, Index src, std::vector<double>& dist);

/// argmax of dist, ties by smallest id (D-6).
Index argmax(const std::vector<double>& dist);

/// D-7: Prim's maximum spanning tree of w(u,v) = min(DFB(u), DFB(v)) from R, with the documented
/// tie rules; stops once E joins the tree (its tree path is final then). `level` holds dense ranks
/// 0..levels-1 of the exact DFB order.
std::vector<Index> prim_path(const Graph& g, const std::vector<Index>& level, Index levels,
                             const std::vector<double>& dfs, Index R, Index E);

/// Option PenalizedDijkstra (§3.4): step cost |step| (1 + lambda (1 - DFB(w)/DFB_max)^p).
std::vector<Index> penalized_path(const Graph& g, const std::vector<double>& dfb, double dfb_max,
                                  double lambda, double power, Index R, Index E);

// ---- polylines in local physical coordinates (mm) ----

using Curve = std::vector<Vec3>;

std::vector<double> cumulative_length(const Curve& P);

/// Point at arc length s (clamped); `seg` is a monotone search hint.
Vec3 point_at(const Curve& P, const std::vector<double>& S, double s, std::size_t& seg);

/// The part of P between arc lengths a < b.
Curve sub_curve(const Curve& P, const std::vector<double>& S, double a, double b);

/// §3.5.1: uniform arc-length resampling with step L / ceil(L / delta) <= delta.
Curve resample_uniform(const Curve& P, double delta, double& step);

/// §3.5.2: Gaussian smoothing along arc length (uniform samples, spacing `step`), endpoints fixed,
/// sigma_eff(s) = min(sigma, s_end/3) so the 3-sigma window stays symmetric and inside the curve.
Curve smooth_gaussian(const Curve& P, double step, double sigma);

struct OpenEndGroup {
  Index size = 0;
  Index first = 0;               // smallest linear index (discovery order)
  Vec3 centroid = Vec3::Zero();  // local physical coordinates, mm
  std::vector<Index> voxels;     // linear indices in the input mask, ascending
};

inline std::string ijk_text(const std::array<Index, 3>& c) {
  return cat("(", c[0], ",", c[1], ",", c[2], ")");
}

}  // namespace medspring::skeleton_detail
