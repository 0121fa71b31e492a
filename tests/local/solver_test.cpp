#include "medspring/local/solver.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <string>

#include "local_fixtures.hpp"
#include "medspring/core/error.hpp"

namespace medspring {
namespace {

using testing::flat_grid;
using testing::flat_tube_positions;
using testing::grid_border;
using testing::mesh_adjacency;
using testing::window_index;

const Vec3 kUnitF = Vec3(0.36, 0.48, 0.8);  // ||F|| = 1

double max_abs(const MatX3& U) {
  return U.cwiseAbs().maxCoeff();
}

MatX3 solve_once(const LocalPatch& p, const Vec3& F, const LocalSettings& s = {}, const MatX3& X = {}) {
  LocalSolver solver;
  solver.precompute(p, X, s);
  MatX3 U;
  solver.solve(F, U);
  return U;
}

// Component along F / ||F|| of U_a, checking U_a is parallel to F (isotropic mode).
double along(const MatX3& U, Index a, const Vec3& F) {
  const Vec3 u = U.row(a).transpose(), f = F.normalized();
  EXPECT_LE(u.cross(f).norm(), 1e-15 * (1.0 + u.norm())) << "U_" << a << " not parallel to F";
  return u.dot(f);
}

void expect_rel(double got, double want, double rel) {
  EXPECT_NEAR(got, want, rel * std::abs(want)) << "got " << got << ", want " << want;
}

// §6.6 / §8.4-17
TEST(LocalSolver, FiveByFiveWindowReferenceValues) {
  const LocalPatch p = structured_window_patch(40, 30, GridNode{20, 7}, {.k_loc = 1.0});
  const MatX3 U = solve_once(p, kUnitF);
  expect_rel(along(U, window_index(0, 0), kUnitF), 39.0 / 172.0, 1e-9);
  for (const auto& o : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}})
    expect_rel(along(U, window_index(o.first, o.second), kUnitF), 21.0 / 344.0, 1e-9);
  expect_rel(along(U, window_index(1, 1), kUnitF), 5.0 / 86.0, 1e-9);
  expect_rel(along(U, window_index(-1, -1), kUnitF), 5.0 / 86.0, 1e-9);
  expect_rel(along(U, window_index(1, -1), kUnitF), 7.0 / 344.0, 1e-9);
  expect_rel(along(U, window_index(-1, 1), kUnitF), 7.0 / 344.0, 1e-9);
  for (Index a = 0; a < p.size(); ++a) {
    if (p.fixed[a] != 0) {
      EXPECT_EQ(U.row(a).norm(), 0.0);
    }
  }
}

TEST(LocalSolver, HexagonalTwoRingReferenceValues) {
  const SurfaceMesh m = tube(40, 30);
  const Adjacency adj = mesh_adjacency(m);
  const Index c = 20 * 30 + 7;
  const LocalPatch p = make_local_patch(adj, k_ring(adj, c, 2), c, 1.0);
  ASSERT_EQ(p.num_free(), 7);
  const MatX3 U = solve_once(p, kUnitF);
  expect_rel(along(U, 0, kUnitF), 2.0 / 9.0, 1e-9);
  for (Index a = 1; a <= 6; ++a) expect_rel(along(U, a, kUnitF), 1.0 / 18.0, 1e-9);
}

TEST(LocalSolver, DisplacementScalesAsForceOverStiffnessAndIsParallelToF) {
  const Vec3 F(0.0, 0.0, -0.5);  // N
  const LocalPatch p = structured_window_patch(40, 30, GridNode{20, 7}, {.k_loc = 0.05});
  const MatX3 U = solve_once(p, F);
  const double scale = F.norm() / 0.05;
  expect_rel(along(U, window_index(0, 0), F), scale * 39.0 / 172.0, 1e-9);
  expect_rel(along(U, window_index(1, 0), F), scale * 21.0 / 344.0, 1e-9);
  expect_rel(along(U, window_index(-1, -1), F), scale * 5.0 / 86.0, 1e-9);
  expect_rel(along(U, window_index(-1, 1), F), scale * 7.0 / 344.0, 1e-9);
}

struct ModeCase {
  LocalStiffness mode;
  double k_r;
};

