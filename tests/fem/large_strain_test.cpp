// The large-strain load path of the volumetric kind (issue 23, item 4; docs/accuracy-nonlinear.md "Large
// strain"): a contact disk pressed into a small cube, the base held, up to about 30 % nominal strain, through
// the same static solve the accuracy tables use (fem::spring_displacement). With the default compression term
// the response is finite, grows with the load and stiffens; the Duffing term (k' = eta k / L0^2) changes
// nothing at a small load and only stiffens at a large one.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <vector>

#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "volumetric_fixtures.hpp"

using namespace medspring;

namespace {

TEST(LargeStrain, ContactPathIsFiniteMonotoneAndStiffensWithTheDefaultCompressionTerm) {
  const double L = 20;
  const VolumetricMesh m = fem::volumetric_mesh(medspring::testing::box_surface(4, L), {.target_nodes = 250});
  std::vector<Index> base;
  Index top = 0;
  const Vec3 centre(L / 2, L / 2, L);
  for (Index i = 0; i < m.surface_nodes; ++i) {
    if (m.X(i, 2) < 1e-9) base.push_back(i);
    if ((m.X.row(i).transpose() - centre).norm() < (m.X.row(top).transpose() - centre).norm()) top = i;
  }
  // E = 10 kPa, nu = 0.45, a 6-mm disk: 0.01 N is about 0.4 % nominal strain, 1 N about 30 %
  const std::vector<double> forces{0.01, 0.3, 0.6, 0.8, 1.0};
  auto path = [&](bool duffing) {
    VolumetricSettings s;  // the defaults: c = kDefaultVolumetricCompression, no return springs with supports
    s.fixed = base;
    if (duffing) s.duffing = DuffingSettings{};  // strain mode, eta = 1 (the accuracy tables' Duffing kind)
    const VolumetricBody body(m, s, "cube");
    EXPECT_GT(body.model().compression.size(), 0) << "the default has the compression term";
    std::vector<double> u;
    for (double F : forces) {
      const MatX3 d = fem::spring_displacement(body, {centre, Vec3(0, 0, -F), 6.0});
      EXPECT_TRUE(d.allFinite()) << F << " N";
      u.push_back(-d(top, 2));
    }
    return u;
  };
  const std::vector<double> lin = path(false), duf = path(true);
  for (std::size_t k = 0; k < forces.size(); ++k)
    std::cout << forces[k] << " N: contact " << lin[k] << " mm (" << 100 * lin[k] / L << " %), Duffing "
              << duf[k] << " mm\n";
  for (std::size_t k = 1; k < forces.size(); ++k) {
    EXPECT_GT(lin[k], lin[k - 1]) << "the contact moves further under a larger load";
    EXPECT_GT(duf[k], duf[k - 1]);
  }
  EXPECT_GT(lin.back() / L, 0.2) << "the path reaches a large strain";
  EXPECT_LT(lin.back() / L, 0.6) << "and does not give way";
  // stiffening: the secant compliance at the largest load is below the small-load one
  EXPECT_LT(lin.back() / forces.back(), 0.95 * lin.front() / forces.front());
  // Duffing: the same response at 1 % strain, never softer, stiffer at the largest load
  EXPECT_NEAR(duf.front() / lin.front(), 1.0, 2e-3);
  for (std::size_t k = 0; k < forces.size(); ++k) EXPECT_LE(duf[k], lin[k] * (1 + 1e-6));
  EXPECT_LT(duf.back(), lin.back() * (1 - 1e-3));
}

}  // namespace
