// The FEM reference pipeline (docs/accuracy.md): meshes, the .frd reader, CalculiX runs, matched loads
// and the closed-form validations on coarse meshes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "medspring/core/error.hpp"
#include "medspring/fem/calculix.hpp"
#include "medspring/fem/frd.hpp"
#include "medspring/fem/matching.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/tet_mesh.hpp"
#include "medspring/fem/validation.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "test_support.hpp"

using namespace medspring;
using namespace medspring::fem;
namespace fs = std::filesystem;

namespace {

const char* kFrd =
    "    1C\n"
    "    2C                             2                                     1\n"
    " -1         1 0.00000E+00 0.00000E+00 0.00000E+00\n"
    " -1         2 1.00000E+00 0.00000E+00 0.00000E+00\n"
    " -3\n"
    "  100CL  101 5.00000E-01           2                     0    1           1\n"
    " -4  DISP        4    1\n"
    " -5  D1          1    2    1    0\n"
    " -1         1 0.00000E+00 0.00000E+00 0.00000E+00\n"
    " -1         2 7.50000E-02-1.00000E-02 1.50000E-03\n"
    " -3\n"
    "  100CL  101 1.00000E+00           2                     0    1           1\n"
    " -4  DISP        4    1\n"
    " -5  D1          1    2    1    0\n"
    " -1         1 0.00000E+00 0.00000E+00 0.00000E+00\n"
    " -1         2 1.50000E-01-2.00000E-02 3.00000E-03\n"
    " -3\n"
    " 9999\n";

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) s.replace(pos, from.size(), to);
  return s;
}

// Expects IoError whose message names `line`.
void expect_frd_error(const std::string& text, int line) {
  try {
    parse_frd(text, "t.frd");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("t.frd: line " + std::to_string(line) + ":"), std::string::npos)
        << e.what();
  }
}

FemSettings no_cache() {
  FemSettings s;
  s.use_cache = false;
  return s;
}

}  // namespace

TEST(FrdReader, ReadsNodesAndTheLastDisplacementBlock) {
  const FrdData d = parse_frd(kFrd, "t.frd");
  ASSERT_EQ(d.ids.size(), 2u);
  EXPECT_EQ(d.ids[1], 2);
  EXPECT_DOUBLE_EQ(d.X(1, 0), 1.0);
  ASSERT_EQ(d.disp.size(), 2u);
  const MatX3 u = last_displacement(d, 2, 1.0);
  EXPECT_DOUBLE_EQ(u(1, 0), 0.15);
  EXPECT_DOUBLE_EQ(u(1, 1), -0.02);  // fields run together without a blank: fixed columns
  EXPECT_DOUBLE_EQ(u(1, 2), 0.003);
  EXPECT_THROW(last_displacement(d, 3, 1.0), IoError);  // node 3 has no displacement
  EXPECT_THROW(last_displacement(d, 2, 2.0), IoError);  // not at the expected step time
}

TEST(FrdReader, MalformedFilesAreRefusedWithTheLineNamed) {
  const std::string ok = kFrd;
  expect_frd_error(replace(ok, " 7.50000E-02-1.00000E-02 1.50000E-03", " 7.50000E-02-1.00000E-02"),
                   10);                                                                        // short
  expect_frd_error(replace(ok, "1.50000E-01-2", "1.5000XE-01-2"), 16);                         // bad number
  expect_frd_error(replace(ok, " 9999\n", ""), 17);                                            // no end
  expect_frd_error(replace(ok, " -1         2 1.00000E+00", " -1         1 1.00000E+00"), 4);  // repeated
  expect_frd_error(
      replace(ok, "    2C                             2", "    2C                             3"), 5);
  expect_frd_error(replace(ok, " -1         2 1.50000E-01", " -1         7 1.50000E-01"),
                   16);  // unknown node
  expect_frd_error(replace(ok, "5.00000E-01", "nan        "), 6);
  expect_frd_error(ok.substr(0, ok.find(" -3\n  100CL")), 4);  // truncated inside the node block
  expect_frd_error(std::string("\x01\x02 -1\n"), 1);
}

