// The vessel FEM reference (docs/accuracy.md, "The vessel"): the structured wall tube, a clamped tube under
// a band load against Timoshenko beam theory, and the SMRM centerline comparison on coarse meshes.
#include "medspring/fem/vessel.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "medspring/core/error.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "test_support.hpp"

using namespace medspring;
using namespace medspring::fem;

namespace {

// A straight circular vessel along x: n atoms at spacing h, lumen radius r, M spokes.
SmrmVessel straight_vessel(Index n, double h, double r, Index M, double thickness_ratio, double E) {
  Centerline line;
  line.points = MatX3::Zero(n, 3);
  line.radii = VecX::Constant(n, r);
  for (Index i = 0; i < n; ++i) line.points(i, 0) = h * static_cast<double>(i);
  line.name = "straight";
  SmrmSettings s;
  s.atoms = n;
  s.spokes = M;
  s.wall.thickness_ratio = thickness_ratio;
  s.wall.E = E;
  return smrm_from_centerline(line, s);
}

// Second moment of area of a regular M-gon of circumradius R about a centroidal axis, mm^4.
double polygon_I(Index M, double R) {
  const double th = 2 * std::numbers::pi / static_cast<double>(M), d = R * std::cos(th / 2),
               t = std::tan(th / 2);
  return 0.5 * static_cast<double>(M) * d * d * d * d / 2 * (t + t * t * t / 3);
}
double polygon_A(Index M, double R) {
  const double th = 2 * std::numbers::pi / static_cast<double>(M), d = R * std::cos(th / 2);
  return static_cast<double>(M) * d * d * std::tan(th / 2);
}

}  // namespace

TEST(TubeMesh, AStraightTubeIsTheExactPolygonalWallAndASharpBendIsRefused) {
  const SmrmVessel v = straight_vessel(5, 2.5, 3.0, 12, 0.2, 0.1);
  MatX3 P(5 * 12, 3);
  P = v.rest_surface();
  const TubeMesh t = tube_mesh(v.rest_atoms(), P, 12, 0.2, 2, 1);
  EXPECT_EQ(t.rings, 5);
  EXPECT_EQ(t.mesh.num_elements(), 8 * 12 * 1 * 6);  // 8 axial cells x 12 spokes x 1 layer x 6
  const double area = polygon_A(12, 3.6) - polygon_A(12, 3.0);
  EXPECT_NEAR(mesh_volume(t.mesh), area * 10.0, 1e-9 * area * 10.0);
  // every node is tagged with where it lies: mid-edge nodes half-way
  EXPECT_DOUBLE_EQ(t.axial.maxCoeff(), 4.0);
  EXPECT_DOUBLE_EQ(t.radial.maxCoeff(), 1.0);
  // rings that cross inside the wall (a kink of 90 degrees between atoms 1 mm apart, radius 3 mm)
  MatX3 C(3, 3);
  C << 0, 0, 0, 1, 0, 0, 1, 1, 0;
  MatX3 Q(3 * 6, 3);
  const Vec3 normals[3] = {Vec3(1, 0, 0), Vec3(1, 1, 0).normalized(), Vec3(0, 1, 0)};
  for (Index i = 0; i < 3; ++i) {
    const Vec3 u = normals[i].cross(Vec3(0, 0, 1)).normalized(), w = Vec3(0, 0, 1);
    for (Index j = 0; j < 6; ++j) {
      const double a = 2 * std::numbers::pi * static_cast<double>(j) / 6;
      Q.row(i * 6 + j) = (C.row(i).transpose() + 3.0 * (std::cos(a) * u + std::sin(a) * w)).transpose();
    }
  }
  try {
    tube_mesh(C, Q, 6, 0.1, 1, 1);
    ADD_FAILURE() << "a kinked tube was meshed";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("turns inside out between rings"), std::string::npos) << e.what();
  }
  EXPECT_THROW(tube_mesh(C, Q.topRows(10), 6, 0.1, 1, 1), InvalidInput);  // sizes
  EXPECT_THROW(tube_mesh(C, Q, 6, 0.0, 1, 1), InvalidInput);              // no wall
}

TEST(VesselReference, ClampedTubeUnderABandLoadMatchesTimoshenkoBeamTheory) {
  // 60 mm tube, lumen radius 3 mm, wall 0.6 mm (ratio 0.2), E = 100 kPa, nu = 0.45, clamped at both ends,
  // 2 mN across the middle: deflection ~0.5 % of the length (small-deflection regime).
  const double E = 0.1, nu = 0.45, P = 0.002, L = 60;
  const Index M = 24;
  const SmrmVessel v = straight_vessel(25, 2.5, 3.0, M, 0.2, E);
  VesselMeshSettings ms;
  ms.thickness_ratio = 0.2;
  ms.spoke_stride = 2;  // 12 FEM spokes
  ms.axial_subdivisions = 2;
  const VesselReference ref(v, {E, nu}, ms);
  const VesselFemResult r = ref.solve(12, Vec3(0, 0, -P));
  const double I = polygon_I(12, 3.6) - polygon_I(12, 3.0), A = polygon_A(12, 3.6) - polygon_A(12, 3.0);
  const double m = 3.0 / 3.6, m2 = m * m, G = E / (2 * (1 + nu));
  const double kappa =
      6 * (1 + nu) * (1 + m2) * (1 + m2) / ((7 + 6 * nu) * (1 + m2) * (1 + m2) + (20 + 12 * nu) * m2);
  const double timoshenko = P * L * L * L / (192 * E * I) + P * L / (4 * kappa * G * A);
  const double fem = -r.centerline(12, 2);
  std::cout << "tube: FEM " << fem << " mm, Timoshenko " << timoshenko << " mm (bending "
            << P * L * L * L / (192 * E * I) << "), nodes " << ref.tube().mesh.num_nodes() << ", "
            << r.solve_seconds << " s\n";
  EXPECT_NEAR(fem, timoshenko, 0.08 * timoshenko);
  // symmetric about the loaded atom, ends held, and the lumen follows the wall
  for (Index k = 1; k < 12; ++k) EXPECT_NEAR(r.centerline(12 - k, 2), r.centerline(12 + k, 2), 0.01 * fem);
  EXPECT_NEAR(r.centerline.row(0).norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.centerline.row(24).norm(), 0.0, 1e-12);
  EXPECT_GT(-r.lumen.col(2).mean(), 0.2 * fem);

  // The SMRM of the same wall: pinned end atoms (no end slope held) and no shear, so the chain with
  // k_b = E I / h^3 and the paper's k_cl, k_r differs from the clamped tube; the comparison reports it.
  const MatX3 u = smrm_centerline_displacement(v.make_chain(false), 12, Vec3(0, 0, -P));
  const CenterlineError e = compare_centerline(u, r.centerline, 12);
  EXPECT_NEAR(e.loaded_fem, fem, 1e-9);
  EXPECT_GT(e.loaded_model, 0.0);
  EXPECT_GE(e.max, e.rms);
  EXPECT_THROW(ref.solve(0, Vec3(0, 0, -P)), InvalidInput);  // an end atom is clamped
  EXPECT_THROW(ref.solve(12, Vec3::Zero()), InvalidInput);
}
