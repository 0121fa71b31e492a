#include "medspring/geometry/topology.hpp"

#include <gtest/gtest.h>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"

namespace medspring {
namespace {

TEST(Topology, AdjacencyIsSymmetricAndSorted) {
  const SurfaceMesh m = kidney_phantom();
  const Adjacency adj = vertex_adjacency(m.num_vertices(), unique_edges(m.F));
  EXPECT_EQ(adj.neighbors.size(), 2u * 1368u);
  for (Index i = 0; i < adj.num_nodes(); ++i)
    for (const Index* p = adj.begin(i); p != adj.end(i); ++p) {
      if (p + 1 != adj.end(i)) {
        EXPECT_LT(*p, *(p + 1));
      }
      EXPECT_TRUE(std::binary_search(adj.begin(*p), adj.end(*p), i));
    }
}

TEST(Topology, KRingOnTubeGrid) {
  const SurfaceMesh m = tube(40, 30);
  const Adjacency adj = vertex_adjacency(m.num_vertices(), unique_edges(m.F));
  const Index c = 20 * 30 + 7;
  EXPECT_EQ(k_ring(adj, c, 0).size(), 1u);
  EXPECT_EQ(k_ring(adj, c, 1).size(), 7u);   // valence 6
  EXPECT_EQ(k_ring(adj, c, 2).size(), 19u);  // hexagonal 2-ring
}

TEST(Topology, BfsPatchOrderAndErrors) {
  const SurfaceMesh m = kidney_phantom();
  const Adjacency adj = vertex_adjacency(m.num_vertices(), unique_edges(m.F));
  const auto p = bfs_patch(adj, m.V, 223, 25);
  ASSERT_EQ(p.size(), 25u);
  EXPECT_EQ(p[0], 223);
  const auto d = hop_distances(adj, 223);
  for (std::size_t k = 1; k < p.size(); ++k) EXPECT_LE(d[p[k - 1]], d[p[k]]);
  EXPECT_THROW(bfs_patch(adj, m.V, 458, 25), InvalidInput);
  EXPECT_THROW(bfs_patch(adj, m.V, 0, 459), InvalidInput);
}

}  // namespace
}  // namespace medspring