TEST(Material, ImpossibleMaterialsAreRefused) {
  EXPECT_THROW(validate_material({0.0, 0.3}), InvalidInput);
  EXPECT_THROW(validate_material({-1.0, 0.3}), InvalidInput);
  EXPECT_THROW(validate_material({1.0, 0.5}), InvalidInput);
  EXPECT_THROW(validate_material({1.0, 0.6}), InvalidInput);
  EXPECT_THROW(validate_material({1.0, NAN}), InvalidInput);
  EXPECT_NO_THROW(validate_material({0.01, 0.49}));
  const Material m = Material::from_kpa(10, 0.45);
  EXPECT_DOUBLE_EQ(m.E, 0.01);  // 10 kPa = 0.01 N/mm^2
  EXPECT_NEAR(m.c10(), 0.01 / (4 * 1.45), 1e-15);
  EXPECT_NEAR(m.d1(), 2.0 / (0.01 / (3 * 0.1)), 1e-12);
}

TEST(TetMesh, BoxMeshIsConformingAndQuadratic) {
  const TetMesh m = box_mesh(graded(0, 2, 2), graded(0, 3, 3), graded(0, 1, 1, 1.0));
  EXPECT_EQ(m.num_elements(), 2 * 3 * 1 * 6);
  EXPECT_NEAR(mesh_volume(m), 6.0, 1e-12);
  // a closed boundary: 2 triangles per cell face on the outside
  EXPECT_EQ(boundary_faces(m).rows(), 2 * 2 * (2 * 3 + 3 * 1 + 2 * 1));
  // grid nodes (3 x 4 x 2) + one per unique edge
  for (Index e = 0; e < m.num_elements(); ++e) {
    const Vec3 mid = m.X.row(m.T(e, 4)), a = m.X.row(m.T(e, 0)), b = m.X.row(m.T(e, 1));
    EXPECT_NEAR((mid - 0.5 * (a + b)).norm(), 0.0, 1e-12);
  }
  const auto g = graded(0, 10, 4, 2.0);
  EXPECT_NEAR(g[1] - g[0], 10.0 / 15.0, 1e-12);  // cells 1 : 2 : 4 : 8
}

// The large-strain tables' FEM strain (docs/accuracy-nonlinear.md, "Large strain"): an affine field gives its
// principal stretches exactly on every element, a large rigid rotation none, a local dent is found in its
// element, and a field of the wrong shape or with a NaN is refused.
TEST(TetMesh, PeakStrainIsThePrincipalStretchAndIgnoresRigidMotion) {
  const TetMesh m = box_mesh(graded(0, 2, 2), graded(0, 3, 3), graded(0, 1, 2));
  const Mat3 R = Eigen::AngleAxisd(1.1, Vec3(1, 2, -0.5).normalized()).toRotationMatrix();
  const Mat3 S = Vec3(0.7, 1.1, 1.25).asDiagonal();  // 30 % shortening, 25 % stretch
  const Mat3 V = Eigen::AngleAxisd(0.4, Vec3(0.3, -1, 2).normalized()).toRotationMatrix();
  auto field = [&](const Mat3& F) {
    MatX3 u(m.num_nodes(), 3);
    for (Index i = 0; i < m.num_nodes(); ++i)
      u.row(i) = (F * m.X.row(i).transpose() - m.X.row(i).transpose() + Vec3(3, -2, 7)).transpose();
    return u;
  };
  const PeakStrain rigid = peak_strain(m, field(R));
  EXPECT_NEAR(rigid.compressive, 0.0, 1e-12);
  EXPECT_NEAR(rigid.tensile, 0.0, 1e-12);
  const PeakStrain a = peak_strain(m, field(R * V * S * V.transpose()));  // rotated principal axes
  EXPECT_NEAR(a.compressive, 0.3, 1e-12);
  EXPECT_NEAR(a.tensile, 0.25, 1e-12);
  // a dent: one corner node of one element pushed in (a node that only few elements share)
  MatX3 u = MatX3::Zero(m.num_nodes(), 3);
  const Index node = m.T(5, 0);
  u(node, 2) = -0.2;
  const PeakStrain d = peak_strain(m, u);
  EXPECT_GT(d.compressive, 0.05);
  ASSERT_GE(d.compressive_element, 0);
  bool has_node = false;
  for (int k = 0; k < 4; ++k) has_node |= m.T(d.compressive_element, k) == node;
  EXPECT_TRUE(has_node) << "the peak sits in an element of the moved node";
  EXPECT_THROW(peak_strain(m, MatX3::Zero(m.num_nodes() - 1, 3)), InvalidInput);
  u(0, 0) = NAN;
  EXPECT_THROW(peak_strain(m, u), InvalidInput);
}

