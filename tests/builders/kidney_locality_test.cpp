// Issue 15, locality of the hybrid kidney built from a user's own mesh: the real kidney surface
// (kidney_left_hubmap_vhm.obj as read, 5,002 nodes) with its numbering shuffled is simulated in reverse
// Cuthill-McKee order behind HybridKidney's surface <-> DOF map; everything a user gives or reads (fixed
// nodes, loads, spokes, surface, fixed_surface_nodes) stays in the mesh's numbering, and the motion is
// the one of the same model built without renumbering, to rounding.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdio>
#include <limits>
#include <numeric>
#include <random>

#include "medspring/builders/organ_source.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/locality.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/sim/simulation.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

constexpr Index kNever = std::numeric_limits<Index>::max();

// Mean |i - j| over a mesh's edges (how far apart neighbours are stored, on average).
double mean_edge_span(const SurfaceMesh& m) {
  const MatX2i E = unique_edges(m.F);
  double s = 0;
  for (Index e = 0; e < E.rows(); ++e) s += static_cast<double>(std::abs(E(e, 0) - E(e, 1)));
  return s / static_cast<double>(E.rows());
}

struct ShuffledKidney {
  SurfaceMesh surface;  // the real kidney surface (mm), numbering shuffled
  MatX3 atoms;          // 20 atoms along its principal axis
};

const ShuffledKidney& shuffled_kidney() {
  static const ShuffledKidney k = [] {
    const LoadedOrgan organ = load_organ(
        {.mesh = testing::require_data_file("kidney_left_hubmap_vhm.obj"), .unit = LengthUnit::Metre});
    std::vector<Index> order(static_cast<std::size_t>(organ.surface.num_vertices()));
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), std::mt19937_64(15));
    ShuffledKidney out{permute_vertices(organ.surface, order), MatX3(20, 3)};
    const MatX3& V = out.surface.V;
    const Vec3 c = V.colwise().mean().transpose();
    const MatX3 D = V.rowwise() - c.transpose();
    const Eigen::SelfAdjointEigenSolver<Mat3> eig(D.transpose() * D);
    const Vec3 axis = eig.eigenvectors().col(2);  // largest variance
    const double half = (D * axis).cwiseAbs().maxCoeff();
    for (Index a = 0; a < 20; ++a)
      out.atoms.row(a) = (c + axis * half * (-0.6 + 1.2 * static_cast<double>(a) / 19.0)).transpose();
    return out;
  }();
  return k;
}

TEST(KidneyLocality, RcmOrderOfAShuffledRealKidneyBringsNeighboursTogether) {
  const SurfaceMesh& s = shuffled_kidney().surface;
  ASSERT_EQ(s.num_vertices(), 5002);
  const std::vector<Index> order = locality_order(s);
  std::vector<Index> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (Index k = 0; k < s.num_vertices(); ++k) ASSERT_EQ(sorted[static_cast<std::size_t>(k)], k);
  const SurfaceMesh r = permute_vertices(s, order);
  std::printf("real kidney, shuffled: bandwidth %ld, mean edge span %.1f; RCM: %ld, %.1f\n",
              static_cast<long>(mesh_bandwidth(s)), mean_edge_span(s), static_cast<long>(mesh_bandwidth(r)),
              mean_edge_span(r));
  // shuffled: neighbours ~ a third of the mesh apart; RCM: within a band of about two level sets
  EXPECT_GT(mesh_bandwidth(s), 4000);
  EXPECT_GT(mean_edge_span(s), 1000.0);
  EXPECT_LT(10 * mesh_bandwidth(r), mesh_bandwidth(s));
  EXPECT_LT(10.0 * mean_edge_span(r), mean_edge_span(s));
}

