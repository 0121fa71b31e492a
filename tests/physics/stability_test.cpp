// The stable-step estimate (physics/stability.hpp, docs/physics.md): the power iteration's omega_rest,
// which sets every symplectic step, bounds the true largest eigenvalue of M^-1/2 K_t M^-1/2 (Eigen's
// dense solver on small models) and stays within its 5 % safety of it.
#include "medspring/physics/stability.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"

namespace medspring {
namespace {

// sqrt of the largest eigenvalue of M^-1/2 K_t(x) M^-1/2 over the free DOFs (rad/ms), dense.
double true_omega(const Model& m, const MatX3& x) {
  const Eigen::MatrixXd K = Eigen::MatrixXd(tangent_stiffness(m, x));
  std::vector<Index> dof;
  for (Index a : m.free_nodes)
    for (int c = 0; c < 3; ++c) dof.push_back(3 * a + c);
  const auto nf = static_cast<Index>(dof.size());
  Eigen::MatrixXd A(nf, nf);
  for (Index r = 0; r < nf; ++r)
    for (Index c = 0; c < nf; ++c)
      A(r, c) = K(dof[r], dof[c]) / std::sqrt(m.mass[dof[r] / 3] * m.mass[dof[c] / 3]);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(A, Eigen::EigenvaluesOnly);
  return std::sqrt(es.eigenvalues().maxCoeff());
}

void expect_bounds(const Model& m, const MatX3& x, double omega) {
  const double w = true_omega(m, x);
  EXPECT_GE(omega, w) << m.name << ": the stable step would be too long";
  EXPECT_LE(omega, 1.05 * w * (1 + 1e-9)) << m.name;  // a Rayleigh quotient never exceeds the true value
  EXPECT_LE(w, gershgorin_omega(m, x) * (1 + 1e-9)) << m.name;
}

TEST(StableStep, PowerIterationBoundsTheDenseLargestEigenvalue) {
  SurfaceBodyParams p;
  for (Index j = 0; j < 10; ++j) p.fixed.push_back(j);
  const Model tube_m = make_surface_model(tube(14, 10, 2.5, 4.0), p, "tube");
  expect_bounds(tube_m, tube_m.x0, tube_m.omega_rest);
  SurfaceBodyParams lin;
  lin.duffing.mode = DuffingMode::Linear;
  lin.node.mass = 0.2;
  const Model sphere_m = make_surface_model(icosphere(2, 10.0), lin, "sphere");
  expect_bounds(sphere_m, sphere_m.x0, sphere_m.omega_rest);
  const Model kidney_m = make_surface_model(kidney_phantom(), {}, "kidney surface");
  expect_bounds(kidney_m, kidney_m.x0, kidney_m.omega_rest);
}

TEST(StableStep, PowerIterationBoundsTheEigenvalueOfADeformedState) {
  SurfaceBodyParams p;
  for (Index j = 0; j < 10; ++j) p.fixed.push_back(j);
  const Model m = make_surface_model(tube(14, 10, 2.5, 4.0), p, "tube");
  State st = make_state(m);
  st.f_ext.row(12 * 10 + 3) = Vec3(0.4, -1.5, 0.3).transpose();
  for (int f = 0; f < 200; ++f) ASSERT_TRUE(step(m, st, StepSettings{}).ok());
  ASSERT_GT((st.x - m.x0).cwiseAbs().maxCoeff(), 1.0);  // stretched: the Duffing springs stiffen
  expect_bounds(m, st.x, power_iteration_omega(m, st.x));
}

}  // namespace
}  // namespace medspring
