// The thin-tetrahedron term as part of the volumetric model (issue 23, VolumetricSettings::thin_tet,
// docs/volumetric-mesh.md "A correction term for thin tetrahedra"): through the MODEL (VolumetricBody, its
// forces, energy, static solve and step), a box of flat cells under uniform stress against linear elasticity
// (P1 represents the uniform strain exactly, so rule + term must give E, nu and mu exactly), forces against
// the energy, momentum, an undamped step's energy, large strain without blow-up, the implicit step, the
// fingerprint and model package, and the refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "medspring/core/params.hpp"
#include "medspring/fem/tet_mesh.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/static_solve.hpp"
#include "volumetric_box.hpp"

using namespace medspring;
using medspring::testing::box;

namespace {

// The unit cube of 3 x 3 x 30 cells: every Kuhn tetrahedron flat (h/L < 0.1).
VolumetricMesh flat_cube() {
  return box(fem::graded(0, 1, 3), fem::graded(0, 1, 3), fem::graded(0, 1, 30));
}

VolumetricSettings settings(ThinTetMode mode, double q_max = kDefaultThinTetQMax) {
  VolumetricSettings s;
  s.E_kPa = 10;
  s.nu = 0.45;
  s.compression = 0;  // the small-strain comparison: no stiffening (it is zero at rest anyway)
  s.return_k = 1e-9;  // against rigid motion only
  s.thin_tet = mode;
  s.thin_tet_q_max = q_max;
  return s;
}

// Nodal forces of the traction t (N/mm^2, constant) on the boundary faces with outward normal n.
void add_traction(const VolumetricMesh& vm, const Vec3& n, const Vec3& t, MatX3& f) {
  const Vec3 c = vm.X.colwise().mean().transpose();
  for (Index k = 0; k < vm.F.rows(); ++k) {
    const Vec3 a = vm.X.row(vm.F(k, 0)), b = vm.X.row(vm.F(k, 1)), d = vm.X.row(vm.F(k, 2));
    Vec3 nf = (b - a).cross(d - a);
    const double A = 0.5 * nf.norm();
    nf.normalize();
    if ((a - c).dot(nf) < 0) nf = -nf;  // outward
    if (nf.dot(n) < 1 - 1e-9) continue;
    for (int j = 0; j < 3; ++j) f.row(vm.F(k, j)) += (A / 3.0) * t.transpose();
  }
}

struct Moduli {
  double E_kPa, nu, mu_kPa;
};

// The unit cube's effective E, nu (uniaxial stress along z) and through-thickness shear modulus mu_xz (a
// uniform shear stress tau_xz) from the model's static equilibrium: mean face displacements.
Moduli cube_moduli(const VolumetricMesh& vm, const VolumetricSettings& s) {
  const VolumetricBody body(vm, s, "cube");
  const Model& m = body.model();
  const double sig = 1e-7;  // N/mm^2 (1e-5 E): geometric nonlinearity below 1e-5
  auto mean_on = [&](const MatX3& u, int axis, double at, int comp) {
    double sum = 0;
    int n = 0;
    for (Index i = 0; i < vm.surface_nodes; ++i)
      if (std::abs(vm.X(i, axis) - at) < 1e-9) sum += u(i, comp), ++n;
    return sum / n;
  };
  MatX3 f = MatX3::Zero(m.num_nodes(), 3);
  add_traction(vm, Vec3::UnitZ(), sig * Vec3::UnitZ(), f);
  add_traction(vm, -Vec3::UnitZ(), -sig * Vec3::UnitZ(), f);
  StaticSettings tol;
  tol.tolerance = 1e-8 * f.cwiseAbs().maxCoeff();
  MatX3 u = static_equilibrium(m, f, tol).x - m.x0;
  const double ez = mean_on(u, 2, 1, 2) - mean_on(u, 2, 0, 2), ex = mean_on(u, 0, 1, 0) - mean_on(u, 0, 0, 0);
  Moduli out{};
  out.E_kPa = sig / ez * 1e3;
  out.nu = -ex / ez;
  f.setZero();  // tau_xz: t = tau e_x on z = 1, -tau e_x on z = 0, tau e_z on x = 1, -tau e_z on x = 0
  add_traction(vm, Vec3::UnitZ(), sig * Vec3::UnitX(), f);
  add_traction(vm, -Vec3::UnitZ(), -sig * Vec3::UnitX(), f);
  add_traction(vm, Vec3::UnitX(), sig * Vec3::UnitZ(), f);
  add_traction(vm, -Vec3::UnitX(), -sig * Vec3::UnitZ(), f);
  tol.tolerance = 1e-8 * f.cwiseAbs().maxCoeff();
  u = static_equilibrium(m, f, tol).x - m.x0;
  const double gamma =
      (mean_on(u, 2, 1, 0) - mean_on(u, 2, 0, 0)) + (mean_on(u, 0, 1, 2) - mean_on(u, 0, 0, 2));
  out.mu_kPa = sig / gamma * 1e3;
  return out;
}

}  // namespace

