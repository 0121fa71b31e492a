// Centerlines of real and phantom anatomy through build_centerline (ALGORITHMS.md §3): the aorta of a
// patient CT (aorta_totalseg_mask.nii.gz, label 1, 1.5 mm voxels, cut by the scan at both ends) and an
// open tube mesh (capped, §3.6).
#include "medspring/builders/centerline_build.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/io/centerline_io.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/io/output_folder.hpp"
#include "medspring/io/volume_io.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

const CenterlineBuild& aorta() {
  static const CenterlineBuild c = build_centerline(
      {.source = {.mask = testing::require_data_file("aorta_totalseg_mask.nii.gz"), .label = 1}});
  return c;
}

// The mask touches the volume border only at its lowest slice (k = 0, 129 voxels: the descending aorta
// cut by the scan); the ascending aorta ends inside the volume at the aortic root. So the root R of D-6 is
// that open end and the far end is a closed tip (trimmed, D-8).
TEST(AortaCenterline, Has40AtomsAnOpenEndWhereTheScanCutsAndAClosedRoot) {
  const CenterlineBuild& c = aorta();
  EXPECT_EQ(c.skeleton.atoms.rows(), 40);
  EXPECT_EQ(c.summary.ends[0], "open");
  EXPECT_EQ(c.summary.ends[1], "closed");
  ASSERT_EQ(c.summary.open_end_sizes.size(), 1u);
  EXPECT_EQ(c.summary.open_end_sizes[0], 129);
  EXPECT_NEAR(c.summary.voxel_size_mm, 1.5, 1e-9);
  // the open end is not trimmed: the first atom lies on the cut slice (k = 0)
  const LabelVolume v = read_label_volume(testing::require_data_file("aorta_totalseg_mask.nii.gz"));
  EXPECT_NEAR(v.to_index(c.skeleton.atoms.row(0).transpose()).z(), 0.0, 0.5);
  EXPECT_EQ(c.skeleton.ends[0].trimmed, 0.0);
  // the arch and the descending aorta: up the descending aorta, over the arch, down the ascending one
  EXPECT_GT(c.summary.length_mm, 300.0);
}

TEST(AortaCenterline, EveryAtomIsInAnAortaVoxelOrWithinHalfAVoxel) {
  const CenterlineBuild& c = aorta();
  const MaskVolume mask =
      select_label(read_label_volume(testing::require_data_file("aorta_totalseg_mask.nii.gz")), 1);
  for (Index a = 0; a < c.skeleton.atoms.rows(); ++a) {
    const Vec3 p = c.skeleton.atoms.row(a).transpose();
    EXPECT_TRUE(mask_contains(mask, p) || distance_outside_mask(mask, p) <= 0.75) << "atom " << a;
  }
  EXPECT_LE(c.summary.max_distance_outside_mm, 0.75);
}

// Independent of the EDT code: brute-force distance from each atom to the nearest background voxel
// centre of the file's label volume, minus half a voxel (§3.2 inscribed radius), against the radius.
TEST(AortaCenterline, RadiiAgreeWithTheDistanceMapWithinOneVoxel) {
  const CenterlineBuild& c = aorta();
  const LabelVolume v = read_label_volume(testing::require_data_file("aorta_totalseg_mask.nii.gz"));
  const double h = 1.5;
  const Index w = 20;  // search window, voxels (30 mm: more than the aorta's radius)
  for (Index a = 0; a < c.skeleton.atoms.rows(); ++a) {
    const Vec3 p = c.skeleton.atoms.row(a).transpose();
    const Vec3 q = v.to_index(p);
    double best = std::numeric_limits<double>::infinity();
    for (Index k = static_cast<Index>(q.z()) - w; k <= static_cast<Index>(q.z()) + w; ++k)
      for (Index j = static_cast<Index>(q.y()) - w; j <= static_cast<Index>(q.y()) + w; ++j)
        for (Index i = static_cast<Index>(q.x()) - w; i <= static_cast<Index>(q.x()) + w; ++i)
          if (v.inside(i, j, k) && v.at(i, j, k) != 1)
            best = std::min(
                best,
                (v.to_world(Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k))) - p)
                    .norm());
    ASSERT_TRUE(std::isfinite(best)) << "atom " << a;
    const double r_map = std::max(best - 0.5 * h, 0.5 * h);
    EXPECT_NEAR(c.skeleton.radii[a], r_map, h) << "atom " << a;
  }
  EXPECT_LE(c.summary.max_radius_deviation_mm, h);
  // an adult aorta: radii between 5 and 20 mm away from the tapering root tip
  EXPECT_GT(c.skeleton.radii.head(37).minCoeff(), 5.0);
  EXPECT_LT(c.skeleton.radii.maxCoeff(), 20.0);
}

TEST(AortaCenterline, WritesACenterlineThatReadCenterlinesLoads) {
  const CenterlineBuild& c = aorta();
  const auto dir = testing::temp_dir("aorta-out") / "centerline";
  write_output_folder(dir, false, [&](const std::filesystem::path& d) { write_centerline_files(d, c); });
  const auto lines = read_centerlines(dir / "centerline.vtp");
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].size(), 40);
  EXPECT_LT((lines[0].points - c.skeleton.atoms).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((lines[0].radii - c.skeleton.radii).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_TRUE(std::filesystem::exists(dir / "surface.vtp"));
  EXPECT_TRUE(std::filesystem::exists(dir / "curve.vtp"));
}

// An open tube mesh (radius 3 mm, 97.5 mm long along x): both loops capped (§3.6), the centerline on
// the axis from cap to cap.
TEST(TubeMeshCenterline, RunsOnTheAxisFromCapToCap) {
  const auto file = testing::temp_dir("tube-mesh") / "tube.obj";
  write_obj(file, tube(40, 30, 2.5, 3.0));
  const CenterlineBuild c = build_centerline({.source = {.mesh = file}, .atoms = 40});
  EXPECT_EQ(c.summary.input_kind, "mesh");
  EXPECT_EQ(c.summary.ends[0], "capped");
  EXPECT_EQ(c.summary.ends[1], "capped");
  const MatX3& A = c.skeleton.atoms;
  EXPECT_LT(A.col(1).cwiseAbs().maxCoeff(), 0.25);
  EXPECT_LT(A.col(2).cwiseAbs().maxCoeff(), 0.25);
  EXPECT_NEAR(A.col(0).minCoeff(), 0.0, 0.5);
  EXPECT_NEAR(A.col(0).maxCoeff(), 97.5, 0.5);
  // the end atoms lie on the cap planes, i.e. on the object's boundary: within half a voxel of it
  EXPECT_LE(c.summary.max_distance_outside_mm, 0.5 * c.summary.voxel_size_mm);
  for (Index a = 1; a + 1 < A.rows(); ++a) EXPECT_TRUE(mask_contains(c.mask, A.row(a).transpose())) << a;
  // inscribed radius of the 30-gon of radius 3 mm is 2.98 mm
  for (Index a = 0; a < A.rows(); ++a) EXPECT_NEAR(c.skeleton.radii[a], 2.98, 0.2) << "atom " << a;
  EXPECT_LE(c.summary.max_radius_deviation_mm, c.summary.voxel_size_mm);
}

}  // namespace
}  // namespace medspring
