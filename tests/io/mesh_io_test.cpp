// Mesh files (io/mesh_io.hpp): the real meshes, round trips through every format, point arrays and
// series, atomic writes. Malformed input: mesh_io_malformed_test.cpp (OBJ, STL, PLY, legacy VTK) and
// mesh_io_vtp_test.cpp (VTK XML).
#include "medspring/io/mesh_io.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLWriter.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridWriter.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "io_test_util.hpp"
#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "mesh_io_test_util.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;
using testing::expect_error_naming;
using testing::to_polydata;
using testing::write_text;

/// Every vertex of `a` has a vertex of `b` within float rounding (2^-24 relative), and vice versa
/// by equal counts.
void expect_same_vertex_set(const MatX3& a, const MatX3& b) {
  ASSERT_EQ(a.rows(), b.rows());
  for (Index i = 0; i < a.rows(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (Index j = 0; j < b.rows(); ++j) best = std::min(best, (a.row(i) - b.row(j)).cwiseAbs().maxCoeff());
    ASSERT_LE(best, std::ldexp(a.row(i).cwiseAbs().maxCoeff(), -24)) << "vertex " << i;
  }
}

// --- the real meshes ---------------------------------------------------------------------------------

TEST(MeshIo, KidneyObjInMetresIsClosedGenusZeroWithTheDocumentedSizeAndVolume) {
  const auto path = testing::require_data_file("kidney_left_hubmap_vhm.obj");
  const MeshReadResult r = read_mesh_with_report(path, {.unit = LengthUnit::Metre});
  EXPECT_EQ(r.format, "OBJ");
  EXPECT_EQ(r.mesh.num_vertices(), 5002);
  EXPECT_EQ(r.mesh.num_faces(), 10000);
  EXPECT_EQ(r.merged_vertices, 0);
  EXPECT_EQ(r.dropped_cells, 0);
  EXPECT_TRUE(r.report.valid()) << r.report.first_problem;
  EXPECT_TRUE(r.report.closed());
  EXPECT_TRUE(r.report.manifold());
  EXPECT_EQ(r.report.components, 1);
  EXPECT_EQ(r.report.euler_characteristic, 2);
  EXPECT_EQ(r.report.inconsistent_edges, 0);
  // data/README.md: 75.9 x 106.7 x 82.7 mm (rounded to 0.1 mm), 1.98e-4 m^3
  const auto b = bounds(r.mesh.V);
  const Vec3 size = (b.row(1) - b.row(0)).transpose();
  EXPECT_NEAR(size(0), 75.9, 0.05);
  EXPECT_NEAR(size(1), 106.7, 0.05);
  EXPECT_NEAR(size(2), 82.7, 0.05);
  EXPECT_NEAR(b(0, 0), 33.6, 0.05);                          // min x 0.0336 m
  EXPECT_NEAR(r.report.signed_volume / 1000.0, 198.0, 0.5);  // cm^3
  EXPECT_GT(r.report.signed_volume, 0.0);                    // outward normals
}

TEST(MeshIo, AortaObjIsClosedManifoldWithTheDocumentedBoundingBox) {
  const auto path = testing::require_data_file("aorta_totalseg_ct.obj");
  const MeshReadResult r = read_mesh_with_report(path);
  EXPECT_EQ(r.mesh.num_vertices(), 10002);
  EXPECT_EQ(r.mesh.num_faces(), 20000);
  EXPECT_TRUE(r.report.valid()) << r.report.first_problem;
  EXPECT_TRUE(r.report.closed());
  EXPECT_EQ(r.report.components, 1);
  EXPECT_EQ(r.report.euler_characteristic, 2);
  EXPECT_NEAR(r.report.signed_volume / 1000.0, 241.0, 0.5);  // cm^3 (README: 241)
  // README (mm, RAS): min (-44.6, 88.4, 539.6), max (17.5, 204.4, 766.4), rounded to 0.1 mm
  const auto b = bounds(r.mesh.V);
  const double expected[2][3] = {{-44.6, 88.4, 539.6}, {17.5, 204.4, 766.4}};
  for (int s = 0; s < 2; ++s)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(b(s, c), expected[s][c], 0.05) << "row " << s << " axis " << c;
}

TEST(MeshIo, EveryMeshInTheDataFolderLoadsAsAValidClosedSurface) {
  int meshes = 0;
  for (const auto& entry : fs::directory_iterator(testing::data_dir())) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".obj" && ext != ".stl" && ext != ".ply" && ext != ".vtk" && ext != ".vtp") continue;
    if (entry.path().filename().string().find("centerline") != std::string::npos) continue;
    SCOPED_TRACE(entry.path().filename().string());
    const MeshReadResult r = read_mesh_with_report(entry.path());
    EXPECT_TRUE(r.report.valid()) << r.report.first_problem;
    EXPECT_TRUE(r.report.closed());
    EXPECT_EQ(r.report.components, 1);
    EXPECT_GT(r.report.signed_volume, 0.0);
    ++meshes;
  }
  EXPECT_GE(meshes, 2);  // kidney and aorta
}