TEST(TetMesh, ClosedSurfaceIsMeshedByTetgenAndOpenOnesAreRefused) {
  const SurfaceMesh sphere = icosphere(2, 10.0);
  TetgenSettings s;
  s.max_volume = 20;
  const TetMesh m = tet_mesh_from_surface(sphere, s);
  EXPECT_NEAR(mesh_volume(m), signed_volume(sphere.V, sphere.F), 1e-9 * mesh_volume(m));
  EXPECT_GT(m.num_elements(), 100);
  const TetMesh finer = tet_mesh_from_surface(sphere, {.max_volume = 5});
  EXPECT_GT(finer.num_elements(), m.num_elements());

  const SurfaceMesh open = tube(10, 12);  // an open tube: refused before TetGen runs
  try {
    tet_mesh_from_surface(open, s);
    ADD_FAILURE() << "open surface accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("boundary"), std::string::npos) << e.what();
  }
  SurfaceMesh inside_out = sphere;
  inside_out.F.col(1).swap(inside_out.F.col(2));
  EXPECT_THROW(tet_mesh_from_surface(inside_out, s), InvalidInput);
}

TEST(FemProblem, SupportsThatLeaveRigidMotionFreeAreRefused) {
  FemProblem p{box_mesh(graded(0, 1, 1), graded(0, 1, 1), graded(0, 1, 1)), {1.0, 0.3}};
  EXPECT_THROW(validate_problem(p), InvalidInput);  // no support at all
  // nodes on one line: rotation about it stays free
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 1) == 0 && p.mesh.X(i, 2) == 0) p.fixed.push_back(i);
  try {
    validate_problem(p);
    ADD_FAILURE() << "a line support accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("1 rigid motion"), std::string::npos) << e.what();
  }
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 2) == 0 && p.mesh.X(i, 1) == 1) p.fixed.push_back(i);
  EXPECT_NO_THROW(validate_problem(p));
  p.material.nu = 0.5;
  EXPECT_THROW(validate_problem(p), InvalidInput);
}

TEST(Matching, DiskLoadsCarryTheTotalForceAndQuadraticInterpolationIsExactOnLinearFields) {
  const TetMesh m = box_mesh(graded(-5, 5, 6), graded(-5, 5, 6), graded(-4, 0, 3));
  const MatX6i top = faces_on_plane(m, boundary_faces(m), 2, 0.0);
  const Vec3 F(0.1, 0, -1);
  Vec3 sum = Vec3::Zero(), moment = Vec3::Zero();
  for (const auto& [node, f] : disk_load_quadratic(m, top, Vec3::Zero(), 2.0, F)) {
    sum += f;
    moment += Vec3(m.X.row(node)).cross(f);
  }
  EXPECT_NEAR((sum - F).norm(), 0.0, 1e-12);
  EXPECT_NEAR(moment.norm(), 0.0, 1e-3);  // centred on a symmetric mesh
  // the same rule on a triangle surface (the spring model's side)
  MatX3 V(top.rows() * 3, 3);
  MatX3i T(top.rows(), 3);
  for (Index t = 0; t < top.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      V.row(3 * t + k) = m.X.row(top(t, k));
      T(t, k) = 3 * t + k;
    }
  const MatX3 fl = disk_load_linear(V, T, Vec3::Zero(), 2.0, F);
  EXPECT_NEAR((fl.colwise().sum().transpose() - F).norm(), 0.0, 1e-12);
  EXPECT_THROW(disk_load_linear(V, T, Vec3(0, 0, 50), 1.0, F), InvalidInput);

  // u = A x + b is reproduced exactly by the face interpolation at any surface point
  Mat3 A;
  A << 0.1, 0.2, -0.3, 0.05, -0.1, 0.2, 0.3, 0.1, 0.0;
  const Vec3 b(1, -2, 0.5);
  MatX3 u(m.num_nodes(), 3);
  for (Index i = 0; i < m.num_nodes(); ++i) u.row(i) = (A * Vec3(m.X.row(i)) + b).transpose();
  const MatX3 pts = (MatX3(3, 3) << 1.3, -2.7, 0.2, 5.5, 0.1, -1.0, -0.4, 4.9, -4.3).finished();
  const MatX6i B = boundary_faces(m);
  const BoundarySample smp = locate_on_boundary(m, B, pts);
  const MatX3 ui = interpolate(B, smp, u);
  EXPECT_NEAR(smp.distance(0), 0.2, 1e-12);
  EXPECT_NEAR(smp.distance(1), 0.5, 1e-12);
  for (Index i = 0; i < 3; ++i) {
    const Vec3 on = pts.row(i).transpose() + Vec3::Zero();  // the nearest boundary point
    (void)on;
    const Index t = smp.face[static_cast<std::size_t>(i)];
    const Vec3 x = smp.bary(i, 0) * Vec3(m.X.row(B(t, 0))) + smp.bary(i, 1) * Vec3(m.X.row(B(t, 1))) +
                   smp.bary(i, 2) * Vec3(m.X.row(B(t, 2)));
    EXPECT_NEAR((ui.row(i).transpose() - (A * x + b)).norm(), 0.0, 1e-12);
  }
}

