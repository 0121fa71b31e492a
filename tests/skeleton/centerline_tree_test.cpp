// The tree skeleton of a mask (issue 17, docs/vessels.md "Trees from a mesh or a segmentation"): a Y finds
// its two outlets sharing the trunk and one junction at the fork, a straight tube is one branch, the real
// aorta mask is one arch + descending tube, and bad masks are refused.
#include "medspring/skeleton/centerline_tree.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>

#include "medspring/io/volume_io.hpp"
#include "medspring/models/smrm_tree.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

MaskVolume mask_of(const Vec3& lo, const Vec3& hi, double h, const std::function<bool(const Vec3&)>& inside) {
  MaskVolume m;
  m.spacing = Vec3::Constant(h);
  m.origin = lo;
  for (int a = 0; a < 3; ++a) m.dims[a] = static_cast<Index>(std::ceil((hi[a] - lo[a]) / h)) + 1;
  m.data.assign(m.size(), 0);
  for (Index k = 0; k < m.dims[2]; ++k)
    for (Index j = 0; j < m.dims[1]; ++j)
      for (Index i = 0; i < m.dims[0]; ++i) m.at(i, j, k) = inside(m.to_world(Vec3(i, j, k))) ? 1 : 0;
  return m;
}

// A Y: trunk A = (0,0,0) -> J = (30,0,0) of radius 4 mm, two branches J -> B1, B2 of radius 3 mm, cut flat
// at their ends (cylinders, not capsules: the ends are where a scan would cut them).
const Vec3 kA(0, 0, 0), kJ(30, 0, 0), kB1(55, 18, 4), kB2(53, -17, -3);

bool in_cylinder(const Vec3& p, const Vec3& a, const Vec3& b, double r, bool cap_a, bool cap_b) {
  const Vec3 ab = b - a;
  const double t = (p - a).dot(ab) / ab.squaredNorm();
  if ((t < 0 && cap_a) || (t > 1 && cap_b)) return false;
  return segment_distance(p, a, b) <= r;
}

bool inside_y(const Vec3& p) {
  return in_cylinder(p, kA, kJ, 4.0, true, false) || in_cylinder(p, kJ, kB1, 3.0, false, true) ||
         in_cylinder(p, kJ, kB2, 3.0, false, true);
}

// Distance from p to the nearest object voxel centre (searched 2 voxels about p).
double distance_to_object_voxel(const MaskVolume& m, const Vec3& p) {
  const Vec3 c = m.to_index(p);
  double best = 1e300;
  for (Index k = static_cast<Index>(std::lround(c.z())) - 2; k <= static_cast<Index>(std::lround(c.z())) + 2;
       ++k)
    for (Index j = static_cast<Index>(std::lround(c.y())) - 2;
         j <= static_cast<Index>(std::lround(c.y())) + 2; ++j)
      for (Index i = static_cast<Index>(std::lround(c.x())) - 2;
           i <= static_cast<Index>(std::lround(c.x())) + 2; ++i)
        if (i >= 0 && j >= 0 && k >= 0 && i < m.dims[0] && j < m.dims[1] && k < m.dims[2] && m.at(i, j, k))
          best = std::min(best, (m.to_world(Vec3(i, j, k)) - p).norm());
  return best;
}

double axis_distance(const Vec3& p) {
  return std::min({segment_distance(p, kA, kJ), segment_distance(p, kJ, kB1), segment_distance(p, kJ, kB2)});
}

