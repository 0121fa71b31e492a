#include "medspring/skeleton/phantom_volumes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace medspring {
namespace {

constexpr double kPi = std::numbers::pi;

double voxel_volume(const MaskVolume& m) {
  double n = 0;
  for (auto v : m.data) n += v;
  return n * m.spacing.prod();
}

TEST(PhantomVolumes, QuarterTorusVolumeMatchesPappusAndIsCutByTheBorder) {
  const QuarterTorusShape s;
  const MaskVolume m = quarter_torus_volume(s);
  const double exact = kPi * s.r * s.r * (0.5 * kPi * s.R);  // Pappus
  EXPECT_NEAR(voxel_volume(m) / exact, 1.0, 0.01);
  // both ends touch the border planes x = 0 and y = 0; nothing touches z or the far sides
  EXPECT_EQ(m.at(0, 80, m.dims[2] / 2), 1);  // (0, 40, 0)
  EXPECT_EQ(m.at(80, 0, m.dims[2] / 2), 1);  // (40, 0, 0)
  for (Index j = 0; j < m.dims[1]; ++j)
    for (Index i = 0; i < m.dims[0]; ++i) {
      EXPECT_EQ(m.at(i, j, 0), 0);
      EXPECT_EQ(m.at(i, j, m.dims[2] - 1), 0);
    }
  EXPECT_NEAR(m.to_world(Vec3(0, 0, m.dims[2] / 2)).z(), 0.0, 1e-15);
}

TEST(PhantomVolumes, EllipsoidVolumeAndTips) {
  const EllipsoidShape s;
  const MaskVolume m = ellipsoid_volume(s);
  const double exact = 4.0 / 3.0 * kPi * s.semi_axes.prod();
  EXPECT_NEAR(voxel_volume(m) / exact, 1.0, 0.01);
  const Vec3 tip = m.to_index(Vec3(40, 0, 0));
  EXPECT_EQ(m.at(static_cast<Index>(tip.x()), static_cast<Index>(tip.y()), static_cast<Index>(tip.z())), 1);
  EXPECT_EQ(m.at(static_cast<Index>(tip.x()) + 1, static_cast<Index>(tip.y()), static_cast<Index>(tip.z())),
            0);
}

TEST(PhantomVolumes, StraightTubeVolumeMatchesCylinderWithCaps) {
  MatX3 seg(2, 3);
  seg << 5.0, 10.0, 10.0, 35.0, 10.0, 10.0;
  const MaskVolume m = tube_volume(seg, 4.0, {81, 41, 41}, Vec3::Constant(0.5), Vec3::Zero());
  const double exact = kPi * 16.0 * 30.0 + 4.0 / 3.0 * kPi * 64.0;  // cylinder + two half-balls
  // a disk of radius 8 voxels holds 197 lattice points against pi 8^2 = 201.1 (Gauss circle error)
  EXPECT_NEAR(voxel_volume(m) / exact, 1.0, 0.03);
}

}  // namespace
}  // namespace medspring
