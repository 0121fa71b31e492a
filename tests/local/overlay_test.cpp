#include "medspring/local/overlay.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "local_fixtures.hpp"
#include "medspring/core/error.hpp"
#include "medspring/local/solver.hpp"

namespace medspring {
namespace {

struct Loaded {
  SurfaceMesh mesh = tube(40, 30);
  LocalPatch patch = structured_window_patch(40, 30, GridNode{20, 7});
  LocalSolver solver;
  MatX3 U;
  Loaded() { solver.precompute(patch); }
};

TEST(LocalOverlay, AddsUToThePatchNodesOnly) {
  Loaded s;
  s.solver.solve(Vec3(0, 0, -0.05), s.U);
  MatX3 surface = s.mesh.V;
  apply_local_overlay(s.patch, s.U, surface);
  std::vector<bool> in(1200, false);
  for (Index a = 0; a < s.patch.size(); ++a) {
    in[s.patch.nodes[a]] = true;
    EXPECT_EQ(surface.row(s.patch.nodes[a]), s.mesh.V.row(s.patch.nodes[a]) + s.U.row(a));
  }
  for (Index i = 0; i < 1200; ++i) {
    if (!in[i]) {
      EXPECT_EQ(surface.row(i), s.mesh.V.row(i));
    }
  }
  EXPECT_LT(surface(607, 2), s.mesh.V(607, 2));
}

TEST(LocalOverlay, ReleasedForceLeavesTheSurfaceUnchanged) {
  Loaded s;
  s.solver.solve(Vec3::Zero(), s.U);
  MatX3 surface = s.mesh.V;
  apply_local_overlay(s.patch, s.U, surface);
  EXPECT_EQ(surface, s.mesh.V);
}

TEST(LocalOverlay, GuardScalesUToTheLimit) {
  Loaded s;
  s.solver.solve(Vec3(0, 0, -1.0), s.U);  // U_c = 20 x 39/172 = 4.53 mm > 0.9 x 3 mm
  const MatX3 U0 = s.U;
  const double uc = U0.row(s.patch.contact_local).norm();
  MatX3 off = U0;
  EXPECT_EQ(limit_local_displacement(s.patch, off, 3.0, {.enabled = false}), 1.0);
  EXPECT_EQ(off, U0);
  const double scale = limit_local_displacement(s.patch, s.U, 3.0);
  EXPECT_NEAR(scale, 2.7 / uc, 1e-15);
  EXPECT_NEAR(s.U.row(s.patch.contact_local).norm(), 2.7, 1e-12);
  EXPECT_LE((s.U - scale * U0).cwiseAbs().maxCoeff(), 1e-15);
  MatX3 small = U0 * 0.1;  // 0.45 mm: below the limit
  const MatX3 small0 = small;
  EXPECT_EQ(limit_local_displacement(s.patch, small, 3.0), 1.0);
  EXPECT_EQ(small, small0);
  EXPECT_THROW(limit_local_displacement(s.patch, small, 0.0), InvalidInput);
}

TEST(LocalOverlay, SmoothingWithZeroTimeConstantPassesUThrough) {
  Loaded s;
  s.solver.solve(Vec3(0.01, 0, -0.05), s.U);
  LocalSmoother smooth;
  MatX3 a = s.mesh.V, b = s.mesh.V;
  smooth.apply(s.patch, s.U, 0.5, a);
  apply_local_overlay(s.patch, s.U, b);
  EXPECT_EQ(a, b);
  MatX3 c = s.mesh.V;
  smooth.apply_released(0.5, c);  // release: U = 0 at once
  EXPECT_EQ(c, s.mesh.V);
}

TEST(LocalOverlay, SmoothingIsAFirstOrderLag) {
  Loaded s;
  s.solver.solve(Vec3(0, 0, -0.05), s.U);
  const double tau = 10.0, dt = 0.5;
  LocalSmoother smooth(tau);
  const Index c = s.patch.contact;
  const double target = s.U(s.patch.contact_local, 2);
  for (int n = 1; n <= 40; ++n) {
    MatX3 surf = s.mesh.V;
    smooth.apply(s.patch, s.U, dt, surf);
    EXPECT_NEAR(surf(c, 2) - s.mesh.V(c, 2), (1.0 - std::exp(-n * dt / tau)) * target, 1e-12);
  }
  const double held = smooth.displacement()(c, 2);
  MatX3 surf = s.mesh.V;
  smooth.apply_released(dt, surf);
  EXPECT_NEAR(smooth.displacement()(c, 2), held * std::exp(-dt / tau), 1e-15);
  EXPECT_THROW(LocalSmoother(-1.0), InvalidInput);
}

TEST(LocalOverlay, WrongSizesAreRejected) {
  Loaded s;
  MatX3 surface = s.mesh.V;
  EXPECT_THROW(apply_local_overlay(s.patch, MatX3::Zero(3, 3), surface), InvalidInput);
  MatX3 small = MatX3::Zero(10, 3);
  EXPECT_THROW(apply_local_overlay(s.patch, MatX3::Zero(25, 3), small), InvalidInput);
}

}  // namespace
}  // namespace medspring
