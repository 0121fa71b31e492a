#include "medspring/geometry/topology.hpp"

#include <algorithm>
#include <cstdint>
#include <deque>
#include <numeric>

#include "medspring/core/check.hpp"

namespace medspring {

MatX2i unique_edges(const MatX3i& F) {
  // (min << 32) | max keys: one integer sort instead of a sort of pairs (the same lexicographic order)
  std::vector<std::uint64_t> e;
  e.reserve(static_cast<std::size_t>(F.rows()) * 3);
  for (Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Index a = F(f, k), b = F(f, (k + 1) % 3);
      if (a != b)
        e.push_back((static_cast<std::uint64_t>(static_cast<std::uint32_t>(std::min(a, b))) << 32) |
                    static_cast<std::uint32_t>(std::max(a, b)));
    }
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  MatX2i E(static_cast<Index>(e.size()), 2);
  for (std::size_t s = 0; s < e.size(); ++s) {
    E(static_cast<Index>(s), 0) = static_cast<Index>(static_cast<std::int32_t>(e[s] >> 32));
    E(static_cast<Index>(s), 1) = static_cast<Index>(static_cast<std::int32_t>(e[s] & 0xffffffffu));
  }
  return E;
}

Adjacency vertex_adjacency(Index n, const MatX2i& edges) {
  // compressed rows in two passes (count, fill), then each row sorted and de-duplicated in place
  std::vector<Index> count(static_cast<std::size_t>(n) + 1, 0);
  for (Index s = 0; s < edges.rows(); ++s) {
    const Index a = edges(s, 0), b = edges(s, 1);
    require_index(a, n, "edges[", s, "][0]");
    require_index(b, n, "edges[", s, "][1]");
    if (a == b) continue;
    ++count[static_cast<std::size_t>(a) + 1];
    ++count[static_cast<std::size_t>(b) + 1];
  }
  for (std::size_t i = 1; i < count.size(); ++i) count[i] += count[i - 1];
  std::vector<Index> fill(count.begin(), count.end() - 1);
  std::vector<Index> nb(static_cast<std::size_t>(count.back()));
  for (Index s = 0; s < edges.rows(); ++s) {
    const Index a = edges(s, 0), b = edges(s, 1);
    if (a == b) continue;
    nb[static_cast<std::size_t>(fill[a]++)] = b;
    nb[static_cast<std::size_t>(fill[b]++)] = a;
  }
  Adjacency adj;
  adj.offsets.assign(static_cast<std::size_t>(n) + 1, 0);
  adj.neighbors.reserve(nb.size());
  for (Index i = 0; i < n; ++i) {
    const auto first = nb.begin() + count[i], last = nb.begin() + count[static_cast<std::size_t>(i) + 1];
    std::sort(first, last);
    const auto end = std::unique(first, last);
    adj.neighbors.insert(adj.neighbors.end(), first, end);
    adj.offsets[static_cast<std::size_t>(i) + 1] = static_cast<Index>(adj.neighbors.size());
  }
  return adj;
}

std::vector<int> hop_distances(const Adjacency& adj, Index c) {
  const Index n = adj.num_nodes();
  require_index(c, n, "hop_distances: source node");
  std::vector<int> d(static_cast<std::size_t>(n), -1);
  std::deque<Index> q{c};
  d[c] = 0;
  while (!q.empty()) {
    const Index a = q.front();
    q.pop_front();
    for (const Index* p = adj.begin(a); p != adj.end(a); ++p)
      if (d[*p] < 0) {
        d[*p] = d[a] + 1;
        q.push_back(*p);
      }
  }
  return d;
}

std::vector<Index> k_ring(const Adjacency& adj, Index c, int k) {
  const auto d = hop_distances(adj, c);
  std::vector<Index> out;
  for (Index i = 0; i < static_cast<Index>(d.size()); ++i)
    if (d[i] >= 0 && d[i] <= k) out.push_back(i);
  std::stable_sort(out.begin(), out.end(), [&](Index a, Index b) { return d[a] < d[b]; });
  return out;
}

std::vector<Index> bfs_patch(const Adjacency& adj, const MatX3& X0, Index c, Index count) {
  const Index n = adj.num_nodes();
  require_index(c, n, "bfs_patch: contact node");
  require(count >= 1, "bfs_patch: patch size must be >= 1 (got ", count, ")");
  require(X0.rows() == n, "bfs_patch: rest positions have ", X0.rows(), " rows, adjacency has ", n, " nodes");
  const auto d = hop_distances(adj, c);
  std::vector<Index> reach;
  for (Index i = 0; i < n; ++i)
    if (d[i] >= 0) reach.push_back(i);
  require(count <= static_cast<Index>(reach.size()), "bfs_patch: patch of ", count,
          " nodes is larger than the ", reach.size(), " nodes reachable from node ", c);
  std::vector<double> dist(static_cast<std::size_t>(n), 0.0);
  for (Index i : reach) dist[i] = (X0.row(i) - X0.row(c)).norm();
  std::sort(reach.begin(), reach.end(), [&](Index a, Index b) {
    if (d[a] != d[b]) return d[a] < d[b];
    if (dist[a] != dist[b]) return dist[a] < dist[b];
    return a < b;
  });
  reach.resize(static_cast<std::size_t>(count));
  return reach;
}

std::vector<Index> valence_histogram(const Adjacency& adj) {
  std::vector<Index> h;
  for (Index i = 0; i < adj.num_nodes(); ++i) {
    const auto d = static_cast<std::size_t>(adj.degree(i));
    if (h.size() <= d) h.resize(d + 1, 0);
    ++h[d];
  }
  return h;
}

}  // namespace medspring
