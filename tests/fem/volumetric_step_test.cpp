// The stable step of the volumetric spring organ (issue 23, docs/volumetric-speed.md "Stable step"): the
// volume term's curvature bound against its exact Hessian, and the local stiffening rule against the true
// omega_max of a loaded TetGen kidney (Lanczos on the exact Hessian at the loaded state) and against the
// global rule.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "compression_rows.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/stability.hpp"
#include "spring_kernel.hpp"  // the force pass with the stiffening optional, detail::LocalStiffening

using namespace medspring;

namespace {

// The largest eigenvalue of one volume term's exact Hessian at x is at most kv / V0 (|dV/dx|^2 + |V - V0|
// L_max / 2), the bound the stiffening uses (tet_kernel.hpp): random tetrahedra, deformations up to
// inversion.
TEST(VolumetricStep, VolumeTermCurvatureBoundHoldsForTheExactHessian) {
  std::mt19937 rng(7);
  std::normal_distribution<double> N(0.0, 1.0);
  int checked = 0;
  double tightest = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Vec3 p[4];
    for (auto& q : p) q = Vec3(N(rng), N(rng), N(rng));
    if (signed_tet_volume(p[0], p[1], p[2], p[3]) < 0) std::swap(p[1], p[2]);
    if (signed_tet_volume(p[0], p[1], p[2], p[3]) < 1e-3) continue;
    ModelBuilder b("tet");
    for (const Vec3& q : p) b.add_node(q, 1.0, 0.0, 0.0);
    b.add_volume(0, 1, 2, 3, 0.7);
    const Model m = b.build();
    MatX3 x = m.x0;
    const double amp = 0.05 + 0.6 * (trial % 10) / 10.0;
    for (Index a = 0; a < 4; ++a) x.row(a) += amp * Vec3(N(rng), N(rng), N(rng)).transpose();
    const Eigen::MatrixXd K = Eigen::MatrixXd(tangent_stiffness(m, x));
    const double lmax = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(K).eigenvalues().cwiseAbs().maxCoeff();
    const Vec3 e1 = (x.row(1) - x.row(0)).transpose(), e2 = (x.row(2) - x.row(0)).transpose(),
               e3 = (x.row(3) - x.row(0)).transpose();
    const Vec3 g1 = e2.cross(e3) / 6, g2 = e3.cross(e1) / 6, g3 = e1.cross(e2) / 6, g0 = -(g1 + g2 + g3);
    const double gg = g0.squaredNorm() + g1.squaredNorm() + g2.squaredNorm() + g3.squaredNorm();
    double L = 0;
    for (Index a = 0; a < 4; ++a)
      for (Index c = 0; c < a; ++c) L = std::max(L, (x.row(a) - x.row(c)).norm());
    const double V = e1.dot(e2.cross(e3)) / 6, V0 = m.volume.V0[0];
    const double bound = 0.7 / V0 * (gg + std::abs(V - V0) * L / 2);
    EXPECT_LE(lmax, bound * (1 + 1e-12)) << "trial " << trial;
    tightest = std::max(tightest, lmax / bound);
    ++checked;
  }
  EXPECT_GT(checked, 200);
  EXPECT_GT(tightest, 0.8);  // the bound is not loose by a large factor either
}

