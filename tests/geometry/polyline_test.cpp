#include "medspring/geometry/polyline.hpp"

#include <gtest/gtest.h>

#include "medspring/core/error.hpp"

namespace medspring {
namespace {

TEST(Polyline, DeduplicateAndResample) {
  Centerline c;
  c.points.resize(5, 3);
  c.points << 0, 0, 0, 1e-6, 0, 0, 1, 0, 0, 2, 0, 0, 4, 0, 0;
  c.radii.resize(5);
  c.radii << 1, 1, 2, 3, 5;
  const Centerline d = deduplicate(c, 1e-3);
  EXPECT_EQ(d.size(), 4);
  const Centerline r = resample(d, 5);
  ASSERT_EQ(r.size(), 5);
  for (Index k = 0; k < 5; ++k) {
    EXPECT_NEAR(r.points(k, 0), k, 1e-12);
    EXPECT_NEAR(r.radii[k], 1.0 + k, 1e-12);
  }
  EXPECT_NEAR(r.length(), 4.0, 1e-12);
  EXPECT_THROW(resample(d, 1), InvalidInput);
}

}  // namespace
}  // namespace medspring
