// Nodal volume terms (average nodal pressure, physics/nodal_volume.hpp): energy, forces against central
// differences, rest stiffness against the forces' differences, momentum, and the single-tetrahedron limit.
#include "medspring/physics/nodal_volume.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "medspring/core/error.hpp"
#include "medspring/physics/volume_terms.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

using testing::jitter;

// An n x n x n grid of unit cubes (edge h), each split into six tetrahedra around its main diagonal.
void grid(int n, double h, MatX3& X, MatX4i& T) {
  const int p = n + 1;
  X.resize(p * p * p, 3);
  auto id = [&](int i, int j, int k) { return (k * p + j) * p + i; };
  for (int k = 0; k < p; ++k)
    for (int j = 0; j < p; ++j)
      for (int i = 0; i < p; ++i) X.row(id(i, j, k)) << h * i, h * j, h * k;
  static constexpr int kPath[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  T.resize(6 * n * n * n, 4);
  int t = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& path : kPath) {
          int c[3] = {i, j, k};
          T(t, 0) = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[path[s]];
            T(t, s + 1) = id(c[0], c[1], c[2]);
          }
          ++t;
        }
}

struct Fixture {
  MatX3 X;
  MatX4i T;
  NodalVolumeTerms N;
  Fixture() {
    grid(2, 3.0, X, T);
    X = jitter(X, 0.4, 7);  // irregular tetrahedra
    std::vector<double> kv(static_cast<std::size_t>(T.rows()));
    for (std::size_t e = 0; e < kv.size(); ++e) kv[e] = 0.01 * (1.0 + 0.5 * static_cast<double>(e % 3));
    N = make_nodal_volume_terms(X, T, kv, "test");
  }
};

TEST(NodalVolume, UniformDeformationStoresTheBulkEnergyOfTheWholeVolume) {
  // under x = A x0 every tetrahedron's volume is det(A) V0, so every J_a = det(A) and the energy is
  // 1/2 k V (det A - 1)^2 exactly, with one modulus
  MatX3 X;
  MatX4i T;
  grid(2, 3.0, X, T);
  X = jitter(X, 0.4, 3);
  const NodalVolumeTerms N = make_nodal_volume_terms(X, T, std::vector<double>(T.rows(), 0.02), "test");
  Mat3 A;
  A << 1.03, 0.02, -0.01, 0.01, 0.98, 0.015, -0.02, 0.01, 1.05;
  const MatX3 x = X * A.transpose();
  double V = 0;
  for (double v : N.V0) V += v;
  EXPECT_NEAR(nodal_volume_energy(N, x), 0.5 * 0.02 * V * std::pow(A.determinant() - 1, 2), 1e-12 * 0.02 * V);
  EXPECT_NEAR(nodal_volume_energy(N, X), 0.0, 1e-15);
}

TEST(NodalVolume, OneTetrahedronIsThePerTetrahedronTerm) {
  MatX3 X(4, 3);
  X << 0, 0, 0, 2.1, 0.2, -0.1, 0.3, 1.8, 0.2, -0.2, 0.4, 2.5;
  MatX4i T(1, 4);
  T << 0, 1, 2, 3;
  const NodalVolumeTerms N = make_nodal_volume_terms(X, T, {0.03}, "test");
  VolumeTerms vt;
  vt.add(0, 1, 2, 3, 0.03);
  finalize_volume_terms(vt, X, "test");
  const MatX3 x = jitter(X, 0.3, 11);
  EXPECT_NEAR(nodal_volume_energy(N, x), volume_energy(vt, x), 1e-14);
  MatX3 f = MatX3::Zero(4, 3), g = MatX3::Zero(4, 3);
  VecX W;
  add_nodal_volume_forces(N, x, f, W);
  add_volume_forces(vt, x.data(), g.data(), false);
  EXPECT_LT((f - g).norm(), 1e-13);
}

TEST(NodalVolume, ForcesAreMinusTheEnergyGradientAndConserveMomentum) {
  const Fixture fx;
  const MatX3 x = jitter(fx.X, 0.3, 5);
  MatX3 f = MatX3::Zero(x.rows(), 3);
  VecX W;
  add_nodal_volume_forces(fx.N, x, f, W);
  const double h = 1e-6;
  double fmax = f.cwiseAbs().maxCoeff(), err = 0;
  for (Index i = 0; i < x.size(); ++i) {
    MatX3 xp = x, xm = x;
    xp.data()[i] += h;
    xm.data()[i] -= h;
    const double d = -(nodal_volume_energy(fx.N, xp) - nodal_volume_energy(fx.N, xm)) / (2 * h);
    err = std::max(err, std::abs(d - f.data()[i]));
  }
  EXPECT_LT(err, 1e-6 * fmax);
  EXPECT_GT(fmax, 1e-4);  // the state is loaded
  // linear and angular momentum: the forces sum to zero, and so do their moments
  EXPECT_LT(f.colwise().sum().norm(), 1e-12 * fmax * static_cast<double>(x.rows()));
  Vec3 M = Vec3::Zero();
  for (Index a = 0; a < x.rows(); ++a) M += x.row(a).transpose().cross(f.row(a).transpose());
  EXPECT_LT(M.norm(), 1e-11 * fmax * static_cast<double>(x.rows()) * 6.0);
}