// §8.4-18
TEST(LocalSolver, RowReplacementEqualsElimination) {
  const SurfaceMesh tb = tube(40, 30), kid = kidney_phantom();
  const Adjacency kadj = mesh_adjacency(kid);
  const std::vector<std::pair<LocalPatch, const MatX3*>> patches = {
      {structured_window_patch(40, 30, GridNode{20, 7}, {.k_loc = 1.0}), &tb.V},
      {structured_window_patch(40, 30, GridNode{1, 29}), &tb.V},
      {bfs_local_patch(kadj, kid.V, 223, {.k_loc = 0.05}), &kid.V},
      {bfs_local_patch(kadj, kid.V, 0, {.k_loc = 0.05, .count = 60}), &kid.V},
  };
  for (const ModeCase mc :
       {ModeCase{LocalStiffness::Isotropic, 0.0}, ModeCase{LocalStiffness::Linearized, 0.02},
        ModeCase{LocalStiffness::AxisProjected, 0.02}, ModeCase{LocalStiffness::PaperLiteral, 0.0}})
    for (const auto& [p, X] : patches) {
      SCOPED_TRACE(::testing::Message() << to_string(mc.mode) << " contact " << p.contact);
      LocalSettings s{.stiffness = mc.mode, .return_stiffness = mc.k_r};
      const MatX3 Ue = solve_once(p, kUnitF, s, *X);
      s.boundary = BoundaryMethod::RowReplacement;
      const MatX3 Ur = solve_once(p, kUnitF, s, *X);
      EXPECT_GT(max_abs(Ue), 0.0);
      EXPECT_LE(max_abs(Ue - Ur), 1e-12 * std::max(1.0, max_abs(Ue)));
    }
}

// §8.4-19
TEST(LocalSolver, LinearInTheForceAndZeroForZeroForce) {
  const SurfaceMesh tb = tube(40, 30);
  const LocalPatch p = structured_window_patch(40, 30, GridNode{20, 7}, {.k_loc = 0.05});
  const Vec3 F(0.1, -0.2, 0.3);
  for (const LocalStiffness mode : {LocalStiffness::Isotropic, LocalStiffness::Linearized,
                                    LocalStiffness::AxisProjected, LocalStiffness::PaperLiteral})
    for (const BoundaryMethod bc : {BoundaryMethod::Elimination, BoundaryMethod::RowReplacement}) {
      SCOPED_TRACE(::testing::Message() << to_string(mode) << " " << to_string(bc));
      LocalSolver solver;
      solver.precompute(p, tb.V, {.stiffness = mode, .boundary = bc});
      MatX3 U1, U2, U0;
      solver.solve(F, U1);
      solver.solve(2.0 * F, U2);
      solver.solve(Vec3::Zero(), U0);
      EXPECT_LE(max_abs(U2 - 2.0 * U1), 1e-12 * max_abs(U1));
      EXPECT_GT(max_abs(U1), 0.0);
      EXPECT_EQ(max_abs(U0), 0.0);
    }
}

// §8.4-20
TEST(LocalSolver, PaperLiteralReproducesThePrintedDefect) {
  const LocalPatch p = structured_window_patch(40, 30, GridNode{20, 7}, {.k_loc = 1.0});
  for (const BoundaryMethod bc : {BoundaryMethod::RowReplacement, BoundaryMethod::Elimination}) {
    LocalSolver solver;
    solver.precompute(p, {}, {.stiffness = LocalStiffness::PaperLiteral, .boundary = bc});
    MatX3 U;
    const LocalSolveInfo info = solver.solve(Vec3::UnitX(), U);
    EXPECT_NE(info.note.find("PaperLiteral"), std::string_view::npos);
    EXPECT_NE(info.note.find("comparison only"), std::string_view::npos);
    EXPECT_NEAR(U(window_index(0, 0), 0), 0.145529, 1e-6);
    EXPECT_NEAR(U(window_index(1, 0), 0), -0.027871, 1e-6);  // moves against the force
    EXPECT_NEAR(U(window_index(0, 1), 0), -0.027871, 1e-6);
    EXPECT_NEAR(U(window_index(-1, 0), 0), 0.013655, 1e-6);
    EXPECT_NEAR(U(window_index(0, -1), 0), 0.013655, 1e-6);
    // The pattern swaps between the x axis and the y, z axes.
    solver.solve(Vec3::UnitY(), U);
    EXPECT_NEAR(U(window_index(0, 0), 1), 0.145529, 1e-6);
    EXPECT_NEAR(U(window_index(1, 0), 1), 0.013655, 1e-6);
    EXPECT_NEAR(U(window_index(-1, 0), 1), -0.027871, 1e-6);
  }
  LocalSolver iso;
  iso.precompute(p);
  MatX3 U;
  EXPECT_TRUE(iso.solve(Vec3::UnitX(), U).note.empty());
}

