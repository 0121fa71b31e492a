// ALGORITHMS.md §8.1 checks 1-4: Duffing springs, soft springs, series chain, transverse two-spring.
#include <gtest/gtest.h>

#include "medspring/core/error.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/static_solve.hpp"
#include "physics_fixtures.hpp"

namespace medspring {
namespace {

using testing::single_spring;

double static_elongation(const Model& m, double F) {
  MatX3 f = MatX3::Zero(m.num_nodes(), 3);
  f(1, 0) = F;
  const StaticResult r = static_equilibrium(m, f);
  return r.x(1, 0) - m.x0(1, 0);
}

TEST(Springs, DuffingSingleSpringStaticMatchesCubicRoots) {  // §8.1-1
  const Model m = single_spring(1.0, 0.01);
  const std::pair<double, double> cases[] = {{0.1, 0.0999900030}, {1, 0.9902885241}, {6.25, 5}, {20, 10},
                                             {100, 20},           {-20, -10}};
  for (auto [F, x] : cases) EXPECT_NEAR(static_elongation(m, F), x, 1e-9 * std::abs(x)) << "F = " << F;
}

TEST(Springs, DuffingInNewtonMillimetreUnits) {  // §8.1-1, k = 0.05 N/mm, l = 10 mm
  const double kp = duffing_coefficient(0.05, 3.0, {.mode = DuffingMode::Absolute, .length = 10.0});
  EXPECT_DOUBLE_EQ(kp, 5e-4);
  EXPECT_NEAR(static_elongation(single_spring(0.05, kp), 0.5), 6.823278, 1e-6);
  EXPECT_NEAR(static_elongation(single_spring(0.05, 0.0), 0.5), 10.0, 1e-9 * 10.0);
}

TEST(Springs, DynamicRelaxationAgreesWithStaticSolve) {  // §8.1-1 dynamic, relative 1e-6
  const Model m = single_spring(1.0, 0.01, 100.0, 1.0, 2.0);
  State s = make_state(m);
  s.f_ext(1, 0) = 1.0;
  StepSettings st{.dt = 0.05};
  for (int i = 0; i < 4000; ++i) step(m, s, st);
  EXPECT_NEAR(s.x(1, 0) - 100.0, 0.9902885241, 1e-6 * 0.99);
}

TEST(Springs, SoftSpringClampAndNoEquilibrium) {  // §8.1-2
  const Model m = single_spring(1.0, -0.01);
  EXPECT_NEAR(static_elongation(m, 3.0), 3.3893624159, 1e-9 * 3.39);
  EXPECT_NEAR(soft_limit(1.0, -0.01), 5.7735026919, 1e-9);
  EXPECT_NEAR(spring_tension(1.0, -0.01, soft_limit(1.0, -0.01)), 3.8490017946, 1e-9);
  EXPECT_NEAR(spring_tension(1.0, -0.01, 50.0), 3.8490017946, 1e-9);  // clamped beyond the peak
  EXPECT_NEAR(spring_tension(1.0, -0.01, -50.0), -3.8490017946, 1e-9);
  EXPECT_EQ(spring_tension_derivative(1.0, -0.01, 6.0), 0.0);
  EXPECT_THROW(static_elongation(m, 4.0), SolverError);
}

TEST(Springs, SeriesChainElongatesTenTimesTheSingleRoot) {  // §8.1-3
  ModelBuilder b("series");
  for (int i = 0; i <= 10; ++i) b.add_node(Vec3(i, 0, 0), 1.0, 1.0, 0.0, i == 0);
  for (int i = 0; i < 10; ++i) b.add_spring(i, i + 1, 1.0, 0.01, 1.0);
  const Model m = b.build();
  MatX3 f = MatX3::Zero(11, 3);
  f(10, 0) = 1.0;
  const StaticResult r = static_equilibrium(m, f);
  EXPECT_NEAR(r.x(10, 0) - 10.0, 9.902885241, 1e-8);
  for (int i = 0; i < 10; ++i) EXPECT_NEAR(r.x(i + 1, 0) - r.x(i, 0) - 1.0, 0.9902885241, 1e-9);
}

double transverse_deflection(double kp, double F) {
  ModelBuilder b("two_spring");
  b.add_node(Vec3(-2.5, 0, 0), 1.0, 1.0, 0.0, true);
  b.add_node(Vec3(0, 0, 0), 1.0, 1.0, 0.0);
  b.add_node(Vec3(2.5, 0, 0), 1.0, 1.0, 0.0, true);
  b.add_spring(0, 1, 0.2, kp, 2.5);
  b.add_spring(1, 2, 0.2, kp, 2.5);
  const Model m = b.build();
  MatX3 f = MatX3::Zero(3, 3);
  f(1, 1) = F;
  return static_equilibrium(m, f).x(1, 1);
}

TEST(Springs, TransverseTwoSpringVectorForm) {  // §8.1-4, tolerance 1e-5 mm
  EXPECT_NEAR(transverse_deflection(0.0, 0.1), 1.594108, 1e-5);
  EXPECT_NEAR(transverse_deflection(0.0, 1.0), 4.708009, 1e-5);
  EXPECT_NEAR(transverse_deflection(0.002, 1.0), 4.521877, 1e-5);
  const double kp_strain = duffing_coefficient(0.2, 2.5, {});
  EXPECT_DOUBLE_EQ(kp_strain, 0.032);
  EXPECT_NEAR(transverse_deflection(kp_strain, 0.1), 1.573998, 1e-5);
  EXPECT_NEAR(transverse_deflection(kp_strain, 1.0), 3.636817, 1e-5);
}

TEST(Springs, DuffingModesOfD3) {
  EXPECT_EQ(duffing_coefficient(0.05, 2.0, {.mode = DuffingMode::Linear}), 0.0);
  EXPECT_DOUBLE_EQ(duffing_coefficient(0.05, 2.0, {.mode = DuffingMode::Strain}), 0.05 / 4.0);
  EXPECT_DOUBLE_EQ(duffing_coefficient(0.05, 2.0, {.mode = DuffingMode::Strain, .eta = 2.0}), 0.1 / 4.0);
  EXPECT_DOUBLE_EQ(duffing_coefficient(0.05, 2.0, {.mode = DuffingMode::Absolute}), 0.0005);
  EXPECT_DOUBLE_EQ(duffing_coefficient(0.05, 2.0, {.mode = DuffingMode::ScaledStrain}), 0.05 / 400.0);
  EXPECT_DOUBLE_EQ(duffing_coefficient(0.05, 2.0, {.mode = DuffingMode::Strain, .soft = true}), -0.05 / 4.0);
  EXPECT_EQ(parse_duffing_mode("absolute"), DuffingMode::Absolute);
  EXPECT_THROW(parse_duffing_mode("cubic"), InvalidInput);
  // hard spring: odd response, stiffer than linear
  EXPECT_DOUBLE_EQ(spring_tension(1.0, 0.01, -3.0), -spring_tension(1.0, 0.01, 3.0));
  EXPECT_GT(spring_tension(1.0, 0.01, 3.0), 3.0);
}

}  // namespace
}  // namespace medspring
