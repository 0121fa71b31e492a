#include "medspring/skeleton/voxelize.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/skeleton/phantom_volumes.hpp"

namespace medspring {
namespace {

Index count(const MaskVolume& m) {
  Index n = 0;
  for (auto v : m.data) n += v;
  return n;
}

bool border_is_background(const MaskVolume& m) {
  for (Index k = 0; k < m.dims[2]; ++k)
    for (Index j = 0; j < m.dims[1]; ++j)
      for (Index i = 0; i < m.dims[0]; ++i) {
        const bool border =
            i == 0 || j == 0 || k == 0 || i == m.dims[0] - 1 || j == m.dims[1] - 1 || k == m.dims[2] - 1;
        if (border && m.at(i, j, k)) return false;
      }
  return true;
}

// ---- ALGORITHMS.md §8.5 check 24 ----
TEST(Voxelize, KidneyPhantomVoxelVolumeWithin3PercentOfMeshVolume) {
  const SurfaceMesh mesh = kidney_phantom();
  VoxelizeStats st;
  const MaskVolume m = voxelize(mesh, {}, &st);
  const Eigen::Matrix<double, 2, 3> box = bounds(mesh.V);
  EXPECT_DOUBLE_EQ(st.voxel_size, (box.row(1) - box.row(0)).minCoeff() / 48.0);  // §3.6 default
  EXPECT_EQ(st.odd_rows, 0);                                                     // watertight
  EXPECT_TRUE(border_is_background(m));
  const double voxel_volume = static_cast<double>(count(m)) * std::pow(st.voxel_size, 3);
  const double mesh_volume = signed_volume(mesh.V, mesh.F);
  EXPECT_NEAR(voxel_volume / mesh_volume, 1.0, 0.03);
  std::printf("[ figures  ] kidney phantom: voxel / mesh volume = %.5f (h_v = %.4f mm)\n",
              voxel_volume / mesh_volume, st.voxel_size);
  // the phantom volume of phantom_volumes.hpp is the same voxelisation
  EXPECT_EQ(kidney_phantom_volume().data, m.data);
}

TEST(Voxelize, IcosphereVoxelsMatchTheMeshVolumeAndPadding) {
  const SurfaceMesh mesh = icosphere(3, 10.0);
  VoxelizeStats st;
  const MaskVolume m = voxelize(mesh, {.padding = 3}, &st);
  EXPECT_TRUE(border_is_background(m));
  const Eigen::Matrix<double, 2, 3> box = bounds(mesh.V);
  for (int a = 0; a < 3; ++a) {
    // the grid covers the box plus 3 voxels on each side
    EXPECT_LE(m.origin[a], box(0, a) - 3 * st.voxel_size + 1e-12);
    EXPECT_GE(m.origin[a] + (m.dims[a] - 1) * st.voxel_size, box(1, a) + 3 * st.voxel_size - 1e-12);
  }
  const double ratio =
      static_cast<double>(count(m)) * std::pow(st.voxel_size, 3) / signed_volume(mesh.V, mesh.F);
  EXPECT_NEAR(ratio, 1.0, 0.02);
}

TEST(Voxelize, RowsWithOddCrossingsAreClassifiedByWindingNumber) {
  const SurfaceMesh closed = icosphere(3, 10.0);
  SurfaceMesh holed = closed;  // remove two faces: the mesh is no longer watertight
  holed.F.row(5) = holed.F.row(holed.num_faces() - 1);
  holed.F.row(17) = holed.F.row(holed.num_faces() - 2);
  holed.F.conservativeResize(holed.num_faces() - 2, 3);
  const VoxelizeSettings vs{.voxel_size = 0.25};
  VoxelizeStats st;
  const MaskVolume a = voxelize(closed, vs), b = voxelize(holed, vs, &st);
  EXPECT_GT(st.odd_rows, 0);
  Index differ = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) differ += a.data[i] != b.data[i];
  EXPECT_LE(differ, count(a) / 1000);  // at most 0.1 % of the voxels change
}

TEST(Voxelize, WindingNumberIsOneInsideAndZeroOutside) {
  const SurfaceMesh mesh = icosphere(2, 5.0);
  EXPECT_NEAR(winding_number(mesh, Vec3(0.3, -0.2, 0.1)), 1.0, 1e-12);
  EXPECT_NEAR(winding_number(mesh, Vec3(7.0, 0.0, 0.0)), 0.0, 1e-12);
}

TEST(Voxelize, RejectsEmptyMeshAndBadSettings) {
  EXPECT_THROW(voxelize(SurfaceMesh{}), InvalidInput);
  EXPECT_THROW(voxelize(icosphere(1), {.divisions = 0}), InvalidInput);
  EXPECT_THROW(voxelize(icosphere(1), {.voxel_size = -1.0}), InvalidInput);
}

TEST(CloseBoundaryLoops, TubeGetsTwoConsistentFanCapsAtItsEndCentroids) {
  SurfaceMesh mesh = tube(40, 30, 2.5, 3.0);
  const std::vector<BoundaryCap> caps = close_boundary_loops(mesh);
  ASSERT_EQ(caps.size(), 2u);
  EXPECT_NEAR((caps[0].centroid - Vec3(0, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((caps[1].centroid - Vec3(97.5, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((caps[0].normal - Vec3(-1, 0, 0)).norm(), 0.0, 1e-12);  // outward
  EXPECT_NEAR((caps[1].normal - Vec3(1, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(caps[0].loop.size(), 30u);
  EXPECT_EQ(mesh.num_vertices(), 1202);
  EXPECT_EQ(mesh.num_faces(), 2340 + 60);
  const MeshReport rep = validate_mesh(mesh);
  EXPECT_TRUE(rep.valid()) << rep.first_problem;
  EXPECT_TRUE(rep.closed());
  EXPECT_EQ(rep.inconsistent_edges, 0);
  EXPECT_EQ(rep.euler_characteristic, 2);
  const double polygon_area = 0.5 * 30 * 9.0 * std::sin(2 * std::numbers::pi / 30);
  EXPECT_NEAR(rep.signed_volume, polygon_area * 97.5, 1e-9 * polygon_area * 97.5);
}

TEST(CloseBoundaryLoops, ClosedMeshIsLeftUnchanged) {
  SurfaceMesh mesh = kidney_phantom();
  const SurfaceMesh before = mesh;
  EXPECT_TRUE(close_boundary_loops(mesh).empty());
  EXPECT_EQ(mesh.V, before.V);
  EXPECT_EQ(mesh.F, before.F);
}

TEST(CenterlineFromMesh, OpenTubeCenterlineRunsCapToCapOnTheAxis) {
  const SurfaceMesh mesh = tube(40, 30, 2.5, 3.0);
  const MeshCenterline mc = centerline_from_mesh(mesh);
  const SkeletonResult& r = mc.skeleton;
  const double hv = mc.voxel_stats.voxel_size;
  ASSERT_EQ(mc.caps.size(), 2u);
  EXPECT_EQ(r.ends[0].kind, EndKind::Capped);
  EXPECT_EQ(r.ends[1].kind, EndKind::Capped);
  EXPECT_GT(r.ends[0].trimmed, 0.0);
  EXPECT_GT(r.ends[0].extended, 0.0);
  ASSERT_EQ(r.atoms.rows(), 40);
  // §3.6: re-extended to the cap planes x = 0 and x = 97.5
  EXPECT_NEAR(r.atoms(0, 0), 0.0, 1e-9);
  EXPECT_NEAR(r.atoms(39, 0), 97.5, 1e-9);
  const double inscribed = 3.0 * std::cos(std::numbers::pi / 30);  // of the 30-gon cross-section
  double max_off = 0.0;
  for (Index i = 0; i < r.atoms.rows(); ++i) {
    max_off = std::max(max_off, std::hypot(r.atoms(i, 1), r.atoms(i, 2)));
    EXPECT_NEAR(r.radii[i], inscribed, hv) << "atom " << i;
  }
  EXPECT_LE(max_off, hv);  // within one voxel of the axis
  std::printf("[ figures  ] tube mesh (h_v %.4f): max off-axis %.4f mm, radius %.4f (inscribed %.4f)\n", hv,
              max_off, r.radii[20], inscribed);
}

TEST(CenterlineFromMesh, KidneyPhantomCenterlineHas42AtomsInsideTheMesh) {
  const SurfaceMesh mesh = kidney_phantom();
  const MeshCenterline mc = centerline_from_mesh(mesh, {.atom_count = 42});
  const SkeletonResult& r = mc.skeleton;
  EXPECT_TRUE(mc.caps.empty());
  ASSERT_EQ(r.atoms.rows(), 42);
  EXPECT_EQ(r.ends[0].kind, EndKind::Closed);
  EXPECT_EQ(r.ends[1].kind, EndKind::Closed);
  for (Index i = 0; i < r.atoms.rows(); ++i) {
    EXPECT_GT(winding_number(mesh, r.atoms.row(i).transpose()), 0.5) << "atom " << i;
    EXPECT_LE(r.radii[i], 18.0) << "atom " << i;  // c = 18 mm is the smallest semi-axis
  }
  // mid-length, the inscribed radius approaches c (polyhedron and voxels make it a little smaller)
  EXPECT_GT(r.radii.maxCoeff(), 16.5);
  // the long axis of the phantom: the end atoms lie near the poles (+-55 mm before bending)
  const double span = (r.atoms.row(0) - r.atoms.row(41)).norm();
  EXPECT_GT(span, 80.0);
  EXPECT_LT(span, 110.0);
}

}  // namespace
}  // namespace medspring