TEST(NodalVolume, RestStiffnessIsTheForcesDerivative) {
  const Fixture fx;
  std::vector<Eigen::Triplet<double>> trip;
  add_nodal_volume_stiffness_triplets(fx.N, fx.X, trip);
  const Index n3 = 3 * static_cast<Index>(fx.X.rows());
  Eigen::SparseMatrix<double> K(n3, n3);
  K.setFromTriplets(trip.begin(), trip.end());
  const Eigen::MatrixXd Kd(K);
  EXPECT_LT((Kd - Kd.transpose()).norm(), 1e-14 * Kd.norm());
  const double h = 1e-6;
  double err = 0;
  VecX W;
  for (Index i = 0; i < n3; ++i) {
    MatX3 xp = fx.X, xm = fx.X, fp = MatX3::Zero(fx.X.rows(), 3), fm = fp;
    xp.data()[i] += h;
    xm.data()[i] -= h;
    add_nodal_volume_forces(fx.N, xp, fp, W);
    add_nodal_volume_forces(fx.N, xm, fm, W);
    const VecX col = -(flat(fp) - flat(fm)) / (2 * h);
    err = std::max(err, (col - Kd.col(i)).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(err, 1e-6 * Kd.cwiseAbs().maxCoeff());
  // positive semi-definite, with rigid motions in its null space
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Kd);
  EXPECT_GT(es.eigenvalues().minCoeff(), -1e-12 * es.eigenvalues().maxCoeff());
}

// Cauchy-Schwarz per node: (sum_e dV_e)^2 <= sum_e V_e sum_e dV_e^2 / V_e, so with one modulus the nodal
// rest stiffness is below the per-tetrahedron one in the Loewner order: the body can only get softer.
TEST(NodalVolume, WithOneModulusTheRestStiffnessIsBelowThePerTetrahedronOne) {
  MatX3 X;
  MatX4i T;
  grid(2, 3.0, X, T);
  X = jitter(X, 0.4, 9);
  const NodalVolumeTerms N = make_nodal_volume_terms(X, T, std::vector<double>(T.rows(), 0.02), "test");
  VolumeTerms vt;
  for (Index e = 0; e < N.T.rows(); ++e) vt.add(N.T(e, 0), N.T(e, 1), N.T(e, 2), N.T(e, 3), 0.02);
  finalize_volume_terms(vt, X, "test");
  std::vector<Eigen::Triplet<double>> tn, tt;
  add_nodal_volume_stiffness_triplets(N, X, tn);
  add_volume_stiffness_triplets(vt, X, tt);
  const Index n3 = 3 * static_cast<Index>(X.rows());
  Eigen::SparseMatrix<double> Kn(n3, n3), Kt(n3, n3);
  Kn.setFromTriplets(tn.begin(), tn.end());
  Kt.setFromTriplets(tt.begin(), tt.end());
  const Eigen::MatrixXd D = Eigen::MatrixXd(Kt) - Eigen::MatrixXd(Kn);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(D);
  EXPECT_GT(es.eigenvalues().minCoeff(), -1e-12 * Eigen::MatrixXd(Kt).norm());
  EXPECT_GT(es.eigenvalues().maxCoeff(), 1e-3 * Eigen::MatrixXd(Kt).norm());  // and strictly softer
}

TEST(NodalVolume, BadTetrahedraAreRefusedWithTheDefectNamed) {
  MatX3 X(4, 3);
  X << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0;  // flat
  MatX4i T(1, 4);
  T << 0, 1, 2, 3;
  EXPECT_THROW(make_nodal_volume_terms(X, T, {0.01}, "test"), InvalidInput);
  X(3, 2) = 1;
  T(0, 3) = 4;  // not a node
  EXPECT_THROW(make_nodal_volume_terms(X, T, {0.01}, "test"), InvalidInput);
  T(0, 3) = 3;
  EXPECT_THROW(make_nodal_volume_terms(X, T, {-1.0}, "test"), InvalidInput);
  EXPECT_NO_THROW(make_nodal_volume_terms(X, T, {0.01}, "test"));
}

}  // namespace
}  // namespace medspring
