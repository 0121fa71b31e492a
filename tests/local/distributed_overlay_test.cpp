// The run-time local overlay of a distributed load (local/distributed_overlay.hpp): the same patch problem as
// loaded_nodes_patch + solve_local_distributed (the calibration's), set up without allocating.
#include "medspring/local/distributed_overlay.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <random>
#include <vector>

#include "local_fixtures.hpp"
#include "medspring/core/error.hpp"
#include "medspring/local/distributed.hpp"

using namespace medspring;
using medspring::testing::mesh_adjacency;

namespace {

// The loaded set of a disk of radius r (mm) around node c, and a force per loaded node (N, #S x 3).
std::vector<Index> disk_nodes(const MatX3& X, Index c, double r) {
  std::vector<Index> out;
  for (Index i = 0; i < X.rows(); ++i)
    if ((X.row(i) - X.row(c)).norm() < r) out.push_back(i);
  return out;
}

// The calibration's overlay (fem::disk_local_overlay's solve): loaded_nodes_patch with one ring and
// solve_local_distributed, scattered to #S x 3.
MatX3 reference(const Adjacency& adj, const std::vector<Index>& loaded, const MatX3& F, double k,
                const std::vector<std::uint8_t>& fixed, std::vector<Index>* nodes = nullptr) {
  const LocalPatch p = loaded_nodes_patch(adj, loaded, loaded.front(), k, fixed, 1);
  MatX3 Fp(p.size(), 3), U;
  for (Index a = 0; a < p.size(); ++a) Fp.row(a) = F.row(p.nodes[a]);
  solve_local_distributed(p, Fp, U);
  MatX3 out = MatX3::Zero(F.rows(), 3);
  for (Index a = 0; a < p.size(); ++a) out.row(p.nodes[a]) = U.row(a);
  if (nodes) *nodes = p.nodes;
  return out;
}

}  // namespace

// On the kidney phantom (458 nodes), disks of 0.1 to 12 mm (1 to >= 10 loaded nodes) around five contacts,
// some with model-fixed nodes inside the patch: the same patch nodes in the same order as loaded_nodes_patch,
// and the same displacement as solve_local_distributed (dense LDLT of the 3 #F system) to 1e-12 relative to
// the largest |U|. A single loaded node is the one-node case of the same solve (only it is free).
TEST(DistributedOverlay, EqualsTheCalibrationsPatchSolve) {
  const SurfaceMesh kid = kidney_phantom();
  const Adjacency adj = mesh_adjacency(kid);
  const Index n = kid.num_vertices();
  std::vector<std::uint8_t> fixed(static_cast<std::size_t>(n), 0);
  for (Index i = 0; i < n; i += 37) fixed[static_cast<std::size_t>(i)] = 1;
  std::mt19937 rng(5);
  std::normal_distribution<double> N(0.0, 0.1);
  const double k = 0.07;
  DistributedOverlay d(adj, k, fixed, 4);  // small capacity: the first large patches grow it
  int cases = 0;
  std::size_t fewest = 1000, most = 0;
  for (Index c : {1, 57, 223, 301, 410})
    for (double r : {0.1, 4.0, 8.0, 12.0}) {
      const std::vector<Index> loaded = disk_nodes(kid.V, c, r);
      fewest = std::min(fewest, loaded.size());
      most = std::max(most, loaded.size());
      SCOPED_TRACE(::testing::Message() << "contact " << c << ", " << loaded.size() << " loaded nodes");
      MatX3 F = MatX3::Zero(n, 3);
      for (Index g : loaded) F.row(g) << N(rng), N(rng), -0.05 + N(rng);
      std::vector<Index> nodes;
      const MatX3 ref = reference(adj, loaded, F, k, fixed, &nodes);
      ASSERT_TRUE(d.prepare(loaded));
      d.solve(F);
      ASSERT_EQ(d.nodes(), nodes);
      MatX3 got = MatX3::Zero(n, 3);
      for (Index a = 0; a < d.size(); ++a) got.row(d.nodes()[a]) = d.displacement().row(a);
      const double scale = ref.cwiseAbs().maxCoeff();
      ASSERT_GT(scale, 0.0);
      EXPECT_LT((got - ref).cwiseAbs().maxCoeff(), 1e-12 * scale);
      if (loaded.size() == 1) {
        EXPECT_EQ(d.num_free(), 1);  // the one-node case: only the loaded node is free
      }
      ++cases;
    }
  EXPECT_EQ(cases, 20);
  EXPECT_EQ(fewest, 1u);
  EXPECT_GE(most, 10u);
  std::cout << "[ loaded nodes per disk: " << fewest << " to " << most << " ]\n";
  EXPECT_GT(d.growths(), 0);  // the workspace grew past its 4 nodes
  EXPECT_GE(d.capacity(), 40);
}

// The factor is reused while the loaded set stays the same (a new force costs one solve, linear in F); a
// changed set is selected and factored again; no free node (every loaded node model-fixed) gives U = 0 and
// prepare() false; bad input is refused with the cause named.
TEST(DistributedOverlay, ReusesTheFactorAndRefusesBadInput) {
  const SurfaceMesh kid = kidney_phantom();
  const Adjacency adj = mesh_adjacency(kid);
  const Index n = kid.num_vertices();
  DistributedOverlay d(adj, 0.05);
  const std::vector<Index> loaded = disk_nodes(kid.V, 223, 12.0);
  ASSERT_GE(loaded.size(), 3u);
  MatX3 F = MatX3::Zero(n, 3);
  for (Index g : loaded) F.row(g) << 0.0, 0.0, -0.01;
  ASSERT_TRUE(d.prepare(loaded));
  d.solve(F);
  const MatX3 U1 = d.displacement();
  ASSERT_TRUE(d.prepare(loaded));  // same set: nothing selected again
  d.solve(2.0 * F);
  EXPECT_LT((MatX3(d.displacement()) - 2.0 * U1).cwiseAbs().maxCoeff(), 1e-15);
  ASSERT_TRUE(d.prepare({loaded.front()}));
  EXPECT_EQ(d.num_free(), 1);

  std::vector<std::uint8_t> fixed(static_cast<std::size_t>(n), 0);
  for (Index g : loaded) fixed[static_cast<std::size_t>(g)] = 1;
  DistributedOverlay held(adj, 0.05, fixed);
  EXPECT_FALSE(held.prepare(loaded));
  held.solve(F);
  EXPECT_EQ(held.displacement().cwiseAbs().maxCoeff(), 0.0);

  const auto refused = [](auto&& f, const char* what) {
    try {
      f();
      ADD_FAILURE() << "not refused: " << what;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused([&] { DistributedOverlay(adj, 0.0); }, "k_loc must be > 0");
  refused([&] { DistributedOverlay(adj, -1.0); }, "k_loc must be > 0");
  refused([&] { DistributedOverlay(adj, 0.05, std::vector<std::uint8_t>(3, 0)); },
          "model-fixed flags have 3");
  refused([&] { d.prepare({0, n}); }, "loaded node 458 out of range [0, 458)");
  ASSERT_TRUE(d.prepare(loaded));  // the refusal left nothing behind: the same patch and U as before
  d.solve(F);
  EXPECT_LT((MatX3(d.displacement()) - U1).cwiseAbs().maxCoeff(), 1e-15);
}