// A TetGen kidney (~800 nodes, supports on the bottom 20 %) pressed by a point load to equilibrium: the
// local stiffening rule keeps omega_rest sqrt(stiffening) above the true omega_max of the loaded state,
// is never above the global rule, and the run has no step trouble.
TEST(VolumetricStep, LocalStiffeningBoundsTheLoadedOmegaAndIsTighterThanTheGlobalRule) {
  const SurfaceMesh s = kidney_phantom();
  const double zmin = s.V.col(2).minCoeff(), zmax = s.V.col(2).maxCoeff();
  VolumetricSettings vs;  // 10 kPa, nu = 0.45
  vs.fixed = fem::support_nodes(s.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
  const VolumetricBody body(fem::volumetric_mesh(s, {.target_nodes = 800}), vs, "kidney");
  const Model& m = body.model();
  ASSERT_EQ(m.volume.rest_rows.size(), 4 * m.volume.packed.size());
  Index top = 0;
  for (Index i = 0; i < body.num_surface_nodes(); ++i)
    if (s.V(i, 2) > s.V(top, 2)) top = i;
  for (const double load : {0.2, 0.5, 1.0}) {
    State st = make_state(m);
    body.transfer_force(top, Vec3(0, 0, -load), st.f_ext);
    for (int i = 0; i < 400; ++i) step(m, st, {.dt = 0.5});
    // no step trouble (a 1 N point load inverts a few tetrahedra under the node: counted, not a failure)
    EXPECT_EQ(st.warnings.total() - st.warnings.inverted_elements, 0u)
        << load << " N: vmax " << st.warnings.velocity_limit << ", nonfinite " << st.warnings.nonfinite;
    EXPECT_TRUE(st.x.allFinite());
    const double local = st.stiffening;
    MatX3 f(m.num_nodes(), 3);
    const double global = detail::internal_forces(m, st.x, st.f_ext, f, true);
    const double omega_true = power_iteration_omega(m, st.x, 60, 1.0);
    EXPECT_GE(local, 1.0);
    // never more sub-steps than the global rule (the value itself may be a looser bound where the frame's
    // sub-step count does not depend on it: forces.cpp refines the bounds only where it does)
    EXPECT_LE(stable_substeps(m, local, 0.5, 0.8), stable_substeps(m, global, 0.5, 0.8)) << load << " N";
    EXPECT_GE(m.omega_rest * std::sqrt(local), omega_true) << load << " N";
    // The step scatters the local rows only where the range [s_springs, global] holds more than one
    // sub-step count of its frame: the same sub-steps as the rule always scattered (a frame of 1e12 ms
    // gives every value its own count, so the rows are always scattered), at the same state.
    // sized as State::stiff_rows (src/physics/compression_rows.hpp)
    VecX scratch = VecX::Zero(stiff_rows_size(m.num_nodes(), m.volume.size(), m.compression.size()));
    const detail::LocalStiffening gated{scratch.data(), 0.5, 0.8}, always{scratch.data(), 1e12, 0.8};
    const double s_gated = detail::internal_forces(m, st.x, st.f_ext, f, true, &gated);
    const double s_always = detail::internal_forces(m, st.x, st.f_ext, f, true, &always);
    EXPECT_LE(s_always, s_gated * (1 + 1e-12)) << load << " N";
    EXPECT_LE(stable_substeps(m, s_gated, 0.5, 0.8), stable_substeps(m, global, 0.5, 0.8)) << load << " N";
    EXPECT_EQ(stable_substeps(m, s_gated, 0.5, 0.8), stable_substeps(m, s_always, 0.5, 0.8)) << load << " N";
    EXPECT_GE(m.omega_rest * std::sqrt(s_always), omega_true) << load << " N";
    std::cout << load << " N: always scattered " << s_always << ", gated " << s_gated << "\n";
    std::cout << load << " N: stiffening local " << local << ", global " << global
              << "; omega bound / true = " << m.omega_rest * std::sqrt(local) / omega_true << "\n";
  }
}

// The springs of a volumetric model go through the gather pass (spring_gather.cpp: the volume pass writes
// State::f, the node pass adds loads, return springs and spring slots): the same motion as the scatter pass
// (internal_forces + symplectic update, the model with its gather table cleared) to rounding, the same
// sub-steps and stiffening, over 300 frames of a 0.5 N load on the 800-node kidney. The volume pass in double
// (the scatter path's internal_forces has no float pass; the float default is VolumeF32's test).
TEST(VolumetricStep, GatherPassEqualsTheScatterPassToRounding) {
  const SurfaceMesh s = kidney_phantom();
  const double zmin = s.V.col(2).minCoeff(), zmax = s.V.col(2).maxCoeff();
  VolumetricSettings vs;
  vs.volume_precision = VolumePrecision::Double;
  vs.fixed = fem::support_nodes(s.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
  const VolumetricBody body(fem::volumetric_mesh(s, {.target_nodes = 800}), vs, "kidney");
  const Model& m = body.model();
  ASSERT_FALSE(m.gather.empty());
  Model scatter = m;
  scatter.gather = SpringGather{};
  Index top = 0;
  for (Index i = 0; i < body.num_surface_nodes(); ++i)
    if (s.V(i, 2) > s.V(top, 2)) top = i;
  State a = make_state(m), b = make_state(scatter);
  body.transfer_force(top, Vec3(0, 0, -0.5), a.f_ext);
  b.f_ext = a.f_ext;
  double disp = 0;
  for (int i = 0; i < 300; ++i) {
    step(m, a, {.dt = 0.5});
    step(scatter, b, {.dt = 0.5});
    ASSERT_EQ(a.substeps, b.substeps) << "frame " << i;
    disp = std::max(disp, (b.x - m.x0).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(disp, 1.0);  // the load moved the kidney by millimetres
  EXPECT_LE((a.x - b.x).cwiseAbs().maxCoeff(), 1e-9 * disp);
  EXPECT_LE((a.v - b.v).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + b.v.cwiseAbs().maxCoeff()));
  EXPECT_NEAR(a.stiffening, b.stiffening, 1e-9 * b.stiffening);
  EXPECT_EQ(a.warnings.total(), b.warnings.total());
}

}  // namespace