TEST(KidneyLocality, ShuffledRealKidneySimulatesInRcmOrderWithTheUsersNumbering) {
  const ShuffledKidney& k = shuffled_kidney();
  const Index ns = k.surface.num_vertices();
  HybridSettings hs;
  // pin the 12 lowest nodes (user numbering)
  std::vector<Index> by_z(static_cast<std::size_t>(ns));
  std::iota(by_z.begin(), by_z.end(), 0);
  std::sort(by_z.begin(), by_z.end(),
            [&](Index a, Index b) { return k.surface.V(a, 2) < k.surface.V(b, 2); });
  hs.fixed.assign(by_z.begin(), by_z.begin() + 12);
  hs.fixed_atoms = {0};

  // default threshold (20,000 nodes): a 5,002-node mesh keeps its numbering
  EXPECT_TRUE(HybridKidney(k.surface, k.atoms, hs, "kept").dof_of_surface().empty());
  auto plain = std::make_shared<HybridKidney>(k.surface, k.atoms, hs, "plain", nullptr, kNever);
  auto local = std::make_shared<HybridKidney>(k.surface, k.atoms, hs, "local", nullptr, 0);
  ASSERT_TRUE(plain->dof_of_surface().empty());
  const std::vector<Index>& dof = local->dof_of_surface();
  ASSERT_EQ(static_cast<Index>(dof.size()), ns);
  std::vector<Index> sorted = dof;
  std::sort(sorted.begin(), sorted.end());
  for (Index v = 0; v < ns; ++v) ASSERT_EQ(sorted[static_cast<std::size_t>(v)], v);

  // what users read is in their numbering, and equal
  EXPECT_EQ(local->rest_surface(), k.surface.V);
  EXPECT_EQ(local->faces(), k.surface.F);
  EXPECT_EQ(local->spokes(), plain->spokes());
  EXPECT_EQ(local->fixed_surface_nodes(), plain->fixed_surface_nodes());
  for (Index v = 0; v < ns; ++v) EXPECT_EQ(local->spoke_length(v), plain->spoke_length(v));
  EXPECT_EQ(local->stats().spokes, plain->stats().spokes);
  EXPECT_EQ(local->model().num_springs(), plain->model().num_springs());
  EXPECT_EQ(local->model().x0.bottomRows(20), k.atoms);
  for (Index v = 0; v < ns; ++v) EXPECT_EQ(local->model().x0.row(local->dof_of(v)), k.surface.V.row(v));

  // the model is in locality order: every spring's ends are close in the DOF numbering
  Index plain_span = 0, local_span = 0;
  for (Index s = 0; s < plain->model().num_springs(); ++s) {
    const auto span = [&](const Model& m) {
      const Index i = m.springs.i[static_cast<std::size_t>(s)], j = m.springs.j[static_cast<std::size_t>(s)];
      return i < ns && j < ns ? std::abs(i - j) : 0;  // surface springs
    };
    plain_span = std::max(plain_span, span(plain->model()));
    local_span = std::max(local_span, span(local->model()));
  }
  EXPECT_LT(10 * local_span, plain_span);

  // 200 updates under two loads in the user's numbering: the same motion to rounding
  Simulation a(plain), b(local);
  const Index n1 = by_z.back(), n2 = by_z[static_cast<std::size_t>(ns / 2)];
  const std::vector<PointLoad> loads{{.node = n1, .force = Vec3(0.02, 0, -0.3), .t_ramp = 20},
                                     {.node = n2, .force = Vec3(0.1, 0.05, 0), .t_ramp = 0}};
  a.set_loads(loads);
  b.set_loads(loads);
  a.advance(200);
  b.advance(200);
  EXPECT_EQ(a.state().substeps, b.state().substeps);
  const double scale = (a.surface() - k.surface.V).cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0.5);  // mm: the loads moved the kidney
  EXPECT_LT((a.surface() - b.surface()).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + scale));
  EXPECT_LT((a.state().x.bottomRows(20) - b.state().x.bottomRows(20)).cwiseAbs().maxCoeff(),
            1e-12 * (1.0 + scale));
  const double vscale = a.state().v.cwiseAbs().maxCoeff();
  ASSERT_GT(vscale, 0.0);
  // the floor: velocities near rest are sums of opposing spring forces of ~1 N, so a different
  // summation order (the node order) leaves ~1e-16 N x h / m; 1e-13 was reached (1.01e-13) once the
  // fused step's vectorised tensions (docs/threads.md) changed the FMA contraction
  for (Index v = 0; v < ns; ++v)
    ASSERT_LT((a.state().v.row(v) - b.state().v.row(local->dof_of(v))).cwiseAbs().maxCoeff(),
              1e-10 * vscale + 5e-13)
        << v;
  for (const Index f : hs.fixed) EXPECT_EQ(b.surface().row(f), k.surface.V.row(f));

  // bad fixed indices are named in the user's numbering, before any renumbering
  HybridSettings bad = hs;
  bad.fixed.push_back(ns + 3);
  try {
    HybridKidney x(k.surface, k.atoms, bad, "bad", nullptr, 0);
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("fixed[12]"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace medspring
