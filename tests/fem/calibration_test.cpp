// Calibration of the volumetric kind on the nonlinear response (issue 23, docs/accuracy-nonlinear.md
// "Calibration of the nonlinear response"): fem::refine_multipliers on an analytic response, then the
// compression coefficient c recovered from a synthetic target (the model itself with a known c under large
// local compression), which the small-strain fit cannot see.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "medspring/core/error.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/loads.hpp"
#include "volumetric_fixtures.hpp"

using namespace medspring;
using medspring::testing::box_surface;

namespace {

// One training case of a response u(m) = A diag(g(m)) with a known minimum at m*.
fem::CalibrationCase analytic_case(const fem::Response& r, const VecX& m_true) {
  fem::CalibrationCase c;
  c.u_fem = r(m_true, {});
  c.contact = 0;
  return c;
}

}  // namespace

// Three families with distinct effects on a 4-node "surface": the descent finds each within its span, a
// held family (span 1) stays where it starts, a family the start lacks starts at 1, and the cost never
// rises above the start's.
TEST(Calibration, RefineFindsEachFamilyWithinItsSpan) {
  const fem::Response r = [](const VecX& m, const fem::ContactLoad&) {
    MatX3 u(4, 3);
    u << 1.0 / m(0), 0, 0,                    //
        0, 1.0 / (m(0) + m(1)), 0,            //
        0, 0, 1.0 / (1.0 + std::sqrt(m(2))),  //
        0.5 / m(1), 0.2, 0;
    return u;
  };
  VecX truth(3);
  truth << 1.2, 0.7, 9.0;
  const std::vector<fem::CalibrationCase> training = {analytic_case(r, truth)};
  VecX start(2);
  start << 1.0, 1.0;  // c's multiplier absent: starts at 1
  const fem::RefineResult res = fem::refine_multipliers(r, start, {1.5, 2.0, 32.0}, training, 14, 2);
  EXPECT_NEAR(res.m(0), 1.2, 0.02);
  EXPECT_NEAR(res.m(1), 0.7, 0.02);
  EXPECT_NEAR(res.m(2), 9.0, 0.5);
  EXPECT_LT(res.cost, 1e-3 * res.start_cost);
  EXPECT_EQ(res.evaluations, 1 + 2 * 3 * 14);

  const fem::RefineResult held = fem::refine_multipliers(r, start, {1.5, 1.0, 32.0}, training, 10, 1);
  EXPECT_EQ(held.m(1), 1.0);
  EXPECT_LE(held.cost, held.start_cost);

  EXPECT_THROW(fem::refine_multipliers(r, VecX::Constant(2, -1.0), {1.5, 2.0}, training), InvalidInput);
  EXPECT_THROW(fem::refine_multipliers(r, start, {}, training), InvalidInput);
}

// A 20 mm cube of 150 nodes on its base, pressed by 0.25 N disks of 5 mm on its top (local compressive
// strain ~ 30 %), ν = 0.3. The target is the model itself with c = 16; the model starts at c = 2. The
// small-strain fit is the same for any c (the term is zero to second order at rest); the refinement on
// the full response recovers c and keeps the scales near 1.
TEST(Calibration, NonlinearFitRecoversAKnownCompressionCoefficient) {
  const double L = 20, c_true = 16, c_start = 2;
  const VolumetricMesh mesh = fem::volumetric_mesh(box_surface(4, L), {.target_nodes = 150});
  std::vector<Index> base;
  for (Index i = 0; i < mesh.surface_nodes; ++i)
    if (mesh.X(i, 2) < 1e-9) base.push_back(i);
  auto body = [&](const VecX& m, double c0) {
    VolumetricSettings s;
    s.nu = 0.3;
    s.return_k = 0.0;
    s.fixed = base;
    s.spring_scale = m(0);
    s.volume_scale = m(1);
    s.compression = c0 * (m.size() > 2 ? m(2) : 1.0);
    return VolumetricBody(mesh, s, "cube");
  };
  std::vector<fem::CalibrationCase> training;
  for (const Vec3& centre : {Vec3(10, 10, L), Vec3(5, 13, L)}) {
    fem::CalibrationCase t;
    t.load = {centre, Vec3(0, 0, -0.25), 5.0};
    t.u_fem = fem::spring_displacement(body(VecX::Ones(2), c_true), t.load);
    t.contact = nearest_node(mesh.X.topRows(mesh.surface_nodes), centre);
    training.push_back(t);
  }
  // the target is nonlinear: c changes the contact displacement by more than 10 %
  const MatX3 u_start = fem::spring_displacement(body(VecX::Ones(2), c_start), training[0].load);
  const double u_true = training[0].u_fem.row(training[0].contact).norm(),
               u_off = u_start.row(training[0].contact).norm();
  ASSERT_GT(u_off, 1.1 * u_true) << "the load does not reach the nonlinear range";

  // the small-strain fit cannot see c: identical for c = 2 and c = 64
  auto small_strain = [&](double c0) {
    return fem::calibrate_scale_and_ratio(
        [&](const VecX& mm, const std::vector<fem::ContactLoad>& ls) {
          return fem::spring_displacement_linear(body(mm, c0), ls);
        },
        training);
  };
  const VecX lin = small_strain(c_start);
  EXPECT_LT((lin - small_strain(64)).norm(), 1e-9 * lin.norm());

  const fem::Response full = [&](const VecX& mm, const fem::ContactLoad& l) {
    return fem::spring_displacement(body(mm, c_start), l);
  };
  const fem::VolumetricFit f = fem::calibrate_volumetric_nonlinear(full, lin, training);
  const fem::RefineResult& r = f.refine;
  const double c_fit = c_start * f.m(2);
  std::cout << "cube: small-strain fit springs x " << lin(0) << ", volume x " << lin(1) << " (cost "
            << f.small_strain_cost << "; closed forms " << f.closed_forms_cost << "); refined springs x "
            << f.m(0) << ", volume x " << f.m(1) << ", c " << c_start << " -> " << c_fit << " (true "
            << c_true << "); cost " << r.start_cost << " -> " << r.cost << " in " << r.evaluations
            << " evaluations\n";
  EXPECT_NEAR(c_fit / c_true, 1.0, 0.25);
  EXPECT_NEAR(f.m(0), 1.0, 0.1);
  EXPECT_NEAR(f.m(1), 1.0, 0.25);
  EXPECT_LT(r.cost, 0.1 * r.start_cost);
}
