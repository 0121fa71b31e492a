// Vessel trees from a segmentation or a closed surface mesh (issue 17, docs/vessels.md): the tree skeleton
// of every endpoint on a procedural Y (its mask, and the union of its tubes as a mesh) finds the two
// outlets and the junction, and the rebuilt tree surface lies within a voxel or two of the input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "medspring/builders/vessel_build.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/io/volume_io.hpp"
#include "medspring/meshing/mesh_repair.hpp"
#include "medspring/meshing/mesh_union.hpp"
#include "medspring/skeleton/centerline_tree.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

// A Y: trunk (0,0,0) -> J = (30,0,0), two branches J -> B1, B2 out of the xy plane and of unequal length
// (a planar, mirror-symmetric Y puts the tube vertices of the union exactly on each other's edges: CGAL
// then leaves zero-area triangles, docs/vessels.md); radius 4 mm (trunk) and 3 mm (branches).
const Vec3 kJ(30.0, 0.0, 0.0), kA(0.0, 0.0, 0.0), kB1(55.0, 18.0, 4.0), kB2(53.0, -17.0, -3.0);

double capsule_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

bool inside_y(const Vec3& p) {
  return capsule_distance(p, kA, kJ) <= 4.0 || capsule_distance(p, kJ, kB1) <= 3.0 ||
         capsule_distance(p, kJ, kB2) <= 3.0;
}

MaskVolume y_mask(double h) {
  MaskVolume m;
  m.spacing = Vec3::Constant(h);
  m.origin = Vec3(-6.0, -24.0, -10.0);
  m.dims = {static_cast<Index>(std::ceil(68.0 / h)), static_cast<Index>(std::ceil(48.0 / h)),
            static_cast<Index>(std::ceil(20.0 / h))};
  m.data.assign(m.size(), 0);
  for (Index k = 0; k < m.dims[2]; ++k)
    for (Index j = 0; j < m.dims[1]; ++j)
      for (Index i = 0; i < m.dims[0]; ++i) m.at(i, j, k) = inside_y(m.to_world(Vec3(i, j, k))) ? 1 : 0;
  return m;
}

// The Y as a closed mesh: the union of its path tubes (flat caps at the three ends), 1.5 mm rings.
SurfaceMesh y_mesh() {
  MatX3 atoms(7, 3);
  atoms << 0, 0, 0, 15, 0, 0, 30, 0, 0, 42.5, 9, 2, 55, 18, 4, 41.5, -8.5, -1.5, 53, -17, -3;
  VecX radii(7);
  radii << 4, 4, 4, 3, 3, 3, 3;
  const CenterlineTree ct = tree_from_parents(atoms, {-1, 0, 1, 2, 3, 2, 5}, radii);
  SmrmTreeSettings ts;
  ts.vessel.spokes = 24;
  return blended_tree_surface(ct, SmrmTree(ct, ts), 1.5).mesh;
}

TEST(VesselTreeSkeleton, YMaskGivesTwoOutletsMeetingAtTheFork) {
  const MaskVolume mask = y_mask(0.5);
  const TreeSkeleton t = extract_centerline_tree(mask);
  for (const auto& l : t.lines)
    std::cerr << "DEBUG line " << l.size() << " from " << l.points.row(0) << " to " << l.points.row(l.size() - 1)
              << " r0 " << l.radii[0] << "\n";
  for (const auto& n : t.notes) std::cerr << "DEBUG " << n << "\n";
  ASSERT_EQ(t.lines.size(), 2u);
  EXPECT_EQ(t.components, 1);
  const CenterlineTree ct = merge_centerlines(t.lines);
  ASSERT_EQ(ct.branches.size(), 3u);
  EXPECT_EQ(ct.junctions(), 1);
  // the root is the widest end (the trunk's, at x = 0, trimmed by about its radius)
  const Vec3 root = ct.branches[0].line.points.row(0).transpose();
  EXPECT_LT(root.x(), 6.0) << root.transpose();
  // the junction lies near the fork (the skeleton of a Y meets a little into the wider trunk)
  const Centerline& trunk = ct.branches[0].line;
  const Vec3 junction = trunk.points.row(trunk.size() - 1).transpose();
  EXPECT_LT((junction - kJ).norm(), 4.0) << junction.transpose();
  // every point of the skeleton is near the Y's axis, and the radii are those of the tube (+- 1 voxel)
  for (const auto& b : ct.branches)
    for (Index k = 0; k < b.line.size(); ++k) {
      const Vec3 p = b.line.points.row(k).transpose();
      const double axis =
          std::min({capsule_distance(p, kA, kJ), capsule_distance(p, kJ, kB1), capsule_distance(p, kJ, kB2)});
      EXPECT_LT(axis, 1.0) << p.transpose();
      const double r_true = (p.x() < kJ.x() - 4.0) ? 4.0 : (p.x() > kJ.x() + 6.0 ? 3.0 : -1.0);
      if (r_true > 0) EXPECT_NEAR(b.line.radii[k], r_true, 0.75) << p.transpose();
    }
  // bad input: an empty mask
  MaskVolume empty = mask;
  std::fill(empty.data.begin(), empty.data.end(), 0);
  EXPECT_THROW(extract_centerline_tree(empty), InvalidInput);
}

TEST(VesselTreeSkeleton, BuildVesselFromAYSegmentationAndMeshIsATreeCloseToTheInput) {
  const std::filesystem::path dir = testing::temp_dir("vessel-tree-skeleton");
  {  // the Y as a label volume
    const MaskVolume m = y_mask(0.5);
    LabelVolume l;
    l.dims = m.dims;
    l.spacing = m.spacing;
    l.origin = m.origin;
    l.direction = m.direction;
    l.data.assign(m.data.begin(), m.data.end());
    write_label_volume(dir / "y.mha", l);
  }
  write_mesh(dir / "y.vtp", y_mesh());
  for (const bool from_mask : {true, false}) {
    SCOPED_TRACE(from_mask ? "segmentation" : "mesh");
    VesselBuildSettings st;
    if (from_mask)
      st.source.mask = dir / "y.mha";
    else
      st.source.mesh = dir / "y.vtp";
    st.all_branches = true;
    st.blend = true;
    st.smrm.atoms = 16;
    const VesselBuild v = build_vessel(st);
    ASSERT_TRUE(v.tree);
    const VesselSummary& s = v.summary;
    EXPECT_EQ(s.branches, 3);
    EXPECT_EQ(s.junctions, 1);
    EXPECT_LE(s.rest_error_mm, 1e-9);
    EXPECT_TRUE(s.blended && s.surface_closed);
    EXPECT_EQ(s.surface_components, 1);
    ASSERT_TRUE(s.has_distance);
    // every rebuilt node lies on the input wall (within about a voxel and the ring discretisation);
    // the Hausdorff distance also counts the input's ends beyond the trimmed skeleton (about a radius)
    EXPECT_LT(s.to_input_max_mm, 1.0);
    EXPECT_LT(s.to_input_mean_mm, 0.4);
    EXPECT_LT(s.hausdorff_mm, 5.0);
    EXPECT_GT(s.hausdorff_mm, 0.0);
    write_vessel_files(dir, v);  // the package of a tree from a mask
    EXPECT_TRUE(std::filesystem::exists(dir / "vessel.msm"));
  }
}

}  // namespace
}  // namespace medspring