// Linear elasticity: E = 10 kPa, nu = 0.45, mu = 3.448 kPa. P1 represents the uniform strain of these loads
// exactly, so with scale_springs (rule + term = P1 on every flagged tetrahedron, and every one is flat here)
// the model's moduli must be the material's (to the solver's tolerance); the rule alone misses them badly.
TEST(ThinTetModel, CubeOfFlatTetrahedraUnderUniformStressMatchesLinearElasticity) {
  const VolumetricMesh vm = flat_cube();
  const double mu = 10.0 / (2 * 1.45);
  const Moduli off = cube_moduli(vm, settings(ThinTetMode::Off));
  const Moduli sc = cube_moduli(vm, settings(ThinTetMode::ScaleSprings));
  const Moduli cl = cube_moduli(vm, settings(ThinTetMode::Clip));
  std::cout << "flat cube E / nu / mu_xz (kPa): off " << off.E_kPa << " / " << off.nu << " / " << off.mu_kPa
            << "; scale_springs " << sc.E_kPa << " / " << sc.nu << " / " << sc.mu_kPa << "; clip " << cl.E_kPa
            << " / " << cl.nu << " / " << cl.mu_kPa << "\n";
  EXPECT_NEAR(sc.E_kPa, 10.0, 1e-3);
  EXPECT_NEAR(sc.nu, 0.45, 1e-4);
  EXPECT_NEAR(sc.mu_kPa, mu, 1e-3);
  EXPECT_LT(off.mu_kPa, 0.2 * mu);        // the springs alone: through-thickness shear (h/L)^2-soft
  EXPECT_NEAR(cl.mu_kPa, mu, 0.03 * mu);  // the clip restores the through-thickness shear too
  // with the term off the model is the plain rule: no terms, the springs unscaled
  const VolumetricBody b(vm, settings(ThinTetMode::Off), "cube");
  EXPECT_EQ(b.model().thin.size(), 0);
  EXPECT_EQ(b.stats().thin_tets, 0);
}

