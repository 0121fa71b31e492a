// The local deformation under a distributed load (ALGORITHMS.md §6, eq. 6; local/distributed.hpp): the patch
// of the loaded nodes plus a ring, and K U = F with each loaded node's own force.
#include "medspring/local/distributed.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <vector>

#include "local_fixtures.hpp"
#include "medspring/core/error.hpp"

using namespace medspring;
using medspring::testing::flat_grid;
using medspring::testing::mesh_adjacency;

namespace {

// The nodes of the G x G grid within radius r of node c (in the plane), with a uniform force share each.
std::vector<Index> disk_nodes(const SurfaceMesh& m, Index c, double r) {
  std::vector<Index> out;
  for (Index i = 0; i < m.num_vertices(); ++i)
    if ((m.V.row(i) - m.V.row(c)).norm() < r) out.push_back(i);
  return out;
}

}  // namespace

// On an 11 x 11 flat grid, a uniform 0.3 N load spread over the 13 nodes within 2.05 mm of the centre: the
// patch is those nodes plus one ring (fixed); U equals the solution of L_ff U = F assembled independently
// from the grid's edges (1e-12 mm), the free nodes are exactly the loaded ones, and the reaction at the
// fixed ring balances the whole load (1e-12 N): no force is lost.
TEST(LocalDistributed, UniformDiskLoadSolvesThePatchSystemAndKeepsTheTotalForce) {
  const Index G = 11, c = 5 * G + 5;
  const double k = 0.05;
  const SurfaceMesh m = flat_grid(G);
  const Adjacency adj = mesh_adjacency(m);
  const std::vector<Index> loaded = disk_nodes(m, c, 2.05);
  ASSERT_EQ(loaded.size(), 13u);
  const LocalPatch p = loaded_nodes_patch(adj, loaded, c, k);
  ASSERT_EQ(p.num_free(), static_cast<Index>(loaded.size()));
  for (Index a = 0; a < p.size(); ++a)  // the loaded nodes first, free; the ring after them, fixed
    EXPECT_EQ(p.fixed[a] != 0, a >= static_cast<Index>(loaded.size())) << "patch node " << a;
  const Vec3 total(0.05, -0.1, -0.3);
  MatX3 F = MatX3::Zero(p.size(), 3);
  for (std::size_t a = 0; a < loaded.size(); ++a) F.row(static_cast<Index>(a)) = total.transpose() / 13.0;
  MatX3 U;
  const Vec3 dropped = solve_local_distributed(p, F, U);
  EXPECT_LT(dropped.norm(), 1e-15);

  // independent: the graph Laplacian of the grid over the loaded nodes, every other node held at 0
  const Index n = static_cast<Index>(loaded.size());
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
  auto local_of = [&](Index g) {
    const auto it = std::find(loaded.begin(), loaded.end(), g);
    return it == loaded.end() ? Index(-1) : static_cast<Index>(it - loaded.begin());
  };
  for (Index a = 0; a < n; ++a)
    for (const Index* q = adj.begin(loaded[a]); q != adj.end(loaded[a]); ++q) {
      L(a, a) += k;
      if (local_of(*q) >= 0) L(a, local_of(*q)) -= k;
    }
  const Eigen::MatrixXd u = L.fullPivLu().solve(Eigen::MatrixXd(F.topRows(n)));
  EXPECT_LT((U.topRows(n) - u).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(U.bottomRows(p.size() - n).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(U.row(p.contact_local).dot(total), 0.0);  // the centre moves along the load

  // the springs' forces on the fixed ring balance the load
  const Eigen::MatrixXd K = local_stiffness_matrix(p, {});
  Eigen::VectorXd Ux(3 * p.size());
  for (Index a = 0; a < p.size(); ++a) Ux.segment<3>(3 * a) = U.row(a).transpose();
  const Eigen::VectorXd f = K * Ux;
  Vec3 reaction = Vec3::Zero();
  for (Index a = n; a < p.size(); ++a) reaction += f.segment<3>(3 * a);
  EXPECT_LT((reaction + total).norm(), 1e-12);
}

// The whole force on the contact node alone gives the existing single-node solve (LocalSolver, the runtime's
// path) to 1e-12 mm: the distributed solve is its generalisation.
TEST(LocalDistributed, ForceOnTheContactAloneEqualsTheSingleNodeSolve) {
  const Index G = 9, c = 4 * G + 4;
  const SurfaceMesh m = flat_grid(G);
  const LocalPatch p = loaded_nodes_patch(mesh_adjacency(m), disk_nodes(m, c, 1.5), c, 0.07);
  MatX3 F = MatX3::Zero(p.size(), 3);
  const Vec3 Fc(0.01, 0.02, -0.2);
  F.row(p.contact_local) = Fc.transpose();
  MatX3 U, V;
  solve_local_distributed(p, F, U);
  LocalSolver s;
  s.precompute(p);
  s.solve(Fc, V);
  EXPECT_LT((U - V).cwiseAbs().maxCoeff(), 1e-12);
}

// A model-fixed loaded node keeps U = 0 and its force is reported as dropped; bad input is refused with the
// defect named.
TEST(LocalDistributed, FixedLoadedNodeDropsItsForceAndBadInputIsRefused) {
  const Index G = 9, c = 4 * G + 4;
  const SurfaceMesh m = flat_grid(G);
  const Adjacency adj = mesh_adjacency(m);
  const std::vector<Index> loaded = disk_nodes(m, c, 1.5);
  std::vector<std::uint8_t> fixed(static_cast<std::size_t>(G * G), 0);
  const Index pinned = loaded.front() == c ? loaded.back() : loaded.front();
  fixed[static_cast<std::size_t>(pinned)] = 1;
  const LocalPatch p = loaded_nodes_patch(adj, loaded, c, 0.05, fixed);
  MatX3 F = MatX3::Constant(p.size(), 3, 0.0);
  for (std::size_t a = 0; a < loaded.size(); ++a) F(static_cast<Index>(a), 2) = -0.1;
  MatX3 U;
  const Vec3 dropped = solve_local_distributed(p, F, U);
  EXPECT_NEAR(dropped(2), -0.1, 1e-15);
  const auto it = std::find(p.nodes.begin(), p.nodes.end(), pinned);
  EXPECT_EQ(U.row(it - p.nodes.begin()).norm(), 0.0);

  EXPECT_THROW(loaded_nodes_patch(adj, {}, c, 0.05), InvalidInput);
  EXPECT_THROW(loaded_nodes_patch(adj, loaded, 0, 0.05), InvalidInput);  // contact not loaded
  EXPECT_THROW(loaded_nodes_patch(adj, {c, G * G}, c, 0.05), InvalidInput);
  EXPECT_THROW(loaded_nodes_patch(adj, loaded, c, 0.05, {}, -1), InvalidInput);
  EXPECT_THROW(solve_local_distributed(p, MatX3::Zero(2, 3), U), InvalidInput);
  EXPECT_THROW(solve_local_distributed(p, F, U, {}, {.stiffness = LocalStiffness::PaperLiteral}),
               InvalidInput);
  try {
    solve_local_distributed(p, MatX3::Zero(2, 3), U);
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("force has 2 rows"), std::string::npos) << e.what();
  }
}
