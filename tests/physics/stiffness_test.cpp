// Forces, energy and tangent stiffness: invariants and finite-difference checks.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/forces.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

using testing::jitter;

Model perturbed_kidney_model(DuffingSettings d, double kr) {
  SurfaceBodyParams p;
  p.duffing = d;
  p.node.return_k = kr;
  return make_surface_model(kidney_phantom(), p);
}

TEST(Forces, ZeroAtRestAndUnderRigidMotion) {
  const Model m = perturbed_kidney_model({}, 0.0);
  MatX3 f(m.num_nodes(), 3);
  const MatX3 zero = MatX3::Zero(m.num_nodes(), 3);
  internal_forces(m, m.x0, zero, f);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-15);
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  MatX3 x = (m.x0 * R.transpose()).rowwise() + Eigen::RowVector3d(5, -3, 2);
  internal_forces(m, x, zero, f);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-12);
  const Model mr = perturbed_kidney_model({}, 0.02);
  internal_forces(mr, mr.x0, zero, f);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(potential_energy(mr, mr.x0), 0.0);
}

TEST(Forces, ForcesAreMinusTheEnergyGradient) {
  for (auto d :
       {DuffingSettings{.mode = DuffingMode::Linear}, DuffingSettings{}, DuffingSettings{.soft = true}}) {
    const Model m = perturbed_kidney_model(d, 0.02);
    const MatX3 x = jitter(m.x0, 0.5, 3);
    MatX3 f(m.num_nodes(), 3);
    internal_forces(m, x, MatX3::Zero(m.num_nodes(), 3), f);
    const double h = 1e-6;
    for (Index q = 0; q < 3 * m.num_nodes(); q += 37) {
      MatX3 xp = x, xm = x;
      xp.data()[q] += h;
      xm.data()[q] -= h;
      const double g = (potential_energy(m, xp) - potential_energy(m, xm)) / (2 * h);
      EXPECT_NEAR(-g, f.data()[q], 1e-6 * (1 + std::abs(g))) << "dof " << q;
    }
  }
}

TEST(Forces, TangentStiffnessMatchesFiniteDifferences) {
  for (auto d : {DuffingSettings{.mode = DuffingMode::Linear}, DuffingSettings{},
                 DuffingSettings{.mode = DuffingMode::Absolute}}) {
    const Model m = perturbed_kidney_model(d, 0.02);
    const MatX3 x = jitter(m.x0, 0.8, 7);
    const Eigen::MatrixXd K = Eigen::MatrixXd(tangent_stiffness(m, x));
    EXPECT_LT((K - K.transpose()).cwiseAbs().maxCoeff(), 1e-14);
    const MatX3 zero = MatX3::Zero(m.num_nodes(), 3);
    MatX3 fp(m.num_nodes(), 3), fm(m.num_nodes(), 3);
    const double h = 1e-6;
    double err = 0, scale = K.cwiseAbs().maxCoeff();
    for (Index q = 0; q < 3 * m.num_nodes(); q += 11) {
      MatX3 xp = x, xm = x;
      xp.data()[q] += h;
      xm.data()[q] -= h;
      internal_forces(m, xp, zero, fp);
      internal_forces(m, xm, zero, fm);
      const VecX col = -(flat(fp) - flat(fm)) / (2 * h);
      err = std::max(err, (col - K.col(q)).cwiseAbs().maxCoeff());
    }
    EXPECT_LT(err, 1e-7 * scale);
  }
}

TEST(Forces, ClampedStiffnessIsPositiveSemidefinite) {
  const Model m = perturbed_kidney_model({}, 0.0);
  MatX3 x = m.x0 * 0.8;  // compressed: phi/L < 0 makes the exact K indefinite
  const Eigen::MatrixXd K = Eigen::MatrixXd(tangent_stiffness(m, x, {.clamp_transverse = true}));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(K);
  EXPECT_GT(es.eigenvalues().minCoeff(), -1e-10);
  const Eigen::MatrixXd Ke = Eigen::MatrixXd(tangent_stiffness(m, x));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ee(Ke);
  EXPECT_LT(ee.eigenvalues().minCoeff(), -1e-6);
}

TEST(Forces, ZeroLengthSpringIsSkipped) {
  ModelBuilder b("coincident");
  b.add_node(Vec3(0, 0, 0), 1, 0, 0);
  b.add_node(Vec3(1, 0, 0), 1, 0, 0);
  b.add_spring(0, 1, 1.0, 0.0, 1.0);
  const Model m = b.build();
  MatX3 x = MatX3::Zero(2, 3);  // both nodes at the origin: direction undefined
  MatX3 f(2, 3);
  internal_forces(m, x, MatX3::Zero(2, 3), f);
  EXPECT_TRUE(f.allFinite());
  EXPECT_EQ(f.norm(), 0.0);
}

}  // namespace
}  // namespace medspring