// The model's forces are minus the gradient of its energy (central differences, the term included), the
// internal forces of a free model sum to zero with zero torque, and a rigid rotation of the rest state gives
// no force.
TEST(ThinTetModel, ModelForcesAreTheEnergyGradientAndConserveMomentum) {
  const VolumetricMesh vm = box(fem::graded(0, 1, 2), fem::graded(0, 1, 2), fem::graded(0, 0.4, 4));
  const VolumetricBody body(vm, settings(ThinTetMode::ScaleSprings, 1.0), "box");
  const Model& m = body.model();
  ASSERT_EQ(m.thin.size(), vm.T.rows());
  const MatX3 zero = MatX3::Zero(m.num_nodes(), 3);
  auto internal = [&](const MatX3& x, MatX3& f) {  // without the (1e-9 N/mm) return springs
    internal_forces(m, x, zero, f);
    for (Index i = 0; i < x.rows(); ++i) f.row(i) += m.kr[i] * (x.row(i) - m.x0.row(i));
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-0.02, 0.02);  // 20 % of a cell's thickness
  MatX3 x = m.x0;
  for (Index i = 0; i < x.rows(); ++i)
    for (int k = 0; k < 3; ++k) x(i, k) += U(rng);
  MatX3 f(m.num_nodes(), 3);
  internal(x, f);
  Vec3 sum = Vec3::Zero(), torque = Vec3::Zero();
  for (Index i = 0; i < x.rows(); ++i) {
    sum += f.row(i).transpose();
    torque += Vec3(x.row(i)).cross(Vec3(f.row(i)));
  }
  const double scale = f.cwiseAbs().maxCoeff();
  EXPECT_LT(sum.norm(), 1e-12 * scale * static_cast<double>(x.rows()));
  EXPECT_LT(torque.norm(), 1e-11 * scale * static_cast<double>(x.rows()));
  double worst = 0;
  for (Index i = 0; i < x.rows(); i += 3)
    for (int k = 0; k < 3; ++k) {
      const double h = 1e-6;
      MatX3 xp = x, xm = x;
      xp(i, k) += h;
      xm(i, k) -= h;
      const double g = (potential_energy(m, xp) - potential_energy(m, xm)) / (2 * h);
      const double r = m.kr[i] * (x(i, k) - m.x0(i, k));  // the return spring's share of the energy
      worst = std::max(worst, std::abs(g - r + f(i, k)) / scale);
    }
  EXPECT_LT(worst, 1e-6);
  // a rigid rotation of the rest state: no force
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const MatX3 xr = (m.x0 * R.transpose()).eval();
  internal(xr, f);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-9 * scale);
}

// An undamped model released from a deformed state keeps its total energy (symplectic Euler: a bounded
// oscillation of O(h omega), under 1 % at a tenth of the stable step), the term's energy included.
TEST(ThinTetModel, UndampedStepKeepsTheTotalEnergy) {
  const VolumetricMesh vm = box(fem::graded(0, 1, 2), fem::graded(0, 1, 2), fem::graded(0, 0.4, 4));
  VolumetricSettings s = settings(ThinTetMode::ScaleSprings, 1.0);
  s.beta = 0;
  s.return_k.reset();
  for (Index i = 0; i < vm.surface_nodes; ++i)
    if (vm.X(i, 2) < 1e-9) s.fixed.push_back(i);
  const VolumetricBody body(vm, s, "box");
  const Model& m = body.model();
  StepSettings ss;
  ss.dt = 0.5;
  ss.safety = 0.1;  // symplectic Euler's energy error is O(h omega): 4 % at the default 0.8
  State st = make_state(m, ss);
  for (Index i = 0; i < m.num_nodes(); ++i)
    if (!m.fixed[static_cast<std::size_t>(i)]) st.x(i, 0) += 0.05 * m.x0(i, 2);  // a through-thickness shear
  const double e0 = total_energy(m, st.x, st.v);
  double worst = 0;
  for (int k = 0; k < 200; ++k) {
    step(m, st, ss);
    worst = std::max(worst, std::abs(total_energy(m, st.x, st.v) - e0) / e0);
  }
  EXPECT_EQ(st.warnings.failed, 0u);
  EXPECT_EQ(st.warnings.nonfinite, 0u);
  EXPECT_LT(worst, 0.01);
}

