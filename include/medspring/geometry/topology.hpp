// Mesh connectivity: unique edges, vertex adjacency (CSR), rings and patches.
#pragma once

#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

/// Unique undirected edges (i < j) of a triangle list, sorted lexicographically (D-1).
MatX2i unique_edges(const MatX3i& F);

/// Compressed sparse row adjacency: the neighbours of node i are
/// neighbors[offsets[i] .. offsets[i+1]), sorted ascending.
struct Adjacency {
  std::vector<Index> offsets;    // #N + 1
  std::vector<Index> neighbors;  // 2 #E

  Index num_nodes() const { return static_cast<Index>(offsets.size()) - 1; }
  Index degree(Index i) const { return offsets[i + 1] - offsets[i]; }
  const Index* begin(Index i) const { return neighbors.data() + offsets[i]; }
  const Index* end(Index i) const { return neighbors.data() + offsets[i + 1]; }
};

/// Builds the adjacency of n nodes from an edge list (duplicates are merged).
Adjacency vertex_adjacency(Index n, const MatX2i& edges);

/// Nodes within k edge hops of c (including c), ordered by (hop distance, index).
std::vector<Index> k_ring(const Adjacency& adj, Index c, int k);

/// Hop distance from c to every node (-1 if unreachable).
std::vector<int> hop_distances(const Adjacency& adj, Index c);

/// The first `count` nodes in breadth-first order from c, ordered by (hop distance, rest Euclidean
/// distance to c, index) (ALGORITHMS.md §6.1). Throws InvalidInput if c is out of range or count
/// exceeds the size of c's component.
std::vector<Index> bfs_patch(const Adjacency& adj, const MatX3& X0, Index c, Index count);

/// Histogram of valences: result[d] = number of nodes with d neighbours.
std::vector<Index> valence_histogram(const Adjacency& adj);

}  // namespace medspring