TEST(CenterlineTree, YMaskGivesThreeBranchesSharingTheTrunkAndOneJunctionAtTheFork) {
  const double h = 0.5;
  const MaskVolume mask = mask_of(Vec3(-3, -24, -10), Vec3(60, 24, 10), h, inside_y);
  const TreeSkeleton t = extract_centerline_tree(mask);
  for (const auto& n : t.notes) std::cout << "  " << n << "\n";
  ASSERT_EQ(t.lines.size(), 2u);
  EXPECT_EQ(t.components, 1);
  const CenterlineTree ct = merge_centerlines(t.lines);
  ASSERT_EQ(ct.branches.size(), 3u);
  EXPECT_EQ(ct.junctions(), 1);
  EXPECT_EQ(ct.branches[1].parent, 0);
  EXPECT_EQ(ct.branches[2].parent, 0);
  // the root is the widest end (the trunk's cap at x = 0); every end reaches its cap (extend_ends: straight
  // on from the cut a radius short of the tip, with the end radius) within a voxel, on the axis
  const Vec3 root = ct.branches[0].line.points.row(0).transpose();
  std::cout << "  root " << root.transpose() << "\n";
  EXPECT_NEAR(root.x(), 0.0, h) << root.transpose();
  EXPECT_LT(root.tail<2>().norm(), h) << root.transpose();
  for (std::size_t b = 1; b < ct.branches.size(); ++b) {
    const Centerline& c = ct.branches[b].line;
    const Vec3 tip = c.points.row(c.size() - 1).transpose();
    const Vec3 cap = (tip - kB1).norm() < (tip - kB2).norm() ? kB1 : kB2;
    const double along = (cap - tip).dot((cap - kJ).normalized());
    std::cout << "  leaf " << b << " end " << along << " mm short of its cap, " << (tip - cap).norm()
              << " mm from the cap's centre, radius " << c.radii[c.size() - 1] << " mm\n";
    EXPECT_NEAR(along, 0.0, h);
    EXPECT_LT((tip - cap).norm(), 1.5 * h);
  }
  EXPECT_GT(t.extended_root_mm, 2.0);  // the cut was about a radius (4 mm) short of the tip
  EXPECT_GT(t.extended_leaf_min_mm, 2.0);
  // the junction: where the two outlets' paths meet, near the fork J
  const Centerline& trunk = ct.branches[0].line;
  const Vec3 junction = trunk.points.row(trunk.size() - 1).transpose();
  std::cout << "  junction " << junction.transpose() << ", " << (junction - kJ).norm()
            << " mm from the fork\n";
  EXPECT_LT((junction - kJ).norm(), 2.0 * h + 0.5) << junction.transpose();
  // the trunk is one branch from the root to the fork: its length is the trunk's, not a side-by-side run
  EXPECT_GT(trunk.length(), 20.0);
  // every point of the skeleton lies on the Y's axis within a voxel, and its radius is the tube's within
  // a voxel (away from the fork, where the inscribed ball grows)
  double worst_axis = 0.0, worst_r = 0.0;
  for (const auto& b : ct.branches)
    for (Index k = 0; k < b.line.size(); ++k) {
      const Vec3 p = b.line.points.row(k).transpose();
      worst_axis = std::max(worst_axis, axis_distance(p));
      const double r_true = (p.x() < kJ.x() - 5.0) ? 4.0 : (p.x() > kJ.x() + 8.0 ? 3.0 : -1.0);
      if (r_true > 0) worst_r = std::max(worst_r, std::abs(b.line.radii[k] - r_true));
    }
  std::cout << "  skeleton to the axis: max " << worst_axis << " mm; radius error max " << worst_r << " mm\n";
  EXPECT_LE(worst_axis, h + 0.01);
  EXPECT_LT(worst_r, h);  // the radius is DFB - h/2 (§3.5.5): within half a voxel either way, and a voxel
                          // at worst on a tube that crosses the grid obliquely
}