// §8.4-21
TEST(LocalSolver, ProjectedModesWithoutReturnSpringAreSingularOnAFlatPatch) {
  const MatX3 X = flat_tube_positions(40, 30);
  const LocalPatch p = structured_window_patch(40, 30, GridNode{20, 7}, {.k_loc = 0.05});
  for (const LocalStiffness mode : {LocalStiffness::AxisProjected, LocalStiffness::Linearized})
    for (const BoundaryMethod bc : {BoundaryMethod::Elimination, BoundaryMethod::RowReplacement}) {
      LocalSolver solver;
      try {
        solver.precompute(p, X, {.stiffness = mode, .boundary = bc, .return_stiffness = 0.0});
        ADD_FAILURE() << to_string(mode) << ": no SolverError";
      } catch (const SolverError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(to_string(mode)), std::string::npos) << msg;
        EXPECT_NE(msg.find("out-of-plane force"), std::string::npos) << msg;
        EXPECT_NE(msg.find("return-spring"), std::string::npos) << msg;
      }
      EXPECT_FALSE(solver.ready());
      // With the return-spring term the out-of-plane response is the return spring alone.
      solver.precompute(p, X, {.stiffness = mode, .boundary = bc, .return_stiffness = 0.02});
      MatX3 U;
      solver.solve(Vec3(0, 0, -0.01), U);
      EXPECT_NEAR(U(window_index(0, 0), 2), -0.01 / 0.02, 1e-12);
      EXPECT_NEAR(U(window_index(1, 0), 2), 0.0, 1e-15);
    }
}

TEST(LocalSolver, StiffnessIsSymmetricExceptPaperLiteral) {
  const SurfaceMesh kid = kidney_phantom();
  const LocalPatch p = bfs_local_patch(mesh_adjacency(kid), kid.V, 223, {.k_loc = 0.05});
  for (const LocalStiffness mode :
       {LocalStiffness::Isotropic, LocalStiffness::Linearized, LocalStiffness::AxisProjected}) {
    const Eigen::MatrixXd K = local_stiffness_matrix(p, kid.V, {.stiffness = mode});
    EXPECT_EQ((K - K.transpose()).cwiseAbs().maxCoeff(), 0.0) << to_string(mode);
    EXPECT_GT(K.cwiseAbs().maxCoeff(), 0.0);
  }
  const Eigen::MatrixXd K = local_stiffness_matrix(p, kid.V, {.stiffness = LocalStiffness::PaperLiteral});
  EXPECT_GT((K - K.transpose()).cwiseAbs().maxCoeff(), 0.0);
}

TEST(LocalSolver, IsotropicStiffnessIsTheLaplacianTimesIdentity) {
  const LocalPatch p = structured_window_patch(40, 30, GridNode{20, 7}, {.k_loc = 0.7});
  const Eigen::MatrixXd K = local_stiffness_matrix(p, MatX3());
  for (Index a = 0; a < p.size(); ++a)
    for (Index b = 0; b < p.size(); ++b) {
      const Mat3 B = K.block<3, 3>(3 * a, 3 * b);
      EXPECT_EQ((B - B(0, 0) * Mat3::Identity()).cwiseAbs().maxCoeff(), 0.0);
    }
  EXPECT_NEAR(K.row(3 * window_index(0, 0)).sum(), 0.0, 1e-15);                  // Laplacian rows sum to 0
  EXPECT_DOUBLE_EQ(K(3 * window_index(0, 0), 3 * window_index(0, 0)), 6 * 0.7);  // valence 6
}