// The stable step with the term (docs/volumetric-mesh.md, "Stable step"): the cube of flat tetrahedra (3 x 3
// x 12 cells, pinned at its base) pressed on its top, the load ramped over 40 ms to 0.4 E, held, then
// released: over 20 % compression without collapse, default step settings, no rollback, no failed frame,
// finite throughout. The same run without the term is printed beside it (finite, but it folds through).
TEST(ThinTetModel, LargeStrainCompressionRunsWithoutBlowUp) {
  const VolumetricMesh vm = box(fem::graded(0, 1, 3), fem::graded(0, 1, 3), fem::graded(0, 1, 12));
  for (ThinTetMode mode : {ThinTetMode::Off, ThinTetMode::ScaleSprings}) {
    VolumetricSettings s = settings(mode);
    s.compression = kDefaultVolumetricCompression;
    s.return_k.reset();
    for (Index i = 0; i < vm.surface_nodes; ++i)
      if (vm.X(i, 2) < 1e-9) s.fixed.push_back(i);
    const VolumetricBody body(vm, s, "cube");
    const Model& m = body.model();
    ASSERT_EQ(m.thin.size() > 0, mode != ThinTetMode::Off);
    constexpr double kPress = 0.004;                       // N/mm^2 = 0.4 E: far beyond the linear range
    constexpr int kRamp = 40, kHold = 100, kFrames = 130;  // 1 ms frames
    StepSettings ss;
    ss.dt = 1.0;
    State st = make_state(m, ss);
    MatX3 press = MatX3::Zero(m.num_nodes(), 3);
    add_traction(vm, Vec3::UnitZ(), -kPress * Vec3::UnitZ(), press);
    double zmin = 1;
    for (int k = 0; k < kFrames; ++k) {
      st.f_ext = (k < kHold ? std::min(1.0, (k + 1.0) / kRamp) : 0.0) * press;
      step(m, st, ss);
      ASSERT_TRUE(st.x.allFinite()) << "frame " << k;
      double top = 0;
      int n = 0;
      for (Index i = 0; i < vm.surface_nodes; ++i)
        if (std::abs(vm.X(i, 2) - 1) < 1e-9) top += st.x(i, 2), ++n;
      zmin = std::min(zmin, top / n);
    }
    std::cout << "flat cube pressed, thin_tet " << to_string(mode) << ": top face mean height down to "
              << zmin << " mm (of 1), " << st.substeps << " substeps, " << st.warnings.rollbacks
              << " rollbacks, " << st.warnings.inverted_elements
              << " inverted tetrahedra at frame ends (summed)\n";
    EXPECT_EQ(st.warnings.nonfinite, 0u);
    if (mode == ThinTetMode::Off)
      continue;            // measured (loaded run): without the term the cube folds
                           // through (top to -0.92 mm): its through-thickness shear is
                           // 1.3 % of mu (test above)
    EXPECT_LT(zmin, 0.8);  // over 20 % compression (0.72 measured)
    EXPECT_GT(zmin, 0.6);  // and no collapse
    EXPECT_EQ(st.warnings.rollbacks, 0u);
    EXPECT_EQ(st.warnings.failed, 0u);
    EXPECT_EQ(st.warnings.nonfinite, 0u);
  }
}

// The implicit integrator (its CG product has the term's co-rotated stiffness) settles on the static
// equilibrium of the same model and load.
TEST(ThinTetModel, ImplicitStepSettlesOnTheStaticEquilibrium) {
  const VolumetricMesh vm = box(fem::graded(0, 1, 2), fem::graded(0, 1, 2), fem::graded(0, 0.4, 4));
  VolumetricSettings s = settings(ThinTetMode::ScaleSprings, 1.0);
  s.beta = 2.0;
  s.return_k.reset();
  for (Index i = 0; i < vm.surface_nodes; ++i)
    if (vm.X(i, 2) < 1e-9) s.fixed.push_back(i);
  const VolumetricBody body(vm, s, "box");
  const Model& m = body.model();
  MatX3 f = MatX3::Zero(m.num_nodes(), 3);
  add_traction(vm, Vec3::UnitZ(), 2e-4 * Vec3::UnitX(), f);  // through-thickness shear
  const MatX3 xs = static_equilibrium(m, f).x;
  StepSettings ss;
  ss.integrator = Integrator::ImplicitEuler;
  ss.dt = 2.0;
  ss.newton_iterations = 3;
  State st = make_state(m, ss);
  st.f_ext = f;
  for (int k = 0; k < 400; ++k) step(m, st, ss);
  const double umax = (xs - m.x0).cwiseAbs().maxCoeff();
  ASSERT_GT(umax, 1e-3);
  EXPECT_LT((st.x - xs).cwiseAbs().maxCoeff(), 1e-4 * umax);
  EXPECT_EQ(st.warnings.failed, 0u);
}