TEST(MeshIo, ExtensionIsCaseInsensitive) {
  const fs::path dir = testing::temp_dir("io-case");
  write_obj(dir / "a.obj", kidney_phantom());
  fs::rename(dir / "a.obj", dir / "A.OBJ");
  EXPECT_EQ(read_mesh(dir / "A.OBJ").num_faces(), 912);
}

// --- round trips --------------------------------------------------------------------------------------

TEST(MeshIo, VtpRoundTripIsExact) {
  const SurfaceMesh m = kidney_phantom();
  const fs::path file = testing::temp_dir("io-vtp") / "kidney.vtp";
  write_vtp(file, m);
  const MeshReadResult r = read_mesh_with_report(file);
  EXPECT_EQ(r.format, "VTP");
  EXPECT_EQ(r.merged_vertices, 0);
  EXPECT_EQ(r.mesh.V, m.V);  // Float64 in the file: bit-exact
  EXPECT_EQ(r.mesh.F, m.F);
}

TEST(MeshIo, ObjRoundTripIsExactToFloatPrecision) {
  const SurfaceMesh m = kidney_phantom();
  const fs::path file = testing::temp_dir("io-obj") / "kidney.obj";
  write_obj(file, m);
  const SurfaceMesh back = read_mesh(file);
  testing::expect_float_rounding_of(m.V, back.V);  // vtkOBJReader stores Float32
  EXPECT_EQ(back.F, m.F);
}

TEST(MeshIo, StlAsciiAndBinaryWeldBackToTheSameVertexCount) {
  const SurfaceMesh m = kidney_phantom();
  const fs::path dir = testing::temp_dir("io-stl");
  for (const bool binary : {false, true}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    const fs::path file = dir / (binary ? "kidney-bin.stl" : "kidney-ascii.stl");
    vtkNew<vtkSTLWriter> writer;
    writer->SetInputData(to_polydata(m));
    writer->SetFileName(file.string().c_str());
    if (binary)
      writer->SetFileTypeToBinary();
    else
      writer->SetFileTypeToASCII();
    ASSERT_EQ(writer->Write(), 1);

    const MeshReadResult raw = read_mesh_with_report(file, {.weld = false});
    EXPECT_EQ(raw.mesh.num_vertices(), 3 * 912);  // STL repeats every corner
    const MeshReadResult r = read_mesh_with_report(file);
    EXPECT_EQ(r.format, "STL");
    EXPECT_EQ(r.mesh.num_vertices(), 458);
    EXPECT_EQ(r.mesh.num_faces(), 912);
    EXPECT_EQ(r.merged_vertices, 3 * 912 - 458);
    EXPECT_TRUE(r.report.closed());
    EXPECT_TRUE(r.report.manifold());
    EXPECT_EQ(r.report.euler_characteristic, 2);
    expect_same_vertex_set(m.V, r.mesh.V);
    EXPECT_NEAR(r.report.signed_volume, signed_volume(m.V, m.F), 1e-5 * signed_volume(m.V, m.F));
  }
}

TEST(MeshIo, PlyRoundTripIsExactToFloatPrecision) {
  const SurfaceMesh m = kidney_phantom();
  const fs::path file = testing::temp_dir("io-ply") / "kidney.ply";
  write_mesh(file, m);
  const MeshReadResult r = read_mesh_with_report(file);
  EXPECT_EQ(r.format, "PLY");
  testing::expect_float_rounding_of(m.V, r.mesh.V);  // vtkPLYWriter stores Float32
  EXPECT_EQ(r.mesh.F, m.F);
}

