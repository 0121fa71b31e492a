// Bending stiffness of the SMRM centerline from the vessel wall (issue 17, docs/vessels.md):
// k_b,i = E I_i / h_i^3 with I of a hollow tube, zero force at the (curved) rest shape, forces and
// stiffness checked against finite differences, the stable step, k_b = 0 as the paper-literal chain,
// the per-update validity rho kappa < 1 and the model package round trip.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "medspring/core/error.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/stability.hpp"

namespace medspring {
namespace {

TEST(SmrmBending, WallStiffnessIsEIOfAHollowTubeOverTheAtomLengthCubed) {
  const Index n = 6;
  MatX3 C(n, 3);
  for (Index i = 0; i < n; ++i) C.row(i) << 2.5 * static_cast<double>(i), 0.0, 0.0;
  VecX r = VecX::Constant(n, 4.0);
  r[3] = 2.0;
  const WallSettings wall{.E = 0.4, .thickness_ratio = 0.25};
  const VecX kb = wall_bending_stiffness(C, r, wall);
  ASSERT_EQ(kb.size(), n);
  EXPECT_EQ(kb[0], 0.0);
  EXPECT_EQ(kb[n - 1], 0.0);
  const double I4 = std::numbers::pi / 4.0 * (std::pow(5.0, 4) - std::pow(4.0, 4));  // r_o = 5, r_i = 4
  EXPECT_NEAR(kb[1], 0.4 * I4 / std::pow(2.5, 3), 1e-12);
  const double I2 = std::numbers::pi / 4.0 * (std::pow(2.5, 4) - std::pow(2.0, 4));
  EXPECT_NEAR(kb[3], 0.4 * I2 / std::pow(2.5, 3), 1e-12);
  // Linear in E, fourth power in the radius, inverse cube in the spacing.
  const VecX kb2 = wall_bending_stiffness(2.0 * C, 2.0 * r, {.E = 0.8, .thickness_ratio = 0.25});
  EXPECT_NEAR(kb2[1] / kb[1], 2.0 * 16.0 / 8.0, 1e-12);
  EXPECT_THROW(wall_bending_stiffness(C, r, {.E = 0.0}), InvalidInput);
  EXPECT_THROW(wall_bending_stiffness(C, r, {.E = 0.5, .thickness_ratio = -1.0}), InvalidInput);
  r[2] = std::nan("");
  EXPECT_THROW(wall_bending_stiffness(C, r, wall), InvalidInput);
}

TEST(SmrmBending, DefaultVesselBendsFromItsWallAndTheRestShapeHasNoForce) {
  for (VesselPath p : {VesselPath::Arc, VesselPath::Helix}) {
    const SmrmVessel v = smrm_phantom(p, CrossSectionShape::Circular);
    EXPECT_EQ(v.settings().bending, BendingMode::Wall);
    EXPECT_EQ(v.model().bending.size(), v.num_atoms() - 2);
    EXPECT_GT(v.bending_stiffness().segment(1, v.num_atoms() - 2).minCoeff(), 0.0);
    // Curved rest shape: the bending terms are zero there (rest curvature is the zero).
    const MatX3 zero = MatX3::Zero(v.num_atoms(), 3);
    MatX3 f(v.num_atoms(), 3);
    internal_forces(v.model(), v.model().x0, zero, f);
    EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-12) << to_string(p);
    EXPECT_NEAR(potential_energy(v.model(), v.model().x0), 0.0, 1e-15);
  }
}

TEST(SmrmBending, ForcesAreMinusTheEnergyGradientAndTheStiffnessItsDerivative) {
  const SmrmVessel v = smrm_phantom(VesselPath::Helix, CrossSectionShape::Circular);
  const Model& m = v.model();
  const Index n = m.num_nodes();
  MatX3 x = m.x0;
  for (Index i = 1; i + 1 < n; ++i)  // a deterministic, non-trivial bend
    x.row(i) +=
        Vec3(0.3 * std::sin(0.7 * static_cast<double>(i)), 0.2 * std::cos(1.3 * static_cast<double>(i)),
             0.1 * std::sin(2.1 * static_cast<double>(i)))
            .transpose();
  const MatX3 zero = MatX3::Zero(n, 3);
  MatX3 f(n, 3);
  internal_forces(m, x, zero, f);
  const double h = 1e-6;
  double worst = 0.0, scale = 0.0;
  for (Index i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      MatX3 xp = x, xm = x;
      xp(i, c) += h;
      xm(i, c) -= h;
      const double g = (potential_energy(m, xp) - potential_energy(m, xm)) / (2 * h);
      worst = std::max(worst, std::abs(f(i, c) + g));
      scale = std::max(scale, std::abs(g));
    }
  EXPECT_GT(scale, 1e-3);                 // the bend is felt
  EXPECT_LT(worst, 1e-6 * scale + 1e-8);  // central differences, O(h^2)
  // The tangent stiffness K_t z (used by the implicit integrator and the stable step) against the
  // difference of the forces along z.
  MatX3 z(n, 3);
  for (Index i = 0; i < n; ++i)
    z.row(i) << std::sin(1.0 + static_cast<double>(i)), std::cos(2.0 * static_cast<double>(i)), 0.5;
  MatX3 fp(n, 3), fm(n, 3);
  internal_forces(m, x + h * z, zero, fp);
  internal_forces(m, x - h * z, zero, fm);
  const Eigen::SparseMatrix<double> K = tangent_stiffness(m, x);  // dof 3 a + c (row-major MatX3)
  const MatX3 fd = -(fp - fm) / (2 * h);
  const VecX Kz = K * Eigen::Map<const VecX>(z.data(), 3 * n);
  const VecX fdv = Eigen::Map<const VecX>(fd.data(), 3 * n);
  EXPECT_LT((Kz - fdv).cwiseAbs().maxCoeff(), 1e-5 * fdv.cwiseAbs().maxCoeff());
}

TEST(SmrmBending, StableStepAccountsForTheBendingTermsAndTheRunStaysStable) {
  SmrmSettings paper;
  paper.bending = BendingMode::Constant;
  paper.chain.kb = 0.0;
  const SmrmVessel flexible = smrm_phantom(VesselPath::Arc, CrossSectionShape::Circular, paper);
  const SmrmVessel stiff = smrm_phantom(VesselPath::Arc, CrossSectionShape::Circular);
  const double kb = stiff.bending_stiffness().maxCoeff();
  // Gershgorin: bending adds 16 k_b to the row bound, so omega^2 grows by about 16 k_b / m.
  EXPECT_GT(stiff.model().omega_rest, flexible.model().omega_rest);
  EXPECT_GE(stiff.model().omega_rest * stiff.model().omega_rest, 16.0 * kb / paper.chain.mass * 0.99);
  EXPECT_LT(dt_safe(stiff.model(), 1.0), dt_safe(flexible.model(), 1.0));
  // A 0.5 ms frame is split into stable substeps: a strong force, held, then released, ends at rest.
  const Model& m = stiff.model();
  State s = make_state(m);
  const std::vector<PointLoad> loads{{.node = 20, .force = Vec3(0, 0, 0.5), .t_ramp = 20, .t_release = 200}};
  for (int k = 0; k < 1600; ++k) step(m, s, {.dt = 0.5}, &loads);
  EXPECT_EQ(s.warnings.total(), 0u);
  EXPECT_GT(s.substeps, 1600u);
  EXPECT_LT((s.x - m.x0).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(SmrmBending, KbZeroIsThePaperChain) {
  SmrmSettings paper;
  paper.bending = BendingMode::Constant;
  paper.chain.kb = 0.0;
  const SmrmVessel v = smrm_phantom(VesselPath::Arc, CrossSectionShape::Circular, paper);
  EXPECT_EQ(v.model().bending.size(), 0);
  EXPECT_EQ(v.bending_stiffness().cwiseAbs().maxCoeff(), 0.0);
  const Model chain = make_chain_model(v.rest_atoms(), paper.chain, v.name());
  EXPECT_EQ(model_fingerprint(v.model()), model_fingerprint(chain));
  // A constant k_b is the §5.2 option at every interior atom.
  paper.chain.kb = 0.3;
  const SmrmVessel c = smrm_phantom(VesselPath::Arc, CrossSectionShape::Circular, paper);
  ASSERT_EQ(c.model().bending.size(), c.num_atoms() - 2);
  EXPECT_EQ(c.model().bending.kb.maxCoeff(), 0.3);
  EXPECT_EQ(c.model().bending.kb.minCoeff(), 0.3);
}

TEST(SmrmBending, ValidityAndTurningAngleAreMeasuredPerUpdate) {
  SmrmSettings paper;
  paper.bending = BendingMode::Constant;
  const SmrmVessel v = smrm_phantom(VesselPath::StraightX, CrossSectionShape::Circular, paper);
  const MatX3& C0 = v.rest_atoms();
  EXPECT_EQ(v.validity(C0).violations, 0);
  EXPECT_NEAR(v.max_turning_change_deg(C0), 0.0, 1e-12);
  // Kink atom 20 by 90 degrees: turning angle 90, kappa = 2 sin 45 / h.
  MatX3 C = C0;
  const double h = (C0.row(1) - C0.row(0)).norm();
  for (Index i = 21; i < C.rows(); ++i)
    C.row(i) = C0.row(20) + Eigen::RowVector3d(0, h * static_cast<double>(i - 20), 0);
  Index atom = -1;
  EXPECT_NEAR(v.max_turning_change_deg(C, &atom), 90.0, 1e-9);
  EXPECT_EQ(atom, 20);
  const CurvatureCheck c = v.validity(C);
  EXPECT_NEAR(c.max_rho_kappa, v.max_spoke()[20] * 2.0 * std::sin(std::numbers::pi / 4) / h, 1e-9);
  EXPECT_EQ(c.violations, c.max_rho_kappa >= 1.0 ? 1 : 0);
  EXPECT_EQ(c.first_atom, c.violations > 0 ? 20 : -1);
}

TEST(SmrmBending, ModelPackageKeepsTheBendingSettings) {
  SmrmSettings s;
  s.wall.E = 0.7;
  s.wall.thickness_ratio = 0.2;
  const SmrmVessel v = smrm_phantom(VesselPath::Helix, CrossSectionShape::Elliptical, s);
  const ModelPackage p = decode_model_package(encode_model_package(package_of(v, "helix")));
  EXPECT_EQ(p.smrm.bending, BendingMode::Wall);
  EXPECT_EQ(p.smrm.wall.E, 0.7);
  EXPECT_EQ(p.smrm.wall.thickness_ratio, 0.2);
  const BodyPtr b = make_body(p);
  EXPECT_EQ(model_fingerprint(b->model()), model_fingerprint(v.model()));
  EXPECT_TRUE(check_fingerprint(p, *b));
}

}  // namespace
}  // namespace medspring