// Direct static solve of the whole spring network, independent of the local layer: K (3N x 3N) summed
// over every mesh edge, fixed DOFs eliminated, full-pivoting LU.
MatX3 direct_network_solve(const SurfaceMesh& m, const std::vector<std::uint8_t>& fixed, double k, double k_r,
                           bool linearized, Index c, const Vec3& F) {
  const Index N = m.num_vertices();
  const MatX2i E = unique_edges(m.F);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(3 * N, 3 * N);
  for (Index s = 0; s < E.rows(); ++s) {
    const Index a = E(s, 0), b = E(s, 1);
    Mat3 B = k * Mat3::Identity();
    if (linearized) {
      const Vec3 n = (m.V.row(b) - m.V.row(a)).normalized().transpose();
      B = k * n * n.transpose();
    }
    K.block<3, 3>(3 * a, 3 * a) += B;
    K.block<3, 3>(3 * b, 3 * b) += B;
    K.block<3, 3>(3 * a, 3 * b) -= B;
    K.block<3, 3>(3 * b, 3 * a) -= B;
  }
  K.diagonal().array() += k_r;
  std::vector<Index> dof;
  for (Index i = 0; i < N; ++i)
    if (!fixed[i])
      for (Index al = 0; al < 3; ++al) dof.push_back(3 * i + al);
  const Index m_ = static_cast<Index>(dof.size());
  Eigen::MatrixXd Kff(m_, m_);
  VecX Ff = VecX::Zero(m_);
  for (Index r = 0; r < m_; ++r) {
    for (Index q = 0; q < m_; ++q) Kff(r, q) = K(dof[r], dof[q]);
    if (dof[r] / 3 == c) Ff(r) = F(dof[r] % 3);
  }
  const VecX uf = Kff.fullPivLu().solve(Ff);
  MatX3 U = MatX3::Zero(N, 3);
  for (Index r = 0; r < m_; ++r) U(dof[r] / 3, dof[r] % 3) = uf(r);
  return U;
}

TEST(LocalSolver, WholeFlatGridPatchMatchesDirectSolveOfTheSpringNetwork) {
  // G = 7: 25 free nodes (dense path); G = 12: 100 free nodes (sparse Cholesky path).
  for (const Index G : {7, 12}) {
    const SurfaceMesh m = flat_grid(G);
    const Adjacency adj = mesh_adjacency(m);
    const auto border = grid_border(G);
    const Index c = 2 * G + 3;
    const Vec3 F(0.3, -0.2, 0.7);
    const LocalPatch p = bfs_local_patch(adj, m.V, c, {.k_loc = 0.7, .count = G * G}, border);
    ASSERT_EQ(p.num_free(), (G - 2) * (G - 2));
    struct Case {
      LocalStiffness mode;
      double k_r;
      bool linearized;
    };
    for (const Case cs :
         {Case{LocalStiffness::Isotropic, 0.0, false}, Case{LocalStiffness::Linearized, 0.05, true}}) {
      SCOPED_TRACE(::testing::Message() << "G = " << G << " " << to_string(cs.mode));
      const MatX3 Ud = direct_network_solve(m, border, 0.7, cs.k_r, cs.linearized, c, F);
      const MatX3 Up = solve_once(p, F, {.stiffness = cs.mode, .return_stiffness = cs.k_r}, m.V);
      double err = 0.0;
      for (Index a = 0; a < p.size(); ++a)
        err = std::max(err, (Up.row(a) - Ud.row(p.nodes[a])).cwiseAbs().maxCoeff());
      EXPECT_LE(err, 1e-9 * max_abs(Ud));
      EXPECT_GT(max_abs(Ud), 0.0);
    }
  }
}

TEST(LocalSolver, SparseAndDenseIsotropicPathsAgree) {
  const SurfaceMesh kid = kidney_phantom();
  const LocalPatch p = bfs_local_patch(mesh_adjacency(kid), kid.V, 100, {.k_loc = 0.05, .count = 120});
  ASSERT_GT(p.num_free(), 64);
  const MatX3 Us = solve_once(p, kUnitF);
  const MatX3 Ud = solve_once(p, kUnitF, {.sparse_threshold = 100000});
  EXPECT_LE(max_abs(Us - Ud), 1e-13 * max_abs(Ud));
}

