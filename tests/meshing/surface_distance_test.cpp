#include "medspring/meshing/surface_distance.hpp"

#include <gtest/gtest.h>

#include "medspring/geometry/phantoms.hpp"
#include "meshing_test_util.hpp"

namespace medspring {
namespace {

TEST(SurfaceDistance, IdenticalSurfacesAreZeroApart) {
  const SurfaceMesh s = icosphere(3, 10.0);
  const SurfaceDistance d = surface_distance(s, s);
  EXPECT_LE(d.hausdorff, 1e-9);
  EXPECT_LE(d.mean, 1e-9);
  EXPECT_GT(d.samples, 2 * s.num_vertices());
}

TEST(SurfaceDistance, ConcentricSpheresAreTheRadiusGapApart) {
  // Faceted spheres of radius 10 and 11 (subdivision 4: facet sagitta < 0.02 mm).
  const SurfaceDistance d = surface_distance(icosphere(4, 10.0), icosphere(4, 11.0), {.sample_spacing = 0.3});
  EXPECT_NEAR(d.hausdorff, 1.0, 0.03);
  EXPECT_NEAR(d.mean, 1.0, 0.03);
  EXPECT_NEAR(d.a_to_b_mean, d.b_to_a_mean, 0.03);
}

TEST(SurfaceDistance, OneSidedDistancesSeeAPushedVertexOnlyFromItsSide) {
  const SurfaceMesh a = icosphere(4, 10.0);  // edges ~0.65 mm
  SurfaceMesh b = a;
  b.V.row(0) *= 1.2;  // 2 mm out along the normal
  const SurfaceDistance d = surface_distance(b, a, {.sample_spacing = 0.2});
  EXPECT_NEAR(d.a_to_b_max, 2.0, 0.02);  // the tip of the spike
  EXPECT_LT(d.b_to_a_max, 0.8);          // the original surface under the spike is close to its flanks
  EXPECT_DOUBLE_EQ(d.hausdorff, d.a_to_b_max);
  EXPECT_DOUBLE_EQ(hausdorff_distance(b, a), d.hausdorff);
}

TEST(SurfaceDistance, PointDistancesAreExact) {
  const SurfaceMesh s = icosphere(3, 10.0);
  MatX3 p(3, 3);
  p << 0, 0, 0, s.V(5, 0), s.V(5, 1), s.V(5, 2), 2.0 * s.V(7, 0), 2.0 * s.V(7, 1), 2.0 * s.V(7, 2);
  const VecX d = distances_to_surface(p, s);
  EXPECT_NEAR(d[0], 10.0, 0.05);  // inscribed radius of the facets
  EXPECT_LE(d[1], 1e-12);         // a vertex of the surface
  EXPECT_NEAR(d[2], 10.0, 1e-9);  // straight out from a vertex
}

TEST(SurfaceDistance, EmptyOrBrokenMeshesAreRefused) {
  const SurfaceMesh s = icosphere(1, 1.0);
  testing::expect_invalid_input_naming([&] { surface_distance(SurfaceMesh{}, s); },
                                       {"mesh a: mesh is empty"});
  SurfaceMesh bad = s;
  bad.F(0, 0) = 999;
  testing::expect_invalid_input_naming([&] { surface_distance(s, bad); }, {"mesh b: invalid mesh", "999"});
}

}  // namespace
}  // namespace medspring
