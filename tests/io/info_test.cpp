#include "medspring/io/info.hpp"

#include <gtest/gtest.h>

#include "io_test_util.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/io/mesh_io.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;

/// Brackets and braces balance outside strings, and the text is one object.
bool json_balanced(const std::string& s) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
      continue;
    }
    if (c == '"')
      in_string = true;
    else if (c == '{' || c == '[')
      ++depth;
    else if (c == '}' || c == ']')
      --depth;
    if (depth < 0) return false;
  }
  return depth == 0 && !in_string && s.front() == '{' && s.back() == '}';
}

TEST(Info, KidneyMeshSummaryHasCountsValidityVolumeAndUnit) {
  const FileInfo info =
      describe_file(testing::require_data_file("kidney_left_hubmap_vhm.obj"), {.unit = LengthUnit::Metre});
  EXPECT_EQ(info.kind, "mesh");
  EXPECT_EQ(info.format, "OBJ");
  EXPECT_EQ(info.unit, "m");
  ASSERT_TRUE(info.mesh.has_value());
  EXPECT_FALSE(info.volume.has_value());
  EXPECT_EQ(info.mesh->report.vertices, 5002);
  EXPECT_EQ(info.mesh->report.edges, 15000);  // closed triangle mesh: E = 3F/2
  EXPECT_EQ(info.mesh->genus(), 0);
  EXPECT_NEAR(info.mesh->volume / 1000.0, 198.0, 0.5);  // cm^3
  EXPECT_NEAR(info.mesh->area / 100.0, 202.0, 1.0);     // README: 0.0202 m^2 = 202 cm^2
  EXPECT_NEAR(info.mesh->edge_mean, 2.3, 0.05);         // README: mean edge 2.3 mm
  EXPECT_NEAR(info.mesh->bounds.size()(1), 106.7, 0.05);
  const std::string text = info.text();
  EXPECT_NE(text.find("5002 vertices"), std::string::npos) << text;
  EXPECT_NE(text.find("genus 0"), std::string::npos) << text;
  EXPECT_LE(std::count(text.begin(), text.end(), '\n'), 24);
  const std::string json = info.to_json();
  EXPECT_TRUE(json_balanced(json)) << json;
  EXPECT_NE(json.find("\"genus\": 0"), std::string::npos) << json;
  EXPECT_NE(json.find("\"closed\": true"), std::string::npos) << json;
}

TEST(Info, MaskSummaryCountsVoxelsPerLabel) {
  const FileInfo info = describe_file(testing::require_data_file("aorta_totalseg_mask.nii.gz"));
  EXPECT_EQ(info.kind, "volume");
  EXPECT_EQ(info.format, "NIfTI");
  ASSERT_TRUE(info.volume.has_value());
  const VolumeInfo& v = *info.volume;
  ASSERT_EQ(v.label_counts.size(), 2u);
  EXPECT_EQ(v.label_counts[0], (std::pair<std::int32_t, std::int64_t>{0, 120 * 126 * 164 - 72810}));
  EXPECT_EQ(v.label_counts[1], (std::pair<std::int32_t, std::int64_t>{1, 72810}));
  EXPECT_EQ(v.foreground_voxels, 72810);
  EXPECT_NEAR(v.foreground_volume, 72810 * 3.375, 1e-6);  // README: 246 cm^3
  EXPECT_NEAR(v.foreground_bounds.min(0), -44.6, 1.5);
  EXPECT_NEAR(v.foreground_bounds.max(2), 766.4, 1.5);
  const std::string json = info.to_json();
  EXPECT_TRUE(json_balanced(json)) << json;
  EXPECT_NE(json.find("\"label_counts\": {\"0\": 2406870, \"1\": 72810}"), std::string::npos) << json;
}

TEST(Info, CenterlineSummaryHasLinesPointsAndRadiusRange) {
  const FileInfo info = describe_file(testing::require_data_file("vmr-0159-aorta-centerline.vtp"),
                                      {.unit = LengthUnit::Centimetre});
  EXPECT_EQ(info.kind, "centerlines");
  ASSERT_TRUE(info.centerlines.has_value());
  const CenterlineInfo& c = *info.centerlines;
  EXPECT_EQ(c.points_per_line, (std::vector<Index>{457, 401, 581, 431}));
  EXPECT_EQ(c.total_points, 1870);
  EXPECT_EQ(c.radius_array, "MaximumInscribedSphereRadius");
  EXPECT_NEAR(c.radius_min, 2.61, 0.005);
  EXPECT_NEAR(c.radius_max, 14.83, 0.005);
  EXPECT_NEAR(c.bounds.size()(2), 196.8, 0.05);  // README: 19.68 cm
  EXPECT_TRUE(json_balanced(info.to_json())) << info.to_json();
}

TEST(Info, CenterlineFileWithoutRadiusIsStillDescribed) {
  MatX3 P(3, 3);
  P << 0, 0, 0, 3, 4, 0, 3, 4, 12;
  const fs::path file = testing::temp_dir("info-norad") / "l.vtp";
  write_polyline_vtp(file, P, {{0, 1, 2}});
  const FileInfo info = describe_file(file);
  ASSERT_TRUE(info.centerlines.has_value());
  EXPECT_EQ(info.centerlines->radius_array, "");
  EXPECT_DOUBLE_EQ(info.centerlines->line_lengths[0], 17.0);
  EXPECT_NE(info.text().find("no radius array"), std::string::npos);
}

TEST(Info, OpenMeshIsReportedOpenWithoutGenus) {
  const fs::path file = testing::temp_dir("info-open") / "tube.vtp";
  write_vtp(file, tube(5, 8, 2.0, 3.0));
  const FileInfo info = describe_file(file);
  ASSERT_TRUE(info.mesh.has_value());
  EXPECT_FALSE(info.mesh->report.closed());
  EXPECT_EQ(info.mesh->report.boundary_edges, 16);
  EXPECT_EQ(info.mesh->genus(), -1);
  EXPECT_NE(info.to_json().find("\"closed\": false"), std::string::npos);
}

TEST(Info, UnknownExtensionListsWhatIsAccepted) {
  const fs::path file = testing::temp_dir("info-ext") / "thing.png";
  testing::write_text(file, "x");
  testing::expect_error_naming([&] { describe_file(file); },
                               "thing.png: unknown file extension '.png' (meshes:");
}

}  // namespace
}  // namespace medspring
