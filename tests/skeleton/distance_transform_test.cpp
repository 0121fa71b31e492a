#include "medspring/skeleton/distance_transform.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "medspring/core/error.hpp"

namespace medspring {
namespace {

MaskVolume random_mask(std::array<Index, 3> dims, const Vec3& spacing, double fill, unsigned seed) {
  MaskVolume m;
  m.dims = dims;
  m.spacing = spacing;
  m.origin = Vec3(1.0, -2.0, 3.0);
  m.data.resize(m.size());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (auto& v : m.data) v = u(rng) < fill ? 1 : 0;
  return m;
}

/// Brute force: squared physical distance from voxel v to the nearest background voxel centre.
double brute_force_squared(const MaskVolume& m, Index i, Index j, Index k) {
  double best = std::numeric_limits<double>::infinity();
  for (Index c = 0; c < m.dims[2]; ++c)
    for (Index b = 0; b < m.dims[1]; ++b)
      for (Index a = 0; a < m.dims[0]; ++a) {
        if (m.at(a, b, c)) continue;
        const double dx = m.spacing[0] * (a - i), dy = m.spacing[1] * (b - j), dz = m.spacing[2] * (c - k);
        best = std::min(best, dx * dx + dy * dy + dz * dz);
      }
  return best;
}

TEST(DistanceTransform, AnisotropicEdtEqualsBruteForceOnRandomVolume) {
  // object fill 0.9 so that distances of several voxels occur
  const MaskVolume m = random_mask({13, 11, 9}, Vec3(0.7, 1.1, 1.6), 0.9, 7);
  const DistanceField df = distance_from_boundary(m);
  EXPECT_FALSE(df.isotropic);
  EXPECT_TRUE(df.squared_edt.data.empty());
  double max_seen = 0.0;
  for (Index k = 0; k < m.dims[2]; ++k)
    for (Index j = 0; j < m.dims[1]; ++j)
      for (Index i = 0; i < m.dims[0]; ++i) {
        const double expected = m.at(i, j, k) ? std::sqrt(brute_force_squared(m, i, j, k)) : 0.0;
        // identical up to floating-point rounding of the sums (1e-12 relative)
        EXPECT_NEAR(df.dfb.at(i, j, k), expected, 1e-12 * std::max(1.0, expected))
            << i << "," << j << "," << k;
        max_seen = std::max(max_seen, expected);
      }
  EXPECT_GT(max_seen, 2.0);  // the volume exercises distances beyond the nearest neighbours
}

TEST(DistanceTransform, IsotropicSquaredEdtIsExactIntegerBruteForce) {
  const MaskVolume m = random_mask({12, 10, 11}, Vec3::Constant(0.5), 0.93, 11);
  const DistanceField df = distance_from_boundary(m);
  ASSERT_TRUE(df.isotropic);
  ASSERT_EQ(df.squared_edt.data.size(), m.size());
  for (Index k = 0; k < m.dims[2]; ++k)
    for (Index j = 0; j < m.dims[1]; ++j)
      for (Index i = 0; i < m.dims[0]; ++i) {
        const double phys = m.at(i, j, k) ? brute_force_squared(m, i, j, k) : 0.0;
        const auto expected = static_cast<std::int32_t>(std::lround(phys / 0.25));  // voxel units
        EXPECT_EQ(df.squared_edt.at(i, j, k), expected) << i << "," << j << "," << k;
        EXPECT_EQ(df.dfb.at(i, j, k), 0.5 * std::sqrt(static_cast<double>(expected)));
      }
}

TEST(DistanceTransform, SingleBackgroundVoxelGivesEuclideanDistanceEverywhere) {
  MaskVolume m;
  m.dims = {7, 6, 5};
  m.spacing = Vec3(0.5, 1.0, 2.0);
  m.data.assign(m.size(), 1);
  m.at(2, 3, 1) = 0;
  const DistanceField df = distance_from_boundary(m);
  for (Index k = 0; k < 5; ++k)
    for (Index j = 0; j < 6; ++j)
      for (Index i = 0; i < 7; ++i) {
        const double d = Vec3(0.5 * (i - 2), 1.0 * (j - 3), 2.0 * (k - 1)).norm();
        EXPECT_NEAR(df.dfb.at(i, j, k), d, 1e-14);
      }
}

TEST(DistanceTransform, VolumeWithoutBackgroundIsInfinite) {
  MaskVolume m;
  m.dims = {3, 4, 2};
  m.data.assign(m.size(), 1);
  const DistanceField df = distance_from_boundary(m);
  for (double d : df.dfb.data) EXPECT_EQ(d, std::numeric_limits<double>::infinity());
}

TEST(DistanceTransform, RejectsNonPositiveSpacingAndWrongDataSize) {
  MaskVolume m;
  m.dims = {3, 3, 3};
  m.data.assign(m.size(), 1);
  m.spacing = Vec3(1.0, 0.0, 1.0);
  EXPECT_THROW(distance_from_boundary(m), InvalidInput);
  m.spacing = Vec3::Ones();
  m.data.resize(26);
  EXPECT_THROW(distance_from_boundary(m), InvalidInput);
}

TEST(Trilinear, ReproducesLinearFieldsAndClampsOutside) {
  ScalarVolume v;
  v.dims = {4, 5, 6};
  v.data.resize(v.size());
  auto f = [](double x, double y, double z) { return 1.5 + 2.0 * x - 0.5 * y + 0.25 * z; };
  for (Index k = 0; k < 6; ++k)
    for (Index j = 0; j < 5; ++j)
      for (Index i = 0; i < 4; ++i) v.at(i, j, k) = f(i, j, k);
  EXPECT_NEAR(trilinear(v, Vec3(1.3, 2.7, 4.1)), f(1.3, 2.7, 4.1), 1e-13);
  EXPECT_NEAR(trilinear(v, Vec3(3.0, 4.0, 5.0)), f(3, 4, 5), 1e-13);   // last voxel
  EXPECT_NEAR(trilinear(v, Vec3(-2.0, 1.0, 9.0)), f(0, 1, 5), 1e-13);  // clamped
  v.spacing = Vec3(2.0, 1.0, 0.5);
  v.origin = Vec3(10, 0, 0);
  EXPECT_NEAR(sample_trilinear(v, Vec3(12.0, 1.5, 1.25)), f(1.0, 1.5, 2.5), 1e-13);
}

}  // namespace
}  // namespace medspring
