// ALGORITHMS.md §8.1 checks 5-6, stability guard, loads, determinism.
#include "medspring/physics/integrators.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/stability.hpp"
#include "physics_fixtures.hpp"

namespace medspring {
namespace {

Model single_node(double m, double kr, double damping) {
  ModelBuilder b("node");
  b.add_node(Vec3::Zero(), m, damping, kr);
  return b.build();
}

TEST(Integrators, ReturnSpringStaticAndFreePeriod) {  // §8.1-5
  const Model m = single_node(1.0, 1.0, 0.0);
  State s = make_state(m);
  s.x(0, 0) = 1.0;
  const StepSettings st{.dt = 1e-3};
  // period 2 pi: first upward zero crossing of v after a full cycle
  double prev_x = s.x(0, 0);
  double crossing = -1;
  int downs = 0;
  for (int i = 0; i < 8000; ++i) {
    step(m, s, st);
    if (prev_x > 0 && s.x(0, 0) <= 0) {
      const double t = s.t - 1e-3 * s.x(0, 0) / (s.x(0, 0) - prev_x);
      if (++downs == 2) crossing = t;
    }
    prev_x = s.x(0, 0);
  }
  EXPECT_NEAR(crossing - std::numbers::pi / 2 - 2 * std::numbers::pi, 0.0, 2e-3);
  // static: delta = F / k_r under a held force with damping
  const Model md = single_node(1.0, 1.0, 2.0);
  State sd = make_state(md);
  sd.f_ext(0, 2) = 0.3;
  for (int i = 0; i < 2000; ++i) step(md, sd, {.dt = 0.05});
  EXPECT_NEAR(sd.x(0, 2), 0.3, 1e-9);
}

TEST(Integrators, DampedOscillatorMatchesAnalyticSolution) {  // §8.1-5, beta = 0.1
  const Model m = single_node(1.0, 1.0, 0.1);
  State s = make_state(m);
  s.x(0, 0) = 1.0;
  s.v(0, 0) = -0.05;  // x(t) = e^{-0.05 t} cos(w_d t)
  const double wd = 0.99874922;
  EXPECT_NEAR(std::sqrt(1 - 0.05 * 0.05), wd, 1e-8);
  for (int i = 1; i <= 10000; ++i) {
    step(m, s, {.dt = 1e-3});
    if (i % 500 == 0) {
      const double t = 1e-3 * i;
      EXPECT_NEAR(s.x(0, 0), std::exp(-0.05 * t) * std::cos(wd * t), 1e-3) << "t = " << t;
    }
  }
}

TEST(Integrators, SymplecticEulerStabilityThreshold) {  // §8.1-6
  for (double factor : {1.99, 2.01}) {
    Model m = single_node(2.0, 8.0, 0.0);  // omega = 2
    m.omega_rest = 1e-9;                   // disable the step bound: test the bare scheme
    State s = make_state(m);
    s.x(0, 0) = 1.0;
    const StepSettings st{.dt = factor / 2.0, .guard = false};
    double amax = 0;
    for (int i = 0; i < 100000 && std::isfinite(s.x(0, 0)); ++i) {
      step(m, s, st);
      amax = std::max(amax, std::abs(s.x(0, 0)));
    }
    if (factor < 2) {
      EXPECT_LT(amax, 20.0) << "bounded for dt = 1.99/omega";
    } else {
      EXPECT_GT(amax, 1e6) << "diverges for dt = 2.01/omega";
    }
  }
}

TEST(Integrators, StepAboveBoundIsSubsteppedOrRefused) {
  const Model m = single_node(2.0, 8.0, 0.0);
  EXPECT_NEAR(m.omega_rest, 2.0 * 1.05, 1e-9);
  const double dt = 2.01 / 2.0;
  State s = make_state(m);
  s.x(0, 0) = 1.0;
  const StepStatus st = step(m, s, {.dt = dt});
  EXPECT_TRUE(st.ok());
  EXPECT_EQ(st.substeps, static_cast<int>(std::ceil(dt / m.dt_safe_rest())));
  for (int i = 0; i < 10000; ++i) step(m, s, {.dt = dt});
  EXPECT_LT(s.x.cwiseAbs().maxCoeff(), 1.0 + 1e-9);
  State r = make_state(m);
  const StepStatus refused = step(m, r, {.dt = dt, .substep = false});
  EXPECT_EQ(refused.code, StepCode::Refused);
  EXPECT_EQ(r.warnings.unstable_refused, 1u);
  EXPECT_EQ(r.t, 0.0);
  EXPECT_THROW(validate_step_settings(m, {.dt = dt, .substep = false}), InvalidInput);
  EXPECT_NO_THROW(validate_step_settings(m, {.dt = dt}));
  EXPECT_THROW(validate_step_settings(m, {.dt = -1}), InvalidInput);
  EXPECT_THROW(validate_step_settings(m, {.dt = std::nan("")}), InvalidInput);
}

TEST(Integrators, GuardRollsBackNonFiniteForces) {
  const Model m = testing::chain(10, 0.2, 0.05, 0.5, {});
  State s = make_state(m);
  s.f_ext(4, 1) = std::nan("");
  const StepStatus st = step(m, s, {.dt = 0.5});
  EXPECT_EQ(st.code, StepCode::Failed);
  EXPECT_TRUE(s.x.allFinite());
  EXPECT_TRUE(s.v.allFinite());
  EXPECT_EQ((s.x - m.x0).norm(), 0.0);
  EXPECT_GT(s.warnings.failed, 0u);
  s.f_ext.setZero();
  s.f_ext(4, 1) = 1e9;  // absurd force: velocity limit -> halved steps -> reported
  const StepStatus st2 = step(m, s, {.dt = 0.5});
  EXPECT_NE(st2.code, StepCode::Ok);
  EXPECT_TRUE(s.x.allFinite());
}

TEST(Integrators, LoadRampHoldRelease) {
  PointLoad L{.node = 0, .force = Vec3(0, 0, 2.0), .t_on = 10, .t_ramp = 20, .t_release = 100};
  EXPECT_EQ(L.scale(5), 0.0);
  EXPECT_DOUBLE_EQ(L.scale(20), 0.5);
  EXPECT_DOUBLE_EQ(L.scale(50), 1.0);
  EXPECT_EQ(L.scale(100), 0.0);
  L.ramp_down = true;
  EXPECT_DOUBLE_EQ(L.scale(110), 0.5);
  EXPECT_EQ(L.scale(130), 0.0);
  MatX3 f = MatX3::Zero(2, 3);
  std::vector<PointLoad> loads{L, {.node = 0, .force = Vec3(1, 0, 0), .t_ramp = 0}};
  accumulate_loads(loads, 110, f);
  EXPECT_DOUBLE_EQ(f(0, 2), 1.0);
  EXPECT_DOUBLE_EQ(f(0, 0), 1.0);
  EXPECT_THROW(validate_loads({{.node = 5}}, 2), InvalidInput);
  EXPECT_THROW(validate_loads({{.node = 0, .force = Vec3(std::nan(""), 0, 0)}}, 2), InvalidInput);
  EXPECT_THROW(validate_loads({{.node = 0, .t_ramp = -1}}, 2), InvalidInput);
  MatX3 X(3, 3);
  X << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  EXPECT_EQ(nearest_node(X, Vec3(1.2, 0.1, 0)), 1);
}

TEST(Integrators, ForceThenReleaseReturnsToRest) {  // §8.2-12 on the core phantoms
  for (const SurfaceMesh& mesh : {kidney_phantom(), tube(40, 30, 2.5, 3.0)}) {
    const Model m = make_surface_model(mesh, {});
    State s = make_state(m);
    const Index c = mesh.num_vertices() == 458 ? 223 : 20 * 30 + 7;
    std::vector<PointLoad> loads{{.node = c, .force = Vec3(0, 0, -1.0), .t_ramp = 20, .t_release = 200}};
    const StepSettings st{.dt = 0.5};
    double max_disp = 0;
    while (s.t < 200) {
      step(m, s, st, &loads);
      max_disp = std::max(max_disp, (s.x.row(c) - m.x0.row(c)).norm());
    }
    EXPECT_GT(max_disp, 1.0);
    double t_back = -1;
    while (s.t < 400) {
      step(m, s, st, &loads);
      if (t_back < 0 && (s.x - m.x0).rowwise().norm().maxCoeff() < 1e-3) t_back = s.t - 200;
    }
    EXPECT_GT(t_back, 0);
    EXPECT_LT(t_back, 200) << mesh.num_vertices() << " nodes";
    EXPECT_EQ(s.warnings.total(), 0u);
  }
}

TEST(Integrators, RerunsAreBitIdentical) {
  const Model m = make_surface_model(kidney_phantom(), {});
  std::vector<PointLoad> loads{{.node = 223, .force = Vec3(0.3, -0.2, -1.0), .t_release = 100}};
  auto run = [&](Integrator in) {
    State s = make_state(m);
    for (int i = 0; i < 300; ++i) step(m, s, {.dt = 0.5, .integrator = in}, &loads);
    return s.x;
  };
  for (auto in : {Integrator::SymplecticEuler, Integrator::ImplicitEuler}) {
    const MatX3 a = run(in), b = run(in);
    EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())), 0);
  }
}

}  // namespace
}  // namespace medspring
