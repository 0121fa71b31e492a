#include "medspring/local/patch.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <utility>

#include "local_fixtures.hpp"
#include "medspring/core/error.hpp"

namespace medspring {
namespace {

using testing::mesh_adjacency;
using testing::window_index;

std::set<std::pair<Index, Index>> global_springs(const LocalPatch& p) {
  std::set<std::pair<Index, Index>> s;
  for (Index k = 0; k < p.num_springs(); ++k) s.emplace(p.nodes[p.springs(k, 0)], p.nodes[p.springs(k, 1)]);
  return s;
}

// Brute-force D-15 / §6.1 check of a patch against the full mesh.
void expect_patch_consistent_with_mesh(const LocalPatch& p, const Adjacency& adj, const MatX2i& E,
                                       const std::vector<std::uint8_t>& model_fixed = {}) {
  const std::set<Index> in(p.nodes.begin(), p.nodes.end());
  ASSERT_EQ(in.size(), p.nodes.size());
  ASSERT_EQ(p.nodes[p.contact_local], p.contact);
  for (Index a = 0; a < p.size(); ++a) {
    bool outside = false;
    for (const Index* q = adj.begin(p.nodes[a]); q != adj.end(p.nodes[a]); ++q) outside |= !in.count(*q);
    const bool mf = !model_fixed.empty() && model_fixed[p.nodes[a]] != 0;
    EXPECT_EQ(p.fixed[a] != 0, outside || mf) << "patch node " << a;
  }
  std::set<std::pair<Index, Index>> expected;
  for (Index s = 0; s < E.rows(); ++s)
    if (in.count(E(s, 0)) && in.count(E(s, 1))) expected.emplace(E(s, 0), E(s, 1));
  EXPECT_EQ(global_springs(p), expected);
  for (Index s = 0; s < p.num_springs(); ++s) EXPECT_LT(p.nodes[p.springs(s, 0)], p.nodes[p.springs(s, 1)]);
  Index free_count = 0;
  for (Index a = 0; a < p.size(); ++a) free_count += p.fixed[a] == 0;
  EXPECT_EQ(p.num_free(), free_count);
  EXPECT_TRUE(std::is_sorted(p.free_nodes.begin(), p.free_nodes.end()));
}

TEST(LocalPatch, FiveByFiveWindowHasNineFreeNodesInsideSixteenFixed) {
  const LocalPatch p = structured_window_patch(40, 30, GridNode{20, 7});
  ASSERT_EQ(p.size(), 25);
  EXPECT_EQ(p.num_free(), 9);
  EXPECT_EQ(p.num_springs(), 56);  // 20 circumferential + 20 axial + 16 diagonal
  EXPECT_EQ(p.contact, 20 * 30 + 7);
  EXPECT_EQ(p.contact_local, window_index(0, 0));
  for (Index di = -2; di <= 2; ++di)
    for (Index dj = -2; dj <= 2; ++dj) {
      const Index a = window_index(di, dj);
      EXPECT_EQ(p.nodes[a], (20 + di) * 30 + 7 + dj);
      EXPECT_EQ(p.fixed[a] != 0, std::abs(di) == 2 || std::abs(dj) == 2) << di << "," << dj;
    }
  EXPECT_TRUE(std::all_of(p.k.begin(), p.k.end(), [](double k) { return k == 0.05; }));
  EXPECT_FALSE(p.trivial());
}

TEST(LocalPatch, StructuredWindowEqualsGeneralPatchOnTheTubeMesh) {
  const SurfaceMesh m = tube(12, 9);
  const Adjacency adj = mesh_adjacency(m);
  const MatX2i E = unique_edges(m.F);
  std::vector<std::uint8_t> model_fixed(static_cast<std::size_t>(m.num_vertices()), 0);
  for (Index j = 0; j < 9; ++j) model_fixed[j] = 1;  // ring 0 clamped
  for (const Index hw : {0, 1, 2, 3, 4})
    for (const Index c : {0, 4, 8, 9, 17, 40, 44, 53, 99, 107}) {  // seam spokes 0 / 8, end rings 0 / 11
      for (const bool use_fixed : {false, true}) {
        const auto& mf = use_fixed ? model_fixed : std::vector<std::uint8_t>{};
        const LocalPatch p = structured_window_patch(12, 9, c, {.k_loc = 0.3, .half_width = hw}, mf);
        SCOPED_TRACE(::testing::Message()
                     << "contact " << c << " half_width " << hw << " fixed " << use_fixed);
        expect_patch_consistent_with_mesh(p, adj, E, mf);
        const LocalPatch q = make_local_patch(adj, p.nodes, c, 0.3, mf);
        EXPECT_EQ(q.fixed, p.fixed);
        EXPECT_EQ(global_springs(q), global_springs(p));
      }
    }
}

TEST(LocalPatch, WindowRingsAreClampedAtTheEndRing) {
  const LocalPatch p = structured_window_patch(40, 30, GridNode{0, 5});
  EXPECT_EQ(p.size(), 15);  // rings 0..2 only
  // Without model-fixed flags, the end-ring nodes next to the contact have no outside neighbour.
  EXPECT_EQ(p.fixed[p.contact_local], 0);
  EXPECT_EQ(p.num_free(), 6);  // rings 0 and 1, spoke offsets -1..1
  std::vector<std::uint8_t> fixed(1200, 0);
  for (Index j = 0; j < 30; ++j) fixed[j] = 1;
  const LocalPatch q = structured_window_patch(40, 30, GridNode{0, 5}, {}, fixed);
  EXPECT_TRUE(q.trivial());  // contact on a clamped end ring
  EXPECT_EQ(q.num_free(), 3);
}

TEST(LocalPatch, InteriorTwoRingOfTheTubeIsTheRegularHexagonalPatch) {
  const SurfaceMesh m = tube(40, 30);
  const Adjacency adj = mesh_adjacency(m);
  const Index c = 20 * 30 + 7;
  EXPECT_EQ(adj.degree(c), 6);
  const LocalPatch p = make_local_patch(adj, k_ring(adj, c, 2), c, 1.0);
  EXPECT_EQ(p.size(), 19);
  EXPECT_EQ(p.num_free(), 7);
  EXPECT_EQ(p.num_springs(), 42);  // 24 triangles, 12 boundary edges: (3 * 24 + 12) / 2
  EXPECT_EQ(p.contact_local, 0);
  for (Index a = 0; a < 7; ++a) EXPECT_EQ(p.fixed[a], 0);  // c and its ring 1
}

TEST(LocalPatch, BfsPatchOnKidneyFollowsD15) {
  const SurfaceMesh m = kidney_phantom();
  const Adjacency adj = mesh_adjacency(m);
  const MatX2i E = unique_edges(m.F);
  for (const Index c : {0, 1, 100, 223, 457}) {
    const LocalPatch p = bfs_local_patch(adj, m.V, c, {.k_loc = 0.05, .count = 25});
    SCOPED_TRACE(::testing::Message() << "contact " << c);
    ASSERT_EQ(p.size(), 25);
    EXPECT_EQ(p.nodes, bfs_patch(adj, m.V, c, 25));
    EXPECT_EQ(p.contact_local, 0);
    EXPECT_EQ(p.fixed[0], 0);
    EXPECT_GT(p.num_free(), 0);
    expect_patch_consistent_with_mesh(p, adj, E);
  }
}

TEST(LocalPatch, BadInputIsRejectedWithClearErrors) {
  const SurfaceMesh m = kidney_phantom();
  const Adjacency adj = mesh_adjacency(m);
  EXPECT_THROW(structured_window_patch(40, 30, GridNode{40, 0}), InvalidInput);
  EXPECT_THROW(structured_window_patch(40, 30, GridNode{0, 30}), InvalidInput);
  EXPECT_THROW(structured_window_patch(40, 30, GridNode{-1, 0}), InvalidInput);
  EXPECT_THROW(structured_window_patch(40, 30, Index{1200}), InvalidInput);
  EXPECT_THROW(structured_window_patch(40, 30, Index{5}, {.half_width = -1}), InvalidInput);
  EXPECT_THROW(structured_window_patch(40, 4, Index{5}, {.half_width = 2}), InvalidInput);
  EXPECT_THROW(structured_window_patch(40, 30, Index{5}, {.k_loc = 0.0}), InvalidInput);
  EXPECT_THROW(structured_window_patch(40, 30, Index{5}, {}, std::vector<std::uint8_t>(10, 0)), InvalidInput);
  EXPECT_THROW(bfs_local_patch(adj, m.V, 458), InvalidInput);
  EXPECT_THROW(bfs_local_patch(adj, m.V, -1), InvalidInput);
  EXPECT_THROW(bfs_local_patch(adj, m.V, 3, {.count = 459}), InvalidInput);
  EXPECT_THROW(bfs_local_patch(adj, m.V, 3, {.count = 0}), InvalidInput);
  EXPECT_THROW(make_local_patch(adj, {1, 2, 3}, 4, 1.0), InvalidInput);    // contact not in the patch
  EXPECT_THROW(make_local_patch(adj, {1, 2, 2}, 1, 1.0), InvalidInput);    // duplicate node
  EXPECT_THROW(make_local_patch(adj, {1, 2, 500}, 1, 1.0), InvalidInput);  // node outside the mesh
  try {
    bfs_local_patch(adj, m.V, 3, {.count = 459});
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("larger than the mesh"), std::string::npos) << e.what();
  }
}

TEST(LocalPatch, SingleNodePatchHasNoFreeNode) {
  const LocalPatch p = structured_window_patch(40, 30, GridNode{20, 7}, {.half_width = 0});
  EXPECT_EQ(p.size(), 1);
  EXPECT_EQ(p.num_free(), 0);
  EXPECT_TRUE(p.trivial());
}

}  // namespace
}  // namespace medspring
