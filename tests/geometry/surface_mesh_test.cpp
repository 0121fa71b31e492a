#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"

namespace medspring {
namespace {

SurfaceMesh two_triangles() {
  SurfaceMesh m;
  m.V.resize(4, 3);
  m.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  m.F.resize(2, 3);
  m.F << 0, 1, 2, 0, 2, 3;
  return m;
}

TEST(SurfaceMesh, OpenSquareIsValidButOpen) {
  const MeshReport r = validate_mesh(two_triangles());
  EXPECT_TRUE(r.valid());
  EXPECT_FALSE(r.closed());
  EXPECT_EQ(r.boundary_edges, 4);
  EXPECT_EQ(r.edges, 5);
  EXPECT_THROW(require_valid_mesh(two_triangles(), "square", {.closed = true}), InvalidInput);
}

TEST(SurfaceMesh, ReportsOutOfRangeIndexWithFaceNumber) {
  SurfaceMesh m = two_triangles();
  m.F(1, 2) = 7;
  const MeshReport r = validate_mesh(m);
  EXPECT_EQ(r.bad_indices, 1);
  EXPECT_NE(r.first_problem.find("face 1"), std::string::npos) << r.first_problem;
  try {
    require_valid_mesh(m, "mesh.obj");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("mesh.obj: face 1"), std::string::npos) << e.what();
  }
}

TEST(SurfaceMesh, ReportsNaNVertex) {
  SurfaceMesh m = two_triangles();
  m.V(2, 1) = std::numeric_limits<double>::quiet_NaN();
  const MeshReport r = validate_mesh(m);
  EXPECT_EQ(r.nonfinite_vertices, 1);
  EXPECT_FALSE(r.valid());
  EXPECT_NE(r.first_problem.find("vertex 2"), std::string::npos);
}

TEST(SurfaceMesh, ReportsDegenerateAndDuplicateFaces) {
  SurfaceMesh m = two_triangles();
  m.F.conservativeResize(4, 3);
  m.F.row(2) << 2, 0, 1;  // duplicate of face 0 (rotated)
  m.F.row(3) << 1, 1, 3;  // repeated index
  const MeshReport r = validate_mesh(m);
  EXPECT_EQ(r.duplicate_faces, 1);
  EXPECT_EQ(r.degenerate_faces, 1);
  EXPECT_FALSE(r.valid());
}

TEST(SurfaceMesh, ReportsNonManifoldEdge) {
  SurfaceMesh m = two_triangles();
  m.V.conservativeResize(5, 3);
  m.V.row(4) << 0.5, 0.5, 1.0;
  m.F.conservativeResize(3, 3);
  m.F.row(2) << 0, 2, 4;  // third face on edge (0,2)
  const MeshReport r = validate_mesh(m);
  EXPECT_EQ(r.nonmanifold_edges, 1);
  EXPECT_FALSE(r.valid());
  EXPECT_NE(r.first_problem.find("non-manifold"), std::string::npos);
}

TEST(SurfaceMesh, WeldMergesNearCoincidentVertices) {
  // An icosphere with every triangle given its own three vertices ("triangle soup").
  const SurfaceMesh ico = icosphere(1, 1.0);
  SurfaceMesh soup;
  soup.V.resize(3 * ico.num_faces(), 3);
  soup.F.resize(ico.num_faces(), 3);
  for (Index f = 0; f < ico.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      soup.V.row(3 * f + k) = ico.V.row(ico.F(f, k)) * (1.0 + 1e-13 * k);
      soup.F(f, k) = 3 * f + k;
    }
  EXPECT_FALSE(validate_mesh(soup).closed());
  weld_vertices(soup);
  EXPECT_EQ(soup.num_vertices(), ico.num_vertices());
  const MeshReport r = validate_mesh(soup);
  EXPECT_TRUE(r.closed() && r.valid());
  EXPECT_EQ(r.euler_characteristic, 2);
}

TEST(SurfaceMesh, NormalsOfSphereAreRadial) {
  const SurfaceMesh m = icosphere(3, 2.0);
  MatX3 N;
  vertex_normals(m.V, m.F, N);
  for (Index i = 0; i < m.num_vertices(); ++i) EXPECT_GT(N.row(i).dot(m.V.row(i) / 2.0), 0.999);
  EXPECT_NEAR(surface_area(m.V, m.F) / (4 * 3.14159265358979 * 4), 1.0, 0.01);  // 642-vertex polyhedron
}

}  // namespace
}  // namespace medspring