TEST(MeshIo, LegacyVtkRoundTripIsExact) {
  const SurfaceMesh m = kidney_phantom();
  const fs::path file = testing::temp_dir("io-vtk") / "kidney.vtk";
  write_mesh(file, m);
  const MeshReadResult r = read_mesh_with_report(file);
  EXPECT_EQ(r.format, "VTK");
  EXPECT_EQ(r.mesh.V, m.V);  // binary legacy file with double points
  EXPECT_EQ(r.mesh.F, m.F);
}

TEST(MeshIo, StlWrittenByWriteMeshRoundTrips) {
  const SurfaceMesh m = icosphere(2, 10.0);
  const fs::path file = testing::temp_dir("io-stl2") / "sphere.stl";
  write_mesh(file, m);
  const SurfaceMesh back = read_mesh(file);
  EXPECT_EQ(back.num_vertices(), m.num_vertices());
  EXPECT_EQ(back.num_faces(), m.num_faces());
  expect_same_vertex_set(m.V, back.V);
}

TEST(MeshIo, PolygonsAreTriangulatedAndLinesAndPointsDroppedWithCounts) {
  const fs::path file = testing::temp_dir("io-poly") / "mixed.obj";
  // a unit square as one quad plus a line and a point cell; vertex 5 is a duplicate of vertex 1
  write_text(file,
             "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 0\n"
             "f 1 5 3 4\nl 1 3\np 2\n");
  const MeshReadResult r = read_mesh_with_report(file);
  EXPECT_EQ(r.file_points, 5);
  EXPECT_EQ(r.file_polygons, 1);
  EXPECT_EQ(r.triangulated_polygons, 1);
  EXPECT_EQ(r.dropped_cells, 2);
  EXPECT_EQ(r.mesh.num_faces(), 2);
  EXPECT_EQ(r.mesh.num_vertices(), 4);  // vertex 2 (unreferenced after welding) and the duplicate removed
  EXPECT_EQ(r.merged_vertices, 1);
  EXPECT_NEAR(surface_area(r.mesh.V, r.mesh.F), 1.0, 1e-12);
  EXPECT_EQ(r.report.boundary_edges, 4);
}

TEST(MeshIo, UnitOptionScalesCoordinatesToMillimetres) {
  const fs::path file = testing::temp_dir("io-unit") / "tri.obj";
  write_text(file, "v 0 0 0\nv 1 0 0\nv 0 2 0\nf 1 2 3\n");
  EXPECT_DOUBLE_EQ(read_mesh(file, {.unit = LengthUnit::Centimetre}).V(2, 1), 20.0);
  EXPECT_DOUBLE_EQ(read_mesh(file, {.unit = LengthUnit::Metre}).V(1, 0), 1000.0);
  EXPECT_DOUBLE_EQ(read_mesh(file).V(1, 0), 1.0);
}

// --- point arrays, polylines, pvd ----------------------------------------------------------------------

TEST(MeshIo, WriteVtpStoresPointArraysByName) {
  const SurfaceMesh m = kidney_phantom();
  MatX3 U = 0.5 * m.V;
  const VecX mag = U.rowwise().norm();
  const fs::path file = testing::temp_dir("io-arrays") / "u.vtp";
  write_vtp(file, m, {{"displacement", U}, {"magnitude", mag}});
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(file.string().c_str());
  reader->Update();
  vtkPointData* pd = reader->GetOutput()->GetPointData();
  vtkDataArray* du = pd->GetArray("displacement");
  vtkDataArray* dm = pd->GetArray("magnitude");
  ASSERT_NE(du, nullptr);
  ASSERT_NE(dm, nullptr);
  EXPECT_EQ(du->GetNumberOfComponents(), 3);
  EXPECT_EQ(dm->GetNumberOfComponents(), 1);
  for (Index i = 0; i < m.num_vertices(); ++i) {
    for (int c = 0; c < 3; ++c) ASSERT_EQ(du->GetComponent(i, c), U(i, c));
    ASSERT_EQ(dm->GetComponent(i, 0), mag(i));
  }
}

