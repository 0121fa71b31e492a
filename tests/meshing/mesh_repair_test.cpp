#include "medspring/meshing/mesh_repair.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "medspring/geometry/phantoms.hpp"
#include "meshing_test_util.hpp"

namespace medspring {
namespace {

using testing::expect_closed_genus0;
using testing::expect_invalid_input_naming;

/// Removes the listed faces and then the vertices no face uses any more.
SurfaceMesh without_faces(const SurfaceMesh& m, const std::vector<Index>& drop) {
  SurfaceMesh out = m;
  out.F.resize(0, 3);
  MatX3i F(m.num_faces(), 3);
  Index n = 0;
  for (Index f = 0; f < m.num_faces(); ++f)
    if (std::find(drop.begin(), drop.end(), f) == drop.end()) F.row(n++) = m.F.row(f);
  out.F = F.topRows(n);
  weld_vertices(out);
  return out;
}

/// The faces around vertex v.
std::vector<Index> star(const SurfaceMesh& m, Index v) {
  std::vector<Index> s;
  for (Index f = 0; f < m.num_faces(); ++f)
    if (m.F(f, 0) == v || m.F(f, 1) == v || m.F(f, 2) == v) s.push_back(f);
  return s;
}

TEST(MeshRepair, CheckCountsHolesAndBoundaryEdges) {
  const SurfaceMesh sphere = icosphere(3, 10.0);
  const ClosedManifoldReport closed = check_closed_manifold(sphere);
  EXPECT_TRUE(closed.ok());
  EXPECT_EQ(closed.holes, 0);
  std::vector<Index> drop = star(sphere, 0);  // a hexagonal or pentagonal hole
  const auto ring = static_cast<Index>(drop.size());
  drop.push_back(sphere.num_faces() - 1);  // and a triangular one elsewhere
  const ClosedManifoldReport open = check_closed_manifold(without_faces(sphere, drop));
  EXPECT_FALSE(open.ok());
  EXPECT_EQ(open.holes, 2);
  EXPECT_EQ(open.mesh.boundary_edges, ring + 3);
  EXPECT_EQ(open.nonmanifold_vertices, 0);
}

TEST(MeshRepair, RequireClosedManifoldNamesTheBoundaryEdgesAndTheHoleOption) {
  const SurfaceMesh sphere = icosphere(2, 10.0);
  const SurfaceMesh open = without_faces(sphere, {3, 40});
  expect_invalid_input_naming(
      [&] { require_closed_manifold(open, "liver.stl"); },
      {"liver.stl: surface is open: 6 boundary edges in 2 holes", "close_small_holes", "--close-holes"});
  EXPECT_TRUE(require_closed_manifold(sphere, "sphere").ok());
}

TEST(MeshRepair, BowTieVertexIsRefused) {
  // Two tetrahedra sharing one vertex: every edge has two triangles, but the vertex joins two fans.
  SurfaceMesh m;
  m.V.resize(7, 3);
  m.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1;
  m.F.resize(8, 3);
  m.F << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3,  //
      0, 5, 4, 0, 4, 6, 0, 6, 5, 4, 5, 6;
  const ClosedManifoldReport r = check_closed_manifold(m);
  EXPECT_EQ(r.nonmanifold_vertices, 1);
  EXPECT_TRUE(r.mesh.closed());
  expect_invalid_input_naming([&] { require_closed_manifold(m, "organ"); },
                              {"organ: surface is not manifold: 1 vertex", "bow-tie"});
}

TEST(MeshRepair, NonManifoldEdgeIsRefused) {
  SurfaceMesh m;
  m.V.resize(5, 3);
  m.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1;
  m.F.resize(3, 3);
  m.F << 0, 1, 2, 1, 0, 3, 0, 1, 4;  // three triangles on edge (0, 1)
  expect_invalid_input_naming(
      [&] { require_closed_manifold(m, "organ"); },
      {"organ: surface is not manifold: 1 edge is shared by more than two triangles"});
  expect_invalid_input_naming([&] { close_small_holes(m, 10); }, {"not manifold"});
}

TEST(MeshRepair, CloseSmallHolesFillsHolesUpToTheLimitAndLeavesLargerOnes) {
  const SurfaceMesh sphere = icosphere(3, 10.0);
  std::vector<Index> drop = star(sphere, 0);
  const auto ring = static_cast<Index>(drop.size());  // 5 at an icosahedron corner
  drop.push_back(sphere.num_faces() - 1);
  SurfaceMesh m = without_faces(sphere, drop);

  const HoleFillReport small = close_small_holes(m, 4);
  EXPECT_EQ(small.holes_found, 2);
  EXPECT_EQ(small.holes_filled, 1);
  EXPECT_EQ(small.holes_skipped, 1);
  EXPECT_GE(small.faces_added, 1);
  EXPECT_EQ(check_closed_manifold(m).holes, 1);
  EXPECT_EQ(check_closed_manifold(m).mesh.boundary_edges, ring);

  const HoleFillReport rest = close_small_holes(m, ring);
  EXPECT_EQ(rest.holes_found, 1);
  EXPECT_EQ(rest.holes_filled, 1);
  expect_closed_genus0(m);
  // The faired patches follow the sphere: the volume comes back within 0.5 %.
  EXPECT_NEAR(signed_volume(m.V, m.F) / signed_volume(sphere.V, sphere.F), 1.0, 0.005);
}

TEST(MeshRepair, CloseSmallHolesRefusesATooSmallLimit) {
  SurfaceMesh m = icosphere(1, 1.0);
  expect_invalid_input_naming([&] { close_small_holes(m, 2); }, {"max_hole_edges must be >= 3 (got 2)"});
}

}  // namespace
}  // namespace medspring
