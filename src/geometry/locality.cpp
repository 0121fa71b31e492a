#include "medspring/geometry/locality.hpp"

#include <algorithm>

#include "medspring/core/check.hpp"

namespace medspring {
namespace {

/// Breadth-first level structure from `root` over the unvisited nodes of its component: fills `seq`
/// with the nodes in visiting order (neighbours by increasing degree) and returns the eccentricity
/// (number of levels - 1). `mark` holds `stamp` for visited nodes.
int bfs_levels(const Adjacency& adj, Index root, std::vector<Index>& seq, std::vector<int>& mark, int stamp,
               std::vector<Index>& scratch, Index* last_level_min_degree) {
  seq.clear();
  seq.push_back(root);
  mark[root] = stamp;
  std::size_t level_begin = 0;
  int levels = 0;
  while (true) {
    const std::size_t level_end = seq.size();
    for (std::size_t q = level_begin; q < level_end; ++q) {
      const Index a = seq[q];
      scratch.clear();
      for (const Index* p = adj.begin(a); p != adj.end(a); ++p)
        if (mark[*p] != stamp) {
          mark[*p] = stamp;
          scratch.push_back(*p);
        }
      std::sort(scratch.begin(), scratch.end(), [&](Index u, Index v) {
        const Index du = adj.degree(u), dv = adj.degree(v);
        return du != dv ? du < dv : u < v;
      });
      seq.insert(seq.end(), scratch.begin(), scratch.end());
    }
    if (seq.size() == level_end) {  // no new level: [level_begin, level_end) is the last level
      if (last_level_min_degree) {
        Index best = seq[level_begin];
        for (std::size_t q = level_begin; q < level_end; ++q) {
          const Index v = seq[q];
          if (adj.degree(v) < adj.degree(best) || (adj.degree(v) == adj.degree(best) && v < best)) best = v;
        }
        *last_level_min_degree = best;
      }
      return levels;
    }
    level_begin = level_end;
    ++levels;
  }
}

}  // namespace

std::vector<Index> rcm_order(const Adjacency& adj) {
  const Index n = adj.num_nodes();
  std::vector<Index> order;
  order.reserve(static_cast<std::size_t>(n));
  std::vector<int> mark(static_cast<std::size_t>(n), 0), done(static_cast<std::size_t>(n), 0);
  std::vector<Index> seq, scratch;
  int stamp = 0;
  for (Index start = 0; start < n; ++start) {
    if (done[start]) continue;
    // pseudo-peripheral node of start's component (George-Liu): a few BFS sweeps
    Index root = start;
    Index far = start;
    int ecc = bfs_levels(adj, root, seq, mark, ++stamp, scratch, &far);
    for (int sweep = 0; sweep < 8; ++sweep) {
      Index far2 = far;
      const int e = bfs_levels(adj, far, seq, mark, ++stamp, scratch, &far2);
      if (e <= ecc) break;
      root = far;
      ecc = e;
      far = far2;
    }
    bfs_levels(adj, root, seq, mark, ++stamp, scratch, nullptr);  // Cuthill-McKee sequence of the component
    for (const Index v : seq) done[v] = 1;
    order.insert(order.end(), seq.begin(), seq.end());
  }
  std::reverse(order.begin(), order.end());
  return order;
}

std::vector<Index> locality_order(const SurfaceMesh& mesh) {
  return rcm_order(vertex_adjacency(mesh.num_vertices(), unique_edges(mesh.F)));
}

std::vector<Index> inverse_permutation(const std::vector<Index>& order) {
  const Index n = static_cast<Index>(order.size());
  std::vector<Index> inv(order.size(), -1);
  for (Index k = 0; k < n; ++k) {
    const Index old = order[static_cast<std::size_t>(k)];
    require_index(old, n, "permutation[", k, "]");
    require(inv[static_cast<std::size_t>(old)] < 0, "permutation: node ", old, " appears twice (at ",
            inv[static_cast<std::size_t>(old)], " and ", k, ")");
    inv[static_cast<std::size_t>(old)] = k;
  }
  return inv;
}

SurfaceMesh permute_vertices(const SurfaceMesh& mesh, const std::vector<Index>& order) {
  require(static_cast<Index>(order.size()) == mesh.num_vertices(), "permute_vertices: permutation has ",
          order.size(), " entries, the mesh ", mesh.num_vertices(), " vertices");
  const std::vector<Index> inv = inverse_permutation(order);
  SurfaceMesh out;
  out.V.resize(mesh.V.rows(), 3);
  for (Index k = 0; k < mesh.num_vertices(); ++k)
    out.V.row(k) = mesh.V.row(order[static_cast<std::size_t>(k)]);
  out.F.resize(mesh.F.rows(), 3);
  for (Index f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) {
      const Index v = mesh.F(f, c);
      require_index(v, mesh.num_vertices(), "permute_vertices: faces[", f, "][", c, "]");
      out.F(f, c) = inv[static_cast<std::size_t>(v)];
    }
  return out;
}

Index mesh_bandwidth(const SurfaceMesh& mesh) {
  Index b = 0;
  for (Index f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) b = std::max(b, std::abs(mesh.F(f, c) - mesh.F(f, (c + 1) % 3)));
  return b;
}

}  // namespace medspring
