#include "medspring/meshing/isosurface.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "medspring/io/mesh_io.hpp"
#include "medspring/io/volume_io.hpp"
#include "medspring/meshing/surface_distance.hpp"
#include "meshing_test_util.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

using testing::expect_closed_genus0;
using testing::expect_invalid_input_naming;
constexpr double kPi = std::numbers::pi;

/// A mask of the voxels whose world centres lie within `radius` of `centre` (any spacing, origin,
/// direction).
MaskVolume ball_mask(std::array<Index, 3> dims, const Vec3& spacing, const Vec3& origin,
                     const Mat3& direction, const Vec3& centre, double radius) {
  MaskVolume m;
  m.dims = dims;
  m.spacing = spacing;
  m.origin = origin;
  m.direction = direction;
  m.data.assign(m.size(), 0);
  for (Index k = 0; k < dims[2]; ++k)
    for (Index j = 0; j < dims[1]; ++j)
      for (Index i = 0; i < dims[0]; ++i)
        if ((m.to_world(Vec3(i, j, k)) - centre).norm() <= radius) m.at(i, j, k) = 1;
  return m;
}

Vec3 area_centroid(const SurfaceMesh& s) {
  Vec3 c = Vec3::Zero();
  double a = 0.0;
  for (Index f = 0; f < s.num_faces(); ++f) {
    const Vec3 p = s.V.row(s.F(f, 0)), q = s.V.row(s.F(f, 1)), r = s.V.row(s.F(f, 2));
    const double af = 0.5 * (q - p).cross(r - p).norm();
    c += af * (p + q + r) / 3.0;
    a += af;
  }
  return c / a;
}

TEST(Isosurface, SphereMaskGivesASphereOfTheAnalyticVolumeAndArea) {
  const double r = 15.0;
  const Vec3 c(23.5, 23.5, 23.5);
  const SurfaceMesh s =
      isosurface(ball_mask({48, 48, 48}, Vec3::Ones(), Vec3::Zero(), Mat3::Identity(), c, r));
  expect_closed_genus0(s);
  EXPECT_NEAR(signed_volume(s.V, s.F) / (4.0 / 3.0 * kPi * r * r * r), 1.0, 0.03);  // > 0: outward
  EXPECT_NEAR(surface_area(s.V, s.F) / (4.0 * kPi * r * r), 1.0, 0.03);
  for (Index i = 0; i < s.num_vertices(); ++i) ASSERT_NEAR((s.V.row(i).transpose() - c).norm(), r, 0.6) << i;
}

TEST(Isosurface, WorldFrameHonoursOriginAnisotropicSpacingAndARotatedMirroredDirection) {
  // Direction: a rotation of 30 degrees about z, times a mirror of the k axis (det = -1).
  Mat3 dir = Eigen::AngleAxisd(kPi / 6.0, Vec3::UnitZ()).toRotationMatrix();
  dir.col(2) *= -1.0;
  const Vec3 origin(100.0, -50.0, 20.0), spacing(0.8, 1.0, 1.25);
  const Vec3 c = origin + dir * spacing.cwiseProduct(Vec3(30.0, 24.0, 19.0));
  const double r = 12.0;
  const SurfaceMesh s = isosurface(ball_mask({60, 48, 38}, spacing, origin, dir, c, r));
  expect_closed_genus0(s);
  EXPECT_LE((area_centroid(s) - c).norm(), 0.1);
  EXPECT_NEAR(signed_volume(s.V, s.F) / (4.0 / 3.0 * kPi * r * r * r), 1.0, 0.03);
}

TEST(Isosurface, DiscreteFlyingEdgesWithoutBlurAlsoGivesTheSphere) {
  const double r = 15.0;
  const Vec3 c(23.5, 23.5, 23.5);
  const SurfaceMesh s =
      isosurface(ball_mask({48, 48, 48}, Vec3::Ones(), Vec3::Zero(), Mat3::Identity(), c, r),
                 {.blur_sigma_voxels = 0.0});
  expect_closed_genus0(s);
  EXPECT_NEAR(signed_volume(s.V, s.F) / (4.0 / 3.0 * kPi * r * r * r), 1.0, 0.04);
  EXPECT_NEAR(surface_area(s.V, s.F) / (4.0 * kPi * r * r), 1.0, 0.05);
}

