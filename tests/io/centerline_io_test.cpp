#include "medspring/io/centerline_io.hpp"

#include <gtest/gtest.h>

#include "io_test_util.hpp"
#include "medspring/io/mesh_io.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;
using testing::expect_error_naming;

TEST(CenterlineIo, VmrAortaHasFourLinesWithTheDocumentedCountsAndRadii) {
  const auto path = testing::require_data_file("vmr-0159-aorta-centerline.vtp");
  const auto lines = read_centerlines(path, LengthUnit::Centimetre);
  ASSERT_EQ(lines.size(), 4u);
  const Index counts[4] = {457, 401, 581, 431};
  const double lengths_cm[4] = {14.3, 15.1, 34.5, 17.0};  // README, rounded to 0.1 cm
  double rmin = 1e9, rmax = 0;
  for (std::size_t l = 0; l < 4; ++l) {
    EXPECT_EQ(lines[l].size(), counts[l]);
    EXPECT_EQ(lines[l].radii.size(), counts[l]);
    EXPECT_EQ(lines[l].name, "line " + std::to_string(l));
    EXPECT_NEAR(lines[l].length(), 10.0 * lengths_cm[l], 0.5) << "line " << l;  // mm
    rmin = std::min(rmin, lines[l].radii.minCoeff());
    rmax = std::max(rmax, lines[l].radii.maxCoeff());
    EXPECT_NEAR(lines[l].radii(0), 13.74, 0.005);  // inlet radius 1.374 cm
  }
  // README: radius 0.261-1.483 cm (3 decimals) -> 2.61-14.83 mm
  EXPECT_NEAR(rmin, 2.61, 0.005);
  EXPECT_NEAR(rmax, 14.83, 0.005);
  // the branches repeat their shared trunk: same first points
  EXPECT_EQ(lines[0].points.row(10), lines[1].points.row(10));
}

TEST(CenterlineIo, UnitScalesPointsAndRadiiAlike) {
  const auto path = testing::require_data_file("vmr-0159-aorta-centerline.vtp");
  const auto cm = read_centerlines(path, LengthUnit::Centimetre);
  const auto mm = read_centerlines(path, LengthUnit::Millimetre);
  ASSERT_EQ(cm.size(), mm.size());
  EXPECT_DOUBLE_EQ(cm[2].points(7, 1), 10.0 * mm[2].points(7, 1));
  EXPECT_DOUBLE_EQ(cm[2].radii(7), 10.0 * mm[2].radii(7));
}

TEST(CenterlineIo, WriteThenReadRoundTripsExactly) {
  Centerline a;
  a.points.resize(3, 3);
  a.points << 0, 0, 0, 1.25, 0, 0, 2.5, 0.5, 0;
  a.radii = Vec3(3.0, 2.5, 2.0);
  Centerline b;
  b.points.resize(2, 3);
  b.points << 0, 0, 0, 0, 0, -7;
  b.radii.resize(2);
  b.radii << 1.0, 0.75;
  const fs::path file = testing::temp_dir("cl-rt") / "lines.vtp";
  write_centerlines(file, {a, b}, "Radius");
  const auto back = read_centerlines(file, LengthUnit::Millimetre, "Radius");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].points, a.points);
  EXPECT_EQ(back[0].radii, a.radii);
  EXPECT_EQ(back[1].points, b.points);
  EXPECT_EQ(back[1].radii, b.radii);
}

TEST(CenterlineIo, MissingRadiusArrayNamesTheArraysThatExist) {
  const auto path = testing::require_data_file("vmr-0159-aorta-centerline.vtp");
  expect_error_naming([&] { read_centerlines(path, LengthUnit::Centimetre, "Radius"); },
                      "no point array 'Radius' (point arrays: 'MaximumInscribedSphereRadius')");
}

TEST(CenterlineIo, NonPositiveRadiusNamesLineAndPoint) {
  Centerline a;
  a.points = MatX3::Zero(4, 3);
  for (Index i = 0; i < 4; ++i) a.points(i, 0) = i;
  a.radii = VecX::Ones(4);
  Centerline b = a;
  b.radii(2) = 0.0;
  const fs::path file = testing::temp_dir("cl-zero") / "zero.vtp";
  write_centerlines(file, {a, b});
  expect_error_naming([&] { read_centerlines(file); }, "zero.vtp: line 1, point 2 (point id 6): radius");
}

TEST(CenterlineIo, FileWithoutLinesIsRejected) {
  const fs::path file = testing::temp_dir("cl-nolines") / "surface.vtp";
  SurfaceMesh m;
  m.V.resize(3, 3);
  m.V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  m.F.resize(1, 3);
  m.F << 0, 1, 2;
  write_vtp(file, m);
  expect_error_naming([&] { read_centerlines(file); }, "surface.vtp: no line cells");
}

TEST(CenterlineIo, WrongExtensionAndMissingFileAreNamed) {
  const fs::path dir = testing::temp_dir("cl-bad");
  expect_error_naming([&] { read_centerlines(dir / "none.vtp"); }, "none.vtp: no such file");
  testing::write_text(dir / "lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n");
  expect_error_naming(
      [&] { read_centerlines(dir / "lines.obj"); },
      "lines.obj: unknown centerline file extension '.obj' (centerlines are read from .vtp or .vtk");
  expect_error_naming([&] { read_centerlines(dir / "lines.csv"); },
                      "lines.csv: unknown centerline file extension");
}

}  // namespace
}  // namespace medspring
