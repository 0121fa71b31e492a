// The visibility filter of ALGORITHMS.md D-9 (§4.2) on the real kidney (kidney_left_hubmap_vhm.obj): at
// the hilum the nearest atom across the renal sinus gives spokes outside the organ; with the filter (on by
// default when the organ's voxels are known) no spoke leaves it. Checked independently of the filter:
// every spoke sampled every quarter voxel against the mask.
#include <gtest/gtest.h>

#include "medspring/builders/kidney_build.hpp"
#include "medspring/builders/organ_source.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

const KidneyBuild& real_kidney() {
  static const KidneyBuild k =
      build_kidney_model({.source = {.mesh = testing::require_data_file("kidney_left_hubmap_vhm.obj"),
                                     .unit = LengthUnit::Metre}});
  return k;
}

/// The largest distance outside the mask (mm) of any point of the spoke, sampled every h / 4.
double spoke_outside(const MaskVolume& mask, const Vec3& p, const Vec3& q) {
  const double h = 0.25 * mask.spacing.minCoeff();
  const Index n = std::max<Index>(1, static_cast<Index>(std::ceil((q - p).norm() / h)));
  double worst = 0;
  for (Index s = 0; s <= n; ++s) {
    const Vec3 x = p + (q - p) * (static_cast<double>(s) / static_cast<double>(n));
    if (!mask_contains(mask, x)) worst = std::max(worst, distance_outside_mask(mask, x, 6));
  }
  return worst;
}

struct Leaving {
  Index count = 0;
  double worst = 0;
};

Leaving spokes_leaving(const HybridKidney& k, const MatX3& atoms, const MaskVolume& mask, double limit) {
  Leaving out;
  const MatX2i& sp = k.spokes();
  for (Index r = 0; r < sp.rows(); ++r) {
    const double d = spoke_outside(mask, k.rest_surface().row(sp(r, 0)).transpose(), atoms.row(sp(r, 1)).transpose());
    out.worst = std::max(out.worst, d);
    if (d > limit) ++out.count;
  }
  return out;
}

TEST(SpokeVisibility, NoSpokeOfTheRealKidneyLeavesTheOrgan) {
  const KidneyBuild& k = real_kidney();
  const double voxel = k.mask.spacing.maxCoeff();
  // The filter rejects a sample more than one voxel outside; between its samples (one voxel apart) a
  // spoke may stray half a voxel further: 2 voxels is "outside the organ".
  const double limit = 2.0 * voxel;
  const HybridStats st = k.model->stats();
  ASSERT_TRUE(st.visibility_filtered);
  EXPECT_GT(st.visibility.rejected, 0) << "the hilum's candidates across the renal sinus were rejected";
  const Leaving with = spokes_leaving(*k.model, k.skeleton.atoms, k.mask, limit);
  EXPECT_EQ(with.count, 0) << "worst " << with.worst << " mm outside (voxel " << voxel << " mm)";
  EXPECT_EQ(st.surface_nodes_without_spoke, 0);
  EXPECT_GE(st.min_spokes_per_atom, 1);

  // Without the filter (the union rule alone), the nearest atom across the renal sinus gives spokes that
  // leave the organ: the test above can fail.
  HybridSettings off = k.model->settings();
  off.visibility_filter = false;
  const HybridKidney plain(SurfaceMesh{k.model->rest_surface(), k.model->faces()}, k.skeleton.atoms, off, "kidney",
                           &k.mask);
  EXPECT_FALSE(plain.stats().visibility_filtered);
  const Leaving without = spokes_leaving(plain, k.skeleton.atoms, k.mask, limit);
  EXPECT_GT(without.count, 0) << "worst " << without.worst << " mm outside";
  EXPECT_GT(without.worst, 3.0 * voxel);
  std::printf("spokes leaving the organ (> %.2f mm): %ld without the filter (worst %.1f mm), %ld with it "
              "(worst %.2f mm); %ld candidates rejected, %ld fallbacks\n",
              limit, static_cast<long>(without.count), without.worst, static_cast<long>(with.count), with.worst,
              static_cast<long>(st.visibility.rejected), static_cast<long>(st.visibility.fallbacks));
}

TEST(SpokeVisibility, WithoutAMaskTheUnionRuleIsUnchanged) {
  // The phantom has no mask: the filter does not run and the spokes are the union rule's.
  const HybridKidney k = hybrid_kidney_phantom();
  EXPECT_FALSE(k.stats().visibility_filtered);
  EXPECT_EQ(k.stats().visibility.rejected, 0);
  const MatX2i plain = union_spokes(k.rest_surface(), k.model().x0.bottomRows(k.num_atoms()), 8);
  ASSERT_EQ(plain.rows(), k.spokes().rows());
  EXPECT_TRUE((plain.array() == k.spokes().array()).all());
}

TEST(SpokeVisibility, SegmentTestRejectsASegmentThroughACavity) {
  // A 20 x 20 x 20 voxel block (1 mm) with a 6-voxel-wide slot cut through its middle along y.
  MaskVolume m;
  m.dims = {20, 20, 20};
  m.data.assign(m.size(), 1);
  for (Index k = 0; k < 20; ++k)
    for (Index j = 0; j < 20; ++j)
      for (Index i = 7; i < 13; ++i) m.at(i, j, k) = 0;
  EXPECT_TRUE(segment_inside_mask(m, Vec3(1, 5, 5), Vec3(5, 15, 15)));    // stays on one side
  EXPECT_FALSE(segment_inside_mask(m, Vec3(2, 10, 10), Vec3(17, 10, 10)));  // crosses the slot
  EXPECT_TRUE(segment_inside_mask(m, Vec3(5, 10, 10), Vec3(7.4, 10, 10)));  // less than a voxel into it
}

}  // namespace
}  // namespace medspring