TEST(Isosurface, KeepsTheLargestComponentUnlessAskedForAll) {
  MaskVolume m =
      ball_mask({64, 32, 32}, Vec3::Ones(), Vec3::Zero(), Mat3::Identity(), Vec3(16, 16, 16), 10.0);
  const MaskVolume small =
      ball_mask({64, 32, 32}, Vec3::Ones(), Vec3::Zero(), Mat3::Identity(), Vec3(46, 16, 16), 7.0);
  for (std::size_t i = 0; i < m.data.size(); ++i) m.data[i] |= small.data[i];
  const SurfaceMesh largest = isosurface(m);
  expect_closed_genus0(largest);
  const double v_large = signed_volume(largest.V, largest.F);
  EXPECT_NEAR(v_large / (4.0 / 3.0 * kPi * 1000.0), 1.0, 0.04);
  const SurfaceMesh both = isosurface(m, {.largest_component = false});
  EXPECT_EQ(check_closed_manifold(both).mesh.components, 2);
  // The blur moves the 0.5 level inward by about sigma^2 / R (1/7 voxel here): ~6 % of the volume.
  EXPECT_NEAR((signed_volume(both.V, both.F) - v_large) / (4.0 / 3.0 * kPi * 343.0), 1.0, 0.1);
}

TEST(Isosurface, ObjectTouchingTheBorderIsClosedWithCaps) {
  MaskVolume m =
      ball_mask({10, 10, 10}, Vec3::Ones(), Vec3::Zero(), Mat3::Identity(), Vec3(4.5, 4.5, 4.5), 100.0);
  const SurfaceMesh s = isosurface(m, {.blur_sigma_voxels = 0.0, .smoothing_iterations = 0});
  expect_closed_genus0(s);
  EXPECT_NEAR(signed_volume(s.V, s.F), 10.0 * 10.0 * 10.0, 20.0);  // the cube of voxel cells
}

TEST(Isosurface, BadVolumesAndSettingsAreRefused) {
  MaskVolume m = ball_mask({8, 8, 8}, Vec3::Ones(), Vec3::Zero(), Mat3::Identity(), Vec3(4, 4, 4), 2.0);
  expect_invalid_input_naming([&] { isosurface(m, {.pass_band = 0.0}); }, {"pass_band"});
  MaskVolume empty = m;
  std::fill(empty.data.begin(), empty.data.end(), std::uint8_t{0});
  expect_invalid_input_naming([&] { isosurface(empty); }, {"mask is empty"});
  MaskVolume short_data = m;
  short_data.data.pop_back();
  expect_invalid_input_naming([&] { isosurface(short_data); }, {"mask has 511 voxels", "need 512"});
  MaskVolume flat = m;
  flat.spacing[1] = 0.0;
  expect_invalid_input_naming([&] { isosurface(flat); }, {"spacing[1]"});
}

TEST(Isosurface, AortaMaskGivesTheAortaSurfaceInScannerCoordinates) {
  const LabelVolume labels = read_label_volume(testing::require_data_file("aorta_totalseg_mask.nii.gz"));
  const MaskVolume aorta = select_label(labels, 1);
  const SurfaceMesh s = isosurface(aorta);
  expect_closed_genus0(s);
  // 72,810 voxels of 1.5^3 mm^3 = 245.7 cm^3 (data README); blur and smoothing shave a little.
  EXPECT_NEAR(signed_volume(s.V, s.F) / (72810.0 * 3.375), 1.0, 0.03);
  // The reference surface was made from the same mask with the NIfTI affine (data README §2).
  const SurfaceMesh reference = read_mesh(testing::require_data_file("aorta_totalseg_ct.obj"));
  const SurfaceDistance d = surface_distance(s, reference);
  std::cout << "aorta isosurface: " << s.num_vertices() << " vertices, volume " << signed_volume(s.V, s.F)
            << " mm^3, Hausdorff to the OBJ " << d.hausdorff << " mm, mean " << d.mean << " mm\n";
  EXPECT_LE(d.hausdorff, 2.0);
  EXPECT_LE(d.mean, 0.3);
}

}  // namespace
}  // namespace medspring