TEST(CenterlineTree, StraightTubeIsOneBranchWithoutJunctions) {
  const Vec3 a(0, 0, 0), b(40, 10, 5);
  const MaskVolume mask = mask_of(Vec3(-6, -6, -6), Vec3(46, 16, 11), 0.5,
                                  [&](const Vec3& p) { return in_cylinder(p, a, b, 3.5, true, true); });
  const TreeSkeleton t = extract_centerline_tree(mask);
  ASSERT_EQ(t.lines.size(), 1u);
  const CenterlineTree ct = merge_centerlines(t.lines);
  EXPECT_EQ(ct.branches.size(), 1u);
  EXPECT_EQ(ct.junctions(), 0);
  for (Index k = 0; k < ct.branches[0].line.size(); ++k) {
    const Vec3 p = ct.branches[0].line.points.row(k).transpose();
    EXPECT_LT(segment_distance(p, a, b), 0.5) << p.transpose();
    EXPECT_NEAR(ct.branches[0].line.radii[k], 3.5, 0.5) << p.transpose();
  }
  // both ends straight on to the flat caps (extend_ends), within a voxel
  const Centerline& c = ct.branches[0].line;
  const Vec3 e0 = c.points.row(0).transpose(), e1 = c.points.row(c.size() - 1).transpose();
  const Vec3 ab = (b - a).normalized();
  const double l0 = std::min((e0 - a).dot(ab), (e1 - a).dot(ab)),
               l1 = std::max((e0 - a).dot(ab), (e1 - a).dot(ab));
  std::cout << "  straight tube ends " << l0 << " and " << (b - a).norm() - l1
            << " mm inside the caps, length " << c.length() << " of " << (b - a).norm() << " mm\n";
  EXPECT_NEAR(l0, 0.0, 0.5);
  EXPECT_NEAR(l1, (b - a).norm(), 0.5);
}

// The TotalSegmentator aorta (../shared/data/README.md: label 1, 1.5 mm voxels, cut by the scan at both
// ends): the mask holds the arch and the descending aorta without the arch's branch stubs, so the tree
// skeleton is one branch over the arch, no junction.
TEST(CenterlineTree, RealAortaMaskIsOneArchAndDescendingTube) {
  const auto file = testing::require_data_file("aorta_totalseg_mask.nii.gz");
  const MaskVolume mask = select_label(read_label_volume(file), 1);
  const TreeSkeleton t = extract_centerline_tree(mask);
  for (const auto& n : t.notes) std::cout << "  " << n << "\n";
  const CenterlineTree ct = merge_centerlines(t.lines);
  std::cout << "  aorta mask: " << t.lines.size() << " endpoint(s), " << ct.branches.size() << " branch(es), "
            << ct.junctions() << " junction(s), length " << ct.branches[0].line.length() << " mm, radii "
            << ct.branches[0].line.radii.minCoeff() << ".." << ct.branches[0].line.radii.maxCoeff()
            << " mm\n";
  EXPECT_EQ(t.lines.size(), 1u);
  EXPECT_EQ(ct.branches.size(), 1u);
  EXPECT_EQ(ct.junctions(), 0);
  EXPECT_GT(ct.branches[0].line.length(), 300.0);  // up the descending aorta, over the arch, down
  // every point inside the aorta: in the cube of an aorta voxel (within sqrt(3)/2 voxel of its centre)
  for (Index k = 0; k < ct.branches[0].line.size(); ++k) {
    const Vec3 p = ct.branches[0].line.points.row(k).transpose();
    EXPECT_LE(distance_to_object_voxel(mask, p), 0.87 * mask.spacing.maxCoeff()) << p.transpose();
  }
}

TEST(CenterlineTree, BadMasksAreRefused) {
  MaskVolume empty = mask_of(Vec3(0, 0, 0), Vec3(10, 10, 10), 1.0, [](const Vec3&) { return false; });
  EXPECT_THROW(extract_centerline_tree(empty), InvalidInput);
  // a ball: its skeleton is only a spur, not a vessel
  const MaskVolume ball =
      mask_of(Vec3(-8, -8, -8), Vec3(8, 8, 8), 0.5, [](const Vec3& p) { return p.norm() <= 6.0; });
  try {
    extract_centerline_tree(ball);
    ADD_FAILURE() << "a ball was accepted as a vessel";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("spur"), std::string::npos) << e.what();
  }
  TreeSkeletonSettings bad;
  bad.ridge_power = -1;
  EXPECT_THROW(extract_centerline_tree(ball, bad), InvalidInput);
}

}  // namespace
}  // namespace medspring