// The load-site read-out (docs/accuracy-nonlinear.md, "The load site"): the disk load's weights on an
// off-centre disk of a graded flat patch sum to 1 and have the disk's centre as their centroid, on both sides
// (linear and quadratic faces), so the disk mean of a linear field u = A x + b is its value at the centre.
// Lumping the load equally on the nodes inside the disk (a wrong rule) misses the centroid on the graded
// patch.
TEST(Matching, DiskLoadWeightsHaveTheDisksCentroidOnAGradedFlatPatch) {
  const TetMesh m = box_mesh(graded(-6, 6, 8, 1.6), graded(-6, 6, 7, 0.7), graded(-4, 0, 2));
  const MatX6i top = faces_on_plane(m, boundary_faces(m), 2, 0.0);
  const Vec3 c(1.3, -0.7, 0.0), F(0.2, -0.1, -1.0);
  const double a = 3.0;
  Vec3 sum = Vec3::Zero(), centroid = Vec3::Zero();
  double wsum = 0;
  for (const auto& [node, f] : disk_load_quadratic(m, top, c, a, F)) {
    const double w = f.dot(F) / F.squaredNorm();
    sum += f;
    wsum += w;
    centroid += w * Vec3(m.X.row(node));
  }
  EXPECT_NEAR((sum - F).norm(), 0.0, 1e-12);
  EXPECT_NEAR(wsum, 1.0, 1e-12);
  EXPECT_NEAR((centroid - c).norm(), 0.0, 0.01) << centroid.transpose();  // 256 sub-triangles per face
  // linear triangles: the patch's corner triangles
  MatX3 V(m.num_nodes(), 3);
  V = m.X;
  MatX3i T(top.rows(), 3);
  for (Index t = 0; t < top.rows(); ++t) T.row(t) << top(t, 0), top(t, 1), top(t, 2);
  const MatX3 fl = disk_load_linear(V, T, c, a, F);
  EXPECT_NEAR((fl.colwise().sum().transpose() - F).norm(), 0.0, 1e-12);
  const VecX w = fl * F / F.squaredNorm();
  EXPECT_NEAR((V.transpose() * w - c).norm(), 0.0, 0.01);
  Mat3 A;
  A << 0.1, 0.2, -0.3, 0.05, -0.1, 0.2, 0.3, 0.1, 0.0;
  const Vec3 b(1, -2, 0.5);
  MatX3 u(V.rows(), 3);
  for (Index i = 0; i < V.rows(); ++i) u.row(i) = (A * Vec3(V.row(i)) + b).transpose();
  EXPECT_NEAR((disk_mean_linear(V, T, {c, F, a}, u) - (A * c + b)).norm(), 0.0, 0.01);
  // the wrong rule: the whole load on the nodes inside the disk, equally
  Vec3 lumped = Vec3::Zero();
  double n = 0;
  for (Index i = 0; i < V.rows(); ++i)
    if (w[i] != 0.0 && (Vec3(V.row(i)) - c).norm() < a) lumped += Vec3(V.row(i)), n += 1;
  const double lin_err = (V.transpose() * w - c).norm(), lumped_err = (lumped / n - c).norm();
  EXPECT_GT(lumped_err, 0.05);
  EXPECT_GT(lumped_err, 5 * lin_err) << lin_err << " " << (centroid - c).norm();
  EXPECT_THROW(disk_mean_linear(V, T, {c, F, a}, u.topRows(3)), InvalidInput);
}

