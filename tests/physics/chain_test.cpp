// ALGORITHMS.md §8.1 checks 7-8 and §8.2 checks 9-10: the centerline chain.
#include <gtest/gtest.h>

#include <cmath>

#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/stability.hpp"
#include "medspring/physics/static_solve.hpp"
#include "physics_fixtures.hpp"

namespace medspring {
namespace {

using testing::chain;

double chain_uy19(DuffingSettings d, double F) {
  const Model m = chain(40, 0.2, 0.05, 0.5, d);
  MatX3 f = MatX3::Zero(40, 3);
  f(19, 1) = F;
  return static_equilibrium(m, f).x(19, 1);
}

TEST(Chain, ReferenceEquilibriumOfSection82) {  // §8.2-9, tolerance 1e-3 mm
  EXPECT_NEAR(chain_uy19({.mode = DuffingMode::Linear}, 0.5), 4.6448, 1e-3);
  EXPECT_NEAR(chain_uy19({.mode = DuffingMode::Absolute}, 0.5), 4.6408, 1e-3);
  EXPECT_NEAR(chain_uy19({.mode = DuffingMode::Strain}, 0.5), 4.5915, 1e-3);
  for (auto mode : {DuffingMode::Linear, DuffingMode::Absolute, DuffingMode::Strain})
    EXPECT_NEAR(chain_uy19({.mode = mode}, 0.05), 0.8675, 1e-3);
}

TEST(Chain, MirrorSymmetryAboutTheLoadedCentreAtom) {  // §8.2-10, 1e-9
  const Model m = chain(41, 0.2, 0.05, 0.5, {});
  MatX3 f = MatX3::Zero(41, 3);
  f(20, 1) = 0.5;
  const MatX3 u = static_equilibrium(m, f).x - m.x0;
  f(20, 1) = -0.5;
  const MatX3 w = static_equilibrium(m, f).x - m.x0;
  for (int k = 0; k <= 20; ++k) {
    EXPECT_NEAR(u(20 - k, 1), u(20 + k, 1), 1e-9);
    EXPECT_NEAR(u(20 - k, 0), -u(20 + k, 0), 1e-9);
  }
  for (int i = 0; i < 41; ++i) {
    EXPECT_NEAR(u(i, 2), 0.0, 1e-9);
    EXPECT_NEAR(w(i, 0), u(i, 0), 1e-9);
    EXPECT_NEAR(w(i, 1), -u(i, 1), 1e-9);
    EXPECT_NEAR(w(i, 2), u(i, 2), 1e-9);
  }
}

TEST(Chain, FrameIndependenceOfThePhysics) {  // §8.2-11 (physics part): straight-z with force along x
  const Model mx = chain(40, 0.2, 0.05, 0.5, {});
  const Model mz = chain(40, 0.2, 0.05, 0.5, {}, 0.5, 2.5, true);
  MatX3 fx = MatX3::Zero(40, 3), fz = MatX3::Zero(40, 3);
  fx(19, 1) = 0.5;
  fz(19, 0) = 0.5;
  const MatX3 ux = static_equilibrium(mx, fx).x - mx.x0;
  const MatX3 uz = static_equilibrium(mz, fz).x - mz.x0;
  for (int i = 0; i < 40; ++i) EXPECT_NEAR(ux.row(i).norm(), uz.row(i).norm(), 1e-9);
}

TEST(Chain, GershgorinBoundOfTheVesselChain) {  // §2.2 reference: omega <= 1.30 rad/ms, dt <= 1.53 ms
  const Model m = chain(40, 0.2, 0.02, 0.5, {});
  EXPECT_GT(m.omega_gershgorin, 1.25);
  EXPECT_LE(m.omega_gershgorin, 1.31);
  EXPECT_LE(m.omega_rest, m.omega_gershgorin * 1.05 + 1e-12);  // the tight estimate is below the bound
  EXPECT_GT(m.omega_rest, 0.9 * m.omega_gershgorin);
}

TEST(Chain, SymplecticEnergyStaysInBandWithoutDrift) {  // §8.1-7
  const Model m = chain(40, 0.2, 0.05, 0.5, {}, 0.0);
  State s = make_state(m);
  s.x(19, 1) = 3.0;
  const StepSettings st{.dt = 0.05};
  const double E0 = total_energy(m, s.x, s.v);
  const int steps = 400000;  // 20 s
  double lo = E0, hi = E0, first = 0, last = 0;
  const int tenth = steps / 10;
  for (int i = 0; i < steps; ++i) {
    step(m, s, st);
    const double E = total_energy(m, s.x, s.v);
    lo = std::min(lo, E);
    hi = std::max(hi, E);
    if (i < tenth) first += E;
    if (i >= steps - tenth) last += E;
  }
  EXPECT_LT((hi - E0) / E0, 0.05);
  EXPECT_LT((E0 - lo) / E0, 0.05);
  EXPECT_LT(std::abs(last - first) / first, 1e-3);
  EXPECT_EQ(s.warnings.total(), 0u);
}

TEST(Chain, DampedEnergyDecreasesStrictlyOverWindows) {  // §8.1-7, damped
  const Model m = chain(40, 0.2, 0.05, 0.5, {}, 0.5);
  State s = make_state(m);
  s.x(19, 1) = 3.0;
  const StepSettings st{.dt = 0.05};
  double prev = 1e300;
  const double E0 = total_energy(m, s.x, s.v);
  int windows = 0;
  for (int w = 0; w < 30 && prev > 1e-12 * E0; ++w, ++windows) {  // 10 ms windows (200 steps)
    double mean = 0;
    for (int i = 0; i < 200; ++i) {
      step(m, s, st);
      mean += total_energy(m, s.x, s.v) / 200;
    }
    EXPECT_LT(mean, prev) << "window " << w;
    prev = mean;
  }
  EXPECT_GE(windows, 5);  // beta = 0.5/ms: E falls by 1e-12 within ~70 ms
}

TEST(Chain, ImplicitAndSymplecticReachTheSameEquilibrium) {  // §8.1-8, 1e-6 mm
  const Model m = chain(40, 0.2, 0.05, 0.5, {});
  MatX3 f = MatX3::Zero(40, 3);
  f(19, 1) = 0.5;
  f(25, 2) = -0.2;
  const MatX3 xs = static_equilibrium(m, f).x;
  State a = make_state(m), b = make_state(m);
  a.f_ext = f;
  b.f_ext = f;
  for (int i = 0; i < 4000; ++i) step(m, a, {.dt = 0.5});  // 2 s
  for (int i = 0; i < 400; ++i) step(m, b, {.dt = 5.0, .integrator = Integrator::ImplicitEuler});
  EXPECT_LT((a.x - xs).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((b.x - xs).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(b.warnings.cg_not_converged, 0u);
}

TEST(Chain, FullNewtonImplicitMatchesStaticSolve) {
  const Model m = chain(40, 0.2, 0.05, 0.5, {});
  MatX3 f = MatX3::Zero(40, 3);
  f(19, 1) = 2.0;  // large load: strongly nonlinear
  const MatX3 xs = static_equilibrium(m, f).x;
  State s = make_state(m);
  s.f_ext = f;
  for (int i = 0; i < 200; ++i)
    step(m, s, {.dt = 20.0, .integrator = Integrator::ImplicitEuler, .newton_iterations = 8});
  EXPECT_LT((s.x - xs).cwiseAbs().maxCoeff(), 1e-6);
}

}  // namespace
}  // namespace medspring
