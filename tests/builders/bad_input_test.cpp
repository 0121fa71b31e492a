// Bad input to the builders fails with one clear line naming the file and what is wrong, and leaves
// nothing half-written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "medspring/builders/centerline_build.hpp"
#include "medspring/builders/kidney_build.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/io/output_folder.hpp"
#include "medspring/io/volume_io.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;

/// The message of the InvalidInput that f throws ("" and a test failure when it throws none).
template <class F>
std::string invalid_input_message(F&& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InvalidInput thrown";
  return {};
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

fs::path write_labels(const std::string& tag, const std::vector<std::pair<Index, std::int32_t>>& voxels) {
  LabelVolume v;
  v.dims = {8, 8, 8};
  v.spacing = Vec3::Constant(1.5);
  v.data.assign(v.size(), 0);
  for (const auto& [index, label] : voxels) v.data[index] = label;
  const fs::path file = testing::temp_dir(tag) / "labels.mha";
  write_label_volume(file, v);
  return file;
}

TEST(BadInput, EmptyMaskIsRefused) {
  const fs::path file = write_labels("empty-mask", {});
  const std::string m1 = invalid_input_message([&] { build_kidney_model({.source = {.mask = file}}); });
  EXPECT_TRUE(contains(m1, "labels.mha: mask is empty")) << m1;
  const std::string m2 =
      invalid_input_message([&] { build_centerline({.source = {.mask = file, .label = 1}}); });
  EXPECT_TRUE(contains(m2, "mask is empty")) << m2;
}

TEST(BadInput, MissingLabelNamesTheLabelsPresent) {
  const fs::path file = write_labels("missing-label", {{100, 1}, {101, 1}, {300, 4}});
  const std::string m =
      invalid_input_message([&] { build_centerline({.source = {.mask = file, .label = 3}}); });
  EXPECT_TRUE(contains(m, "labels.mha: label 3 not found; labels present: 1 (2 voxels), 4 (1 voxels)")) << m;
}

TEST(BadInput, SeveralLabelsWithoutAChosenLabelAreRefused) {
  const fs::path file = write_labels("several-labels", {{100, 1}, {300, 4}});
  const std::string m = invalid_input_message([&] { build_kidney_model({.source = {.mask = file}}); });
  EXPECT_TRUE(contains(m, "2 labels present, choose one with label (--label N)")) << m;
}

TEST(BadInput, OpenMeshIsRefusedUnlessItsHolesAreClosed) {
  SurfaceMesh open = kidney_phantom();
  open.F.conservativeResize(open.F.rows() - 1, 3);  // one triangle removed: a hole of 3 edges
  const fs::path file = testing::temp_dir("open-mesh") / "open.obj";
  write_obj(file, open);
  const std::string m = invalid_input_message([&] { build_kidney_model({.source = {.mesh = file}}); });
  EXPECT_TRUE(contains(m, "open.obj: surface is open: 3 boundary edges in 1 hole")) << m;
  EXPECT_TRUE(contains(m, "--close-holes")) << m;
  const LoadedOrgan closed = load_organ({.mesh = file, .close_holes = 8});
  EXPECT_EQ(closed.holes_closed, 1);
  EXPECT_TRUE(validate_mesh(closed.surface).closed());
}

TEST(BadInput, NonManifoldMeshIsRefused) {
  SurfaceMesh m = kidney_phantom();
  // a fin: a third triangle on the edge of face 0
  const Index a = m.F(0, 0), b = m.F(0, 1);
  m.V.conservativeResize(m.V.rows() + 1, 3);
  m.V.row(m.V.rows() - 1) = 0.5 * (m.V.row(a) + m.V.row(b)) + Vec3(0, 0, 30).transpose();
  m.F.conservativeResize(m.F.rows() + 1, 3);
  m.F.row(m.F.rows() - 1) << a, b, static_cast<Index>(m.V.rows() - 1);
  const fs::path file = testing::temp_dir("fin-mesh") / "fin.obj";
  write_obj(file, m);
  const std::string msg = invalid_input_message([&] { build_kidney_model({.source = {.mesh = file}}); });
  EXPECT_TRUE(contains(msg, "fin.obj: surface is not manifold")) << msg;
}

TEST(BadInput, TooFewNodesAreRefusedBeforeAnyWork) {
  const std::string m = invalid_input_message(
      [&] { build_kidney_model({.source = {.mesh = "does-not-exist.obj"}, .nodes = 10}); });
  EXPECT_TRUE(contains(m, "nodes must be >= 20 (got 10)")) << m;
  const std::string m2 = invalid_input_message(
      [&] { build_kidney_model({.source = {.mesh = "does-not-exist.obj"}, .nodes = 100, .atoms = 1}); });
  EXPECT_TRUE(contains(m2, "atoms must be >= 2")) << m2;
}

// 30 nodes cannot follow the real kidney: the coarse surface cuts through the skeleton.
TEST(BadInput, NodeCountTooSmallForTheShapeIsRefused) {
  const std::string m = invalid_input_message([&] {
    build_kidney_model({.source = {.mesh = testing::require_data_file("kidney_left_hubmap_vhm.obj"),
                                   .unit = LengthUnit::Metre},
                        .nodes = 30,
                        .atoms = 10});
  });
  EXPECT_TRUE(contains(m, "kidney: 30 surface nodes are too few for the shape of kidney_left_hubmap_vhm.obj"))
      << m;
  EXPECT_TRUE(contains(m, "use more nodes (--nodes)")) << m;
}

TEST(BadInput, MetreFileReadAsMillimetresWarnsAboutTheUnit) {
  const LoadedOrgan organ = load_organ({.mesh = testing::require_data_file("kidney_left_hubmap_vhm.obj")});
  ASSERT_EQ(organ.warnings.size(), 1u);
  EXPECT_TRUE(contains(organ.warnings[0], "use --unit m")) << organ.warnings[0];
  const LoadedOrgan right = load_organ(
      {.mesh = testing::require_data_file("kidney_left_hubmap_vhm.obj"), .unit = LengthUnit::Metre});
  EXPECT_TRUE(right.warnings.empty());
}

TEST(BadInput, MeshAndMaskTogetherAreRefused) {
  const std::string m = invalid_input_message([&] { load_organ({.mesh = "a.obj", .mask = "b.nii"}); });
  EXPECT_TRUE(contains(m, "exactly one of a mesh and a mask (got both)")) << m;
}

TEST(OutputFolder, NonEmptyFolderIsRefusedWithoutForceAndReplacedWithIt) {
  const fs::path dir = testing::temp_dir("out-force") / "model";
  fs::create_directories(dir);
  std::ofstream(dir / "old.txt") << "old";
  auto write_new = [](const fs::path& d) { std::ofstream(d / "new.txt") << "new"; };
  EXPECT_THROW(write_output_folder(dir, false, write_new), IoError);
  EXPECT_TRUE(fs::exists(dir / "old.txt"));
  write_output_folder(dir, true, write_new);
  EXPECT_FALSE(fs::exists(dir / "old.txt"));
  EXPECT_TRUE(fs::exists(dir / "new.txt"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.parent_path()), fs::directory_iterator()), 1);
}

TEST(OutputFolder, FailureHalfWayLeavesNothingBehind) {
  const fs::path root = testing::temp_dir("out-fail");
  const fs::path dir = root / "new" / "model";
  EXPECT_THROW(write_output_folder(dir, false,
                                   [](const fs::path& d) {
                                     std::ofstream(d / "surface.vtp") << "half";
                                     throw IoError("disk full");
                                   }),
               IoError);
  EXPECT_FALSE(fs::exists(root / "new"));
  EXPECT_TRUE(fs::is_empty(root));
  // an existing folder with --force is left as it was when the new files fail
  fs::create_directories(dir);
  std::ofstream(dir / "old.txt") << "old";
  EXPECT_THROW(write_output_folder(dir, true, [](const fs::path&) { throw IoError("disk full"); }), IoError);
  EXPECT_TRUE(fs::exists(dir / "old.txt"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.parent_path()), fs::directory_iterator()), 1);
}

}  // namespace
}  // namespace medspring