TEST(MeshIo, WriteVtpRejectsArraysOfTheWrongLengthAndWritesNothing) {
  const SurfaceMesh m = kidney_phantom();
  const fs::path dir = testing::temp_dir("io-badarray");
  expect_error_naming([&] { write_vtp(dir / "u.vtp", m, {{"magnitude", VecX::Zero(3)}}); }, "'magnitude'");
  expect_error_naming(
      [&] {
        write_vtp(dir / "u.vtp", m, {{"a", VecX::Zero(458)}, {"a", VecX::Zero(458)}});
      },
      "used twice");
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(MeshIo, PolylineVtpIsNotASurfaceMesh) {
  MatX3 P(4, 3);
  P << 0, 0, 0, 1, 0, 0, 2, 0, 0, 2, 1, 0;
  const fs::path file = testing::temp_dir("io-lines") / "lines.vtp";
  write_polyline_vtp(file, P, {{0, 1, 2}, {2, 3}});
  expect_error_naming([&] { read_mesh(file); }, "lines.vtp: no polygons");
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(file.string().c_str());
  reader->Update();
  EXPECT_EQ(reader->GetOutput()->GetNumberOfLines(), 2);
  EXPECT_EQ(reader->GetOutput()->GetNumberOfPoints(), 4);
  MatX2i S(2, 2);
  S << 0, 1, 1, 3;
  write_segments_vtp(file, P, S, {{"id", VecX::LinSpaced(4, 0, 3)}});
  reader->Modified();
  reader->Update();
  EXPECT_EQ(reader->GetOutput()->GetNumberOfLines(), 2);
  EXPECT_NE(reader->GetOutput()->GetPointData()->GetArray("id"), nullptr);
  expect_error_naming([&] { write_polyline_vtp(file, P, {{0, 9}}); }, "line 0 point 1");
}

TEST(MeshIo, PvdListsEveryFrameWithItsTime) {
  const fs::path file = testing::temp_dir("io-pvd") / "run.pvd";
  write_pvd(file, {{0.0, "frame_0000.vtp"}, {0.25, "frame_0001.vtp"}, {0.5, "a&b.vtp"}});
  const std::string text = testing::read_text(file);
  EXPECT_NE(text.find("type=\"Collection\""), std::string::npos);
  EXPECT_NE(text.find("timestep=\"0.25\" group=\"\" part=\"0\" file=\"frame_0001.vtp\""), std::string::npos)
      << text;
  EXPECT_NE(text.find("file=\"a&amp;b.vtp\""), std::string::npos);
  std::size_t count = 0;
  for (auto p = text.find("<DataSet"); p != std::string::npos; p = text.find("<DataSet", p + 1)) ++count;
  EXPECT_EQ(count, 3u);
}

// --- atomic writes -------------------------------------------------------------------------------------

TEST(MeshIo, AtomicWriteLeavesOnlyTheTargetFile) {
  const fs::path dir = testing::temp_dir("io-atomic");
  write_vtp(dir / "a.vtp", kidney_phantom());
  write_obj(dir / "a.obj", kidney_phantom());
  write_pvd(dir / "a.pvd", {{0.0, "a.vtp"}});
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"a.obj", "a.pvd", "a.vtp"}));
}

TEST(MeshIo, WriteIntoAMissingFolderFailsAndCreatesNothing) {
  const fs::path dir = testing::temp_dir("io-nofolder");
  const fs::path target = dir / "missing" / "a.vtp";
  expect_error_naming([&] { write_vtp(target, kidney_phantom()); }, "a.vtp");
  expect_error_naming([&] { write_obj(dir / "missing" / "a.obj", kidney_phantom()); }, "does not exist");
  expect_error_naming([&] { write_pvd(dir / "missing" / "a.pvd", {}); }, "a.pvd");
  EXPECT_FALSE(fs::exists(dir / "missing"));
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(MeshIo, FailedWriteKeepsTheOldFileAndRemovesTheTemporary) {
  const fs::path dir = testing::temp_dir("io-failwrite");
  const fs::path target = dir / "a.vtp";
  write_text(target, "old content");
  // make the temporary path unusable: a folder where the writer wants its file
  fs::path tmp = target;
  tmp += ".tmp-" + std::to_string(::getpid()) + ".vtp";
  fs::create_directory(tmp);
  expect_error_naming([&] { write_vtp(target, kidney_phantom()); }, "a.vtp");
  EXPECT_EQ(testing::read_text(target), "old content");
  EXPECT_FALSE(fs::exists(tmp));
}

}  // namespace
}  // namespace medspring