TEST(LocalSolver, IsotropicResponseIsNonNegativeAndPeaksAtTheContact) {
  const SurfaceMesh kid = kidney_phantom();
  const Adjacency adj = mesh_adjacency(kid);
  for (const Index c : {0, 50, 223, 457}) {
    LocalSolver solver;
    solver.precompute(bfs_local_patch(adj, kid.V, c, {.k_loc = 0.05}));
    const VecX& g = solver.green();
    ASSERT_EQ(g.size(), 25);
    EXPECT_GE(g.minCoeff(), 0.0);  // discrete maximum principle
    EXPECT_EQ(g.maxCoeff(), g(0));
    EXPECT_GT(g(0), 0.0);
  }
}

TEST(LocalSolver, FixedContactOrNoFreeNodeGivesZeroWithoutError) {
  std::vector<std::uint8_t> fixed(1200, 0);
  for (Index j = 0; j < 30; ++j) fixed[j] = 1;
  for (const LocalStiffness mode : {LocalStiffness::Isotropic, LocalStiffness::Linearized}) {
    LocalSolver solver;
    const MatX3 X = flat_tube_positions(40, 30);
    solver.precompute(structured_window_patch(40, 30, GridNode{0, 3}, {}, fixed), X,
                      {.stiffness = mode, .return_stiffness = 0.0});
    MatX3 U;
    EXPECT_TRUE(solver.solve(Vec3(0, 0, 1), U).zero);
    EXPECT_EQ(U.rows(), 15);
    EXPECT_EQ(max_abs(U), 0.0);
    solver.precompute(structured_window_patch(40, 30, GridNode{20, 3}, {.half_width = 0}), X,
                      {.stiffness = mode});
    EXPECT_TRUE(solver.solve(Vec3(0, 0, 1), U).zero);
    EXPECT_EQ(U.rows(), 1);
    EXPECT_EQ(max_abs(U), 0.0);
  }
}

TEST(LocalSolver, IsotropicPatchWithoutFixedNodeIsReportedSingular) {
  const SurfaceMesh kid = kidney_phantom();
  const LocalPatch p = bfs_local_patch(mesh_adjacency(kid), kid.V, 10, {.count = 458});
  EXPECT_EQ(p.num_free(), 458);  // closed mesh, whole patch: no node has an outside neighbour
  for (const BoundaryMethod bc : {BoundaryMethod::Elimination, BoundaryMethod::RowReplacement}) {
    LocalSolver solver;
    try {
      solver.precompute(p, {}, {.boundary = bc});
      ADD_FAILURE() << "no SolverError";
    } catch (const SolverError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("Isotropic"), std::string::npos) << msg;
      EXPECT_NE(msg.find("not connected to any fixed node"), std::string::npos) << msg;
    }
  }
}

TEST(LocalSolver, BadInputIsRejected) {
  const LocalPatch p = structured_window_patch(40, 30, GridNode{20, 7});
  LocalSolver solver;
  MatX3 U;
  EXPECT_TRUE(solver.solve(kUnitF, U).zero);  // before precompute: nothing to do, no throw
  EXPECT_THROW(solver.precompute(p, {}, {.stiffness = LocalStiffness::Linearized}),
               InvalidInput);  // no positions
  EXPECT_THROW(solver.precompute(p, {}, {.return_stiffness = -1.0}), InvalidInput);
  EXPECT_THROW(solver.precompute(p, {}, {.pivot_tolerance = 0.0}), InvalidInput);
  MatX3 X = tube(40, 30).V;
  X.row(20 * 30 + 8) = X.row(20 * 30 + 7);  // zero-length spring
  EXPECT_THROW(solver.precompute(p, X, {.stiffness = LocalStiffness::AxisProjected}), InvalidInput);
  LocalPatch bad = p;
  bad.contact_local = 3;
  EXPECT_THROW(solver.precompute(bad), InvalidInput);
  bad = p;
  bad.k(4) = -1.0;
  EXPECT_THROW(solver.precompute(bad), InvalidInput);
}

}  // namespace
}  // namespace medspring