TEST(Calculix, AMissingCcxNamesThePackage) {
  const char* old_path = std::getenv("PATH");
  const std::string saved = old_path ? old_path : "";
  setenv("PATH", "/nonexistent-medspring", 1);
  FemProblem p{box_mesh(graded(0, 1, 1), graded(0, 1, 1), graded(0, 1, 1)), {1.0, 0.3}};
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 2) == 0) p.fixed.push_back(i);
  try {
    solve(p, no_cache());
    ADD_FAILURE() << "solved without ccx";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("calculix-ccx"), std::string::npos) << e.what();
  }
  setenv("PATH", saved.c_str(), 1);
}

TEST(Calculix, AFailedRunReportsItsLogAndCachesNothing) {
  FemProblem p{box_mesh(graded(0, 1, 1), graded(0, 1, 1), graded(0, 1, 1)), Material::from_kpa(1, 0.3)};
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 2) == 0) p.fixed.push_back(i);
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 2) == 1) p.loads.push_back({i, Vec3(0, 0, -10.0)});  // crushes the 1 kPa cube
  FemSettings s;
  s.cache_dir = medspring::testing::temp_dir("fem_fail").string();
  try {
    solve(p, s);
    ADD_FAILURE() << "a crushed cube converged";
  } catch (const SolverError& e) {
    EXPECT_NE(std::string(e.what()).find("CalculiX"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(s.cache_dir));
}

TEST(Calculix, ResultsAreCachedByTheirInputDeck) {
  FemProblem p{box_mesh(graded(0, 2, 2), graded(0, 2, 1), graded(0, 2, 1)), Material::from_kpa(10, 0.45)};
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 0) == 0) p.fixed.push_back(i);
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 0) == 2) p.loads.push_back({i, Vec3(0, 0, -1e-4)});
  FemSettings s;
  s.cache_dir = medspring::testing::temp_dir("fem_cache").string();
  const FemResult a = solve(p, s);
  EXPECT_FALSE(a.from_cache);
  const FemResult b = solve(p, s);
  EXPECT_TRUE(b.from_cache);
  EXPECT_EQ(a.key, b.key);
  EXPECT_EQ(a.u, b.u);
  p.material.E *= 2;  // another material: another key, a fresh solve
  const FemResult c = solve(p, s);
  EXPECT_FALSE(c.from_cache);
  EXPECT_NE(c.key, a.key);
  // twice as stiff, small strains: about half the displacement
  EXPECT_NEAR(c.u.col(2).minCoeff() / a.u.col(2).minCoeff(), 0.5, 0.01);
}

// Closed forms on coarse meshes (level 1); the finer levels and their errors are in docs/accuracy.md
// (`medspring accuracy`).
TEST(Validation, UniaxialNeoHookeanStretchIsExact) {
  const ValidationResult r = validate_uniaxial(1, no_cache());
  EXPECT_GT(r.analytic, 1.1);  // a large-deformation case
  EXPECT_LT(r.rel_error, 1e-4) << r.fem << " vs " << r.analytic;
}

TEST(Validation, CantileverMatchesBeamTheory) {
  const ValidationResult r = validate_cantilever(1, no_cache());
  EXPECT_LT(r.rel_error, 0.05) << r.fem << " vs " << r.analytic;
}

TEST(Validation, DiskIndentationMatchesBoussinesq) {
  for (const ValidationResult& r : validate_boussinesq(1, no_cache()))
    EXPECT_LT(r.rel_error, 0.05) << r.name << ": " << r.fem << " vs " << r.analytic;
}