// The terms enter the fingerprint only when present; a model package rebuilds the same model.
TEST(ThinTetModel, FingerprintAndModelPackage) {
  const VolumetricMesh vm = box(fem::graded(0, 1, 2), fem::graded(0, 1, 2), fem::graded(0, 0.4, 4));
  const VolumetricBody off(vm, settings(ThinTetMode::Off), "box");
  const VolumetricBody none(vm, settings(ThinTetMode::ScaleSprings, 1e-6), "box");  // no tetrahedron flagged
  const VolumetricBody on(vm, settings(ThinTetMode::ScaleSprings, 1.0), "box");
  EXPECT_EQ(none.model().thin.size(), 0);
  EXPECT_EQ(model_fingerprint(none.model()), model_fingerprint(off.model()));
  EXPECT_NE(model_fingerprint(on.model()), model_fingerprint(off.model()));
  EXPECT_GT(on.stats().thin_tets, 0);
  EXPECT_LT(on.stats().thin_spring_factor, 1.0);
  const ModelPackage p = decode_model_package(encode_model_package(package_of(on, "box")), "box.msm");
  EXPECT_EQ(p.volumetric.thin_tet, ThinTetMode::ScaleSprings);
  EXPECT_EQ(p.volumetric.thin_tet_q_max, 1.0);
  const BodyPtr again = make_body(p);
  EXPECT_TRUE(check_fingerprint(p, *again));
  EXPECT_EQ(model_fingerprint(again->model()), model_fingerprint(on.model()));
}

// Bad values are refused with the parameter named: by the body, by the declaration (scene files, Python,
// set_param of the CLI options) and for a Poisson ratio the term does not cover.
TEST(ThinTetModel, BadSettingsAreRefusedWithTheParameterNamed) {
  const VolumetricMesh vm = box(fem::graded(0, 1, 2), fem::graded(0, 1, 2), fem::graded(0, 0.4, 4));
  auto refused = [&](const VolumetricSettings& s, const std::string& what) {
    try {
      const VolumetricBody b(vm, s, "box");
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "not refused: " << what;
  };
  for (double q : {0.0, -0.1, 1.5, std::nan("")})
    refused(settings(ThinTetMode::ScaleSprings, q), "thin_tet_q_max");
  VolumetricSettings neg = settings(ThinTetMode::Clip);
  neg.nu = -0.2;
  refused(neg, "thin_tet");
  VolumetricSettings s;
  EXPECT_THROW(set_param(s, "thin_tet", "fine"), InvalidInput);
  try {
    set_param(s, "thin_tet_q_max", "2");
    ADD_FAILURE() << "thin_tet_q_max 2 not refused";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("thin_tet_q_max"), std::string::npos) << e.what();
  }
  set_param(s, "thin_tet", "scale_springs");
  set_param(s, "thin_tet_q_max", "0.5");
  EXPECT_EQ(s.thin_tet, ThinTetMode::ScaleSprings);
  EXPECT_EQ(s.thin_tet_q_max, 0.5);
  s.thin_tet_q_max = 0;
  try {
    validate_params(s, "model.parameters");
    ADD_FAILURE() << "thin_tet_q_max 0 not refused by validate_params";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("model.parameters.thin_tet_q_max"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_thin_tet_mode("on"), InvalidInput);
  EXPECT_STREQ(to_string(ThinTetMode::Clip), "clip");
}
