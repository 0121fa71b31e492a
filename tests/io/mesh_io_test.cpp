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
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;
using testing::expect_error_naming;
using testing::write_text;

vtkSmartPointer<vtkPolyData> to_polydata(const SurfaceMesh& m) {
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  for (Index i = 0; i < m.num_vertices(); ++i) pts->InsertNextPoint(m.V(i, 0), m.V(i, 1), m.V(i, 2));
  vtkNew<vtkCellArray> cells;
  for (Index f = 0; f < m.num_faces(); ++f) {
    const vtkIdType ids[3] = {m.F(f, 0), m.F(f, 1), m.F(f, 2)};
    cells->InsertNextCell(3, ids);
  }
  poly->SetPoints(pts);
  poly->SetPolys(cells);
  return poly;
}

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

// --- malformed input ----------------------------------------------------------------------------------

class MalformedMesh : public ::testing::Test {
 protected:
  fs::path dir_ = testing::temp_dir("io-bad");
};

TEST_F(MalformedMesh, MissingFileIsNamed) {
  expect_error_naming([&] { read_mesh(dir_ / "nothere.obj"); }, "nothere.obj: no such file");
}

TEST_F(MalformedMesh, UnknownExtensionIsNamed) {
  write_text(dir_ / "mesh.xyz", "v 0 0 0\n");
  expect_error_naming([&] { read_mesh(dir_ / "mesh.xyz"); }, "mesh.xyz: unknown mesh file extension '.xyz'");
}

TEST_F(MalformedMesh, EmptyFilesAreNamed) {
  for (const char* name : {"empty.obj", "empty.stl", "empty.ply", "empty.vtp", "empty.vtk"}) {
    write_text(dir_ / name, "");
    expect_error_naming([&] { read_mesh(dir_ / name); }, std::string(name) + ": file is empty");
  }
}

TEST_F(MalformedMesh, ObjFaceIndexOutOfRangeNamesFileAndLine) {
  write_text(dir_ / "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n");
  expect_error_naming([&] { read_mesh(dir_ / "range.obj"); }, "range.obj:4: vertex index 99 out of range");
}

TEST_F(MalformedMesh, ObjNonNumericCoordinateNamesFileAndLine) {
  write_text(dir_ / "abc.obj", "v 0 0 0\nv 1 abc 3\nv 0 1 0\nf 1 2 3\n");
  expect_error_naming([&] { read_mesh(dir_ / "abc.obj"); },
                      "abc.obj:2: 'v' coordinate 'abc' is not a number");
}

TEST_F(MalformedMesh, ObjNanCoordinateNamesFileAndLine) {
  write_text(dir_ / "nan.obj", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  expect_error_naming([&] { read_mesh(dir_ / "nan.obj"); }, "nan.obj:1: 'v' coordinate 'nan' is not finite");
}

TEST_F(MalformedMesh, ObjOtherSyntaxErrorsNameFileAndLine) {
  write_text(dir_ / "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n");
  expect_error_naming([&] { read_mesh(dir_ / "zero.obj"); }, "zero.obj:4:");
  write_text(dir_ / "rel.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n");
  expect_error_naming([&] { read_mesh(dir_ / "rel.obj"); }, "rel.obj:3:");
  // texture index without any 'vt' (vtkOBJReader crashes on this one)
  write_text(dir_ / "vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/2 3/3\n");
  expect_error_naming([&] { read_mesh(dir_ / "vt.obj"); },
                      "vt.obj:4: texture coordinate index 1 out of range");
  write_text(dir_ / "two.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2\n");
  expect_error_naming([&] { read_mesh(dir_ / "two.obj"); }, "two.obj:5: 'f' needs at least 3 vertices");
  write_text(dir_ / "short.obj", "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  expect_error_naming([&] { read_mesh(dir_ / "short.obj"); }, "short.obj:1: 'v' needs 3 coordinates");
  write_text(dir_ / "noface.obj", "v 0 0 0\nv 1 0 0\n");
  expect_error_naming([&] { read_mesh(dir_ / "noface.obj"); }, "noface.obj: no polygons");
}

TEST_F(MalformedMesh, ObjForwardReferencesAreCheckedAgainstTheFinalVertexCount) {
  write_text(dir_ / "forward.obj", "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
  EXPECT_EQ(read_mesh(dir_ / "forward.obj").num_faces(), 1);
  write_text(dir_ / "forward-bad.obj", "f 1 2 3\nf 1 2 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
  expect_error_naming([&] { read_mesh(dir_ / "forward-bad.obj"); },
                      "forward-bad.obj:2: vertex index 9 out of range (the file has 3 vertices)");
}

TEST_F(MalformedMesh, ObjWithTextureAndNormalIndicesReads) {
  write_text(dir_ / "vtvn.obj",
             "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
             "f 1/1/1 2/2/1 3/3/1\n");
  const SurfaceMesh m = read_mesh(dir_ / "vtvn.obj");
  EXPECT_EQ(m.num_vertices(), 3);
  EXPECT_EQ(m.num_faces(), 1);
}

TEST_F(MalformedMesh, TruncatedBinaryStlIsNamed) {
  const fs::path good = dir_ / "good.stl";
  write_mesh(good, kidney_phantom());
  std::string bytes = testing::read_text(good);
  write_text(dir_ / "trunc.stl", bytes.substr(0, bytes.size() / 2));
  expect_error_naming([&] { read_mesh(dir_ / "trunc.stl"); }, "trunc.stl: truncated binary STL");
  write_text(dir_ / "tiny.stl", std::string("\x01\x02\x03", 3));
  expect_error_naming([&] { read_mesh(dir_ / "tiny.stl"); }, "tiny.stl");
}

TEST_F(MalformedMesh, MalformedAsciiStlIsNamed) {
  write_text(dir_ / "bad-ascii.stl", "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0\n");
  expect_error_naming([&] { read_mesh(dir_ / "bad-ascii.stl"); }, "bad-ascii.stl");
}

TEST_F(MalformedMesh, GarbageInXmlPlyAndLegacyFilesIsNamed) {
  const std::string garbage = "\x7f\x45\x12 this is not a mesh \x01\x02\xff\xfe";
  for (const char* name : {"garbage.vtp", "garbage.ply", "garbage.vtk"}) {
    write_text(dir_ / name, garbage);
    expect_error_naming([&] { read_mesh(dir_ / name); }, name);
  }
  // a truncated .vtp
  write_vtp(dir_ / "whole.vtp", kidney_phantom());
  const std::string vtp = testing::read_text(dir_ / "whole.vtp");
  write_text(dir_ / "cut.vtp", vtp.substr(0, vtp.size() * 2 / 3));
  expect_error_naming([&] { read_mesh(dir_ / "cut.vtp"); }, "cut.vtp");
}

std::string base64_decode(std::string_view text) {
  static const std::string A = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::uint32_t acc = 0;
  int bits = 0;
  for (char c : text) {
    const auto v = A.find(c);
    if (v == std::string::npos) break;
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    if ((bits += 6) >= 8) out.push_back(static_cast<char>((acc >> (bits -= 8)) & 0xff));
  }
  return out;
}

std::string base64_encode(std::string_view bytes) {
  static const char* A = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t v = 0;
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    for (std::size_t k = 0; k < 3; ++k)
      v = (v << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    for (std::size_t k = 0; k < 4; ++k) out.push_back(k <= n ? A[(v >> (18 - 6 * k)) & 63] : '=');
  }
  return out;
}

/// One triangle in VTK XML, appended raw and uncompressed with UInt32 headers: the points (the
/// size header says `points_bytes`), connectivity Int32 {0, 1, 2}, and the one cell offset `offset`
/// (Int32 or Int64).
template <class Offset>
std::string one_triangle_raw_vtp(Offset offset, std::uint32_t points_bytes = 36) {
  static_assert(std::is_same_v<Offset, std::int32_t> || std::is_same_v<Offset, std::int64_t>);
  std::string raw;
  auto put = [&](const auto& v) { raw.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(points_bytes);
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(v);
  put(std::uint32_t{12});
  for (std::int32_t v : {0, 1, 2}) put(v);
  put(static_cast<std::uint32_t>(sizeof(Offset)));
  put(offset);
  return cat(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" ",
      "header_type=\"UInt32\">\n<PolyData>\n<Piece NumberOfPoints=\"3\" NumberOfPolys=\"1\">\n",
      "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" "
      "offset=\"0\"/></Points>\n",
      "<Polys><DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" offset=\"40\"/>\n",
      "<DataArray type=\"", sizeof(Offset) == 8 ? "Int64" : "Int32",
      "\" Name=\"offsets\" format=\"appended\" offset=\"56\"/></Polys>\n",
      "</Piece>\n</PolyData>\n<AppendedData encoding=\"raw\">\n_", raw, "\n</AppendedData>\n</VTKFile>\n");
}

TEST_F(MalformedMesh, VtpSizeHeadersBeyondTheFileAreRefusedBeforeVtkAllocates) {
  // write_vtp: appended base64 data, zlib, UInt64 headers [blocks, block size, last size, compressed
  // sizes], the header its own base64 stream; the Points array is at offset 0
  write_vtp(dir_ / "whole.vtp", kidney_phantom());
  const std::string vtp = testing::read_text(dir_ / "whole.vtp");
  const std::size_t data = vtp.find('_', vtp.find("<AppendedData")) + 1;
  const std::size_t header_chars = 44;  // 4 words = 32 bytes
  auto patched = [&](std::size_t word, std::uint64_t value) {
    std::string h = base64_decode(std::string_view(vtp).substr(data, header_chars));
    EXPECT_EQ(h.size(), 32u);
    for (int k = 0; k < 8; ++k) h[8 * word + k] = static_cast<char>((value >> (8 * k)) & 0xff);
    std::string b = vtp;
    b.replace(data, header_chars, base64_encode(h));
    return b;
  };
  write_text(dir_ / "same.vtp", patched(0, 1));  // the helpers re-encode the header faithfully
  EXPECT_EQ(testing::read_text(dir_ / "same.vtp"), vtp);
  write_text(dir_ / "blocks.vtp", patched(0, std::uint64_t(1) << 60));  // block count
  expect_error_naming(
      [&] { read_mesh(dir_ / "blocks.vtp"); },
      "blocks.vtp: VTK XML: DataArray 'Points' declares 1152921504606846976 compressed blocks");
  write_text(dir_ / "packed.vtp", patched(3, std::uint64_t(1) << 40));  // compressed size of block 0
  expect_error_naming([&] { read_mesh(dir_ / "packed.vtp"); }, "compressed bytes, the file holds");
  write_text(dir_ / "unpacked.vtp", patched(1, std::uint64_t(1) << 39));  // uncompressed block size
  expect_error_naming([&] { read_mesh(dir_ / "unpacked.vtp"); }, "uncompressed bytes from");
  {  // pieces whose point counts each fit in the file, but not together: VTK allocates for the sum
    std::string pieces =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" "
        "byte_order=\"LittleEndian\">\n<PolyData>\n";
    for (int k = 0; k < 3; ++k) pieces += "<Piece NumberOfPoints=\"900\" NumberOfPolys=\"0\"></Piece>\n";
    pieces += "</PolyData>\n</VTKFile>\n";
    write_text(dir_ / "pieces.vtp", pieces);
    expect_error_naming([&] { read_mesh(dir_ / "pieces.vtp"); },
                        "pieces.vtp: VTK XML: the pieces' NumberOfPoints add up to 1800: more than a");
  }
  {  // no blocks and block size 0: vtkXMLDataParser still divides by the block size (fuzz_mesh_vtp, SIGFPE)
    std::string h = base64_decode(std::string_view(vtp).substr(data, header_chars));
    std::fill(h.begin(), h.begin() + 16, '\0');
    std::string b = vtp;
    b.replace(data, header_chars, base64_encode(h));
    write_text(dir_ / "no-blocks.vtp", b);
    expect_error_naming([&] { read_mesh(dir_ / "no-blocks.vtp"); },
                        "no-blocks.vtp: VTK XML: DataArray 'Points': compression header with block size 0");
  }

  // appended raw, uncompressed, UInt32 headers: one triangle
  write_text(dir_ / "raw.vtp", one_triangle_raw_vtp(std::int32_t{3}));
  EXPECT_EQ(read_mesh(dir_ / "raw.vtp").num_faces(), 1);
  write_text(dir_ / "raw-big.vtp", one_triangle_raw_vtp(std::int32_t{3}, 0x7fffffff));
  expect_error_naming([&] { read_mesh(dir_ / "raw-big.vtp"); },
                      "raw-big.vtp: VTK XML: DataArray '' declares 2147483647 bytes, the file holds");
}

TEST_F(MalformedMesh, VtpCellOffsetsBeyondTheConnectivityAreRefusedBeforeVtkAllocates) {
  // vtkXMLUnstructuredDataReader sizes the connectivity array by the last cell offset before it reads
  // it (fuzz_mesh_vtp: an offset of 3e9 allocated 24 GB). check_vtk_xml decodes the offsets (raw,
  // base64; zlib, LZ4, LZMA) and compares the last one with what the connectivity array declares.
  const SurfaceMesh kidney = kidney_phantom();
  const std::string last_offset = std::to_string(3 * kidney.num_faces());
  struct Mode {
    const char* name;
    int compressor;  // vtkXMLWriter::CompressorType
    bool appended, base64;
  };
  for (const Mode& mode : {Mode{"zlib-appended-base64", vtkXMLWriter::ZLIB, true, true},
                           Mode{"lz4-appended-base64", vtkXMLWriter::LZ4, true, true},
                           Mode{"lzma-binary", vtkXMLWriter::LZMA, false, true},
                           Mode{"zlib-binary", vtkXMLWriter::ZLIB, false, true},
                           Mode{"none-binary", vtkXMLWriter::NONE, false, true}}) {
    SCOPED_TRACE(mode.name);
    vtkNew<vtkXMLPolyDataWriter> writer;
    writer->SetInputData(to_polydata(kidney));
    writer->SetCompressorType(mode.compressor);
    writer->SetHeaderTypeToUInt64();
    if (mode.appended)
      writer->SetDataModeToAppended();
    else
      writer->SetDataModeToBinary();
    writer->SetEncodeAppendedData(mode.base64);
    const fs::path good = dir_ / cat(mode.name, ".vtp");
    writer->SetFileName(good.string().c_str());
    ASSERT_EQ(writer->Write(), 1);
    EXPECT_EQ(read_mesh(good).num_faces(), kidney.num_faces());  // the check refuses no valid file

    // the connectivity array's header: 4 UInt64 words (1 block; uncompressed: 1 word), 44 base64 chars
    std::string vtp = testing::read_text(good);
    const std::size_t tag = vtp.find("Name=\"connectivity\"", vtp.find("<Polys"));
    ASSERT_NE(tag, std::string::npos);
    std::size_t data = 0;
    if (mode.appended) {
      const std::size_t off = vtp.find("offset=\"", tag) + 8;
      data = vtp.find('_', vtp.find("<AppendedData")) + 1 + std::stoul(vtp.substr(off));
    } else {
      data = vtp.find_first_not_of(" \t\r\n", vtp.find('>', tag) + 1);
    }
    const bool compressed = mode.compressor != vtkXMLWriter::NONE;
    const std::size_t header_chars = compressed ? 44 : 12;
    std::string h = base64_decode(std::string_view(vtp).substr(data, header_chars));
    // compressed: the header is a base64 stream of its own (32 bytes); uncompressed: one stream with
    // the data (12 characters = the 8-byte size and the first data byte)
    ASSERT_EQ(h.size(), compressed ? 32u : 9u);
    const std::uint64_t one_value = 8;  // the connectivity now declares one Int64 value
    for (int k = 0; k < 8; ++k)
      h[(compressed ? 16 : 0) + k] = static_cast<char>((one_value >> (8 * k)) & 0xff);
    vtp.replace(data, header_chars, base64_encode(h));
    const fs::path bad = dir_ / cat(mode.name, "-short.vtp");
    write_text(bad, vtp);
    expect_error_naming([&] { read_mesh(bad); },
                        cat(bad.filename().string(), ": VTK XML: piece 0: Polys offsets end at ", last_offset,
                            " connectivity values, the connectivity array holds 1"));
  }

  // ascii, and appended raw with a 2e9 offset (the fuzzer's case): one triangle
  const std::string ascii =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      "<PolyData>\n<Piece NumberOfPoints=\"3\" NumberOfPolys=\"1\">\n"
      "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 "
      "0</DataArray></Points>\n"
      "<Polys><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2</DataArray>\n"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">OFFSET</DataArray></Polys>\n"
      "</Piece>\n</PolyData>\n</VTKFile>\n";
  auto with_offset = [&](const std::string& v) {
    std::string s = ascii;
    s.replace(s.find("OFFSET"), 6, v);
    return s;
  };
  write_text(dir_ / "ascii.vtp", with_offset("3"));
  EXPECT_EQ(read_mesh(dir_ / "ascii.vtp").num_faces(), 1);
  write_text(dir_ / "ascii-huge.vtp", with_offset("2000000000"));
  expect_error_naming(
      [&] { read_mesh(dir_ / "ascii-huge.vtp"); },
      "ascii-huge.vtp: VTK XML: piece 0: Polys offsets end at 2000000000 connectivity values, "
      "the connectivity array holds 3");
  write_text(dir_ / "ascii-negative.vtp", with_offset("-5"));
  expect_error_naming([&] { read_mesh(dir_ / "ascii-negative.vtp"); },
                      "ascii-negative.vtp: VTK XML: piece 0: Polys offsets hold -5 (offsets are >= 0)");

  write_text(dir_ / "raw3.vtp", one_triangle_raw_vtp(std::int64_t{3}));
  EXPECT_EQ(read_mesh(dir_ / "raw3.vtp").num_faces(), 1);
  write_text(dir_ / "raw-huge.vtp", one_triangle_raw_vtp(std::int64_t{3'000'000'000}));
  // VTK reads an array with an `offset` attribute from the appended section whatever its `format` says
  // (fuzz_centerline: format="1ppended")
  std::string misspelled = one_triangle_raw_vtp(std::int64_t{3'000'000'000});
  misspelled.replace(misspelled.find("format=\"appended\" offset=\"56\""), 17, "format=\"1ppended\"");
  write_text(dir_ / "raw-misspelled.vtp", misspelled);
  expect_error_naming([&] { read_mesh(dir_ / "raw-misspelled.vtp"); },
                      "Polys offsets end at 3000000000 connectivity values");
  expect_error_naming([&] { read_mesh(dir_ / "raw-huge.vtp"); },
                      "raw-huge.vtp: VTK XML: piece 0: Polys offsets end at 3000000000 connectivity values, "
                      "the connectivity array holds 3");
}

TEST_F(MalformedMesh, VtpWithOutOfRangeIndexOrNanPointIsNamed) {
  SurfaceMesh m;
  m.V.resize(3, 3);
  m.V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  m.F.resize(1, 3);
  m.F << 0, 1, 2;
  auto poly = to_polydata(m);
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetInputData(poly);
  // index 7 of 3 points
  vtkNew<vtkCellArray> bad;
  const vtkIdType ids[3] = {0, 1, 7};
  bad->InsertNextCell(3, ids);
  poly->SetPolys(bad);
  writer->SetFileName((dir_ / "index.vtp").string().c_str());
  ASSERT_EQ(writer->Write(), 1);
  expect_error_naming([&] { read_mesh(dir_ / "index.vtp"); }, "index.vtp: polygon 0 references point 7");
  // NaN coordinate
  poly = to_polydata(m);
  poly->GetPoints()->SetPoint(1, std::numeric_limits<double>::quiet_NaN(), 0, 0);
  writer->SetInputData(poly);
  writer->SetFileName((dir_ / "nan.vtp").string().c_str());
  ASSERT_EQ(writer->Write(), 1);
  expect_error_naming([&] { read_mesh(dir_ / "nan.vtp"); }, "nan.vtp: point 1 has non-finite coordinates");
}

TEST_F(MalformedMesh, LegacyVtkThatIsNotPolyDataIsNamed) {
  vtkNew<vtkUnstructuredGrid> grid;
  vtkNew<vtkPoints> pts;
  pts->InsertNextPoint(0, 0, 0);
  grid->SetPoints(pts);
  vtkNew<vtkUnstructuredGridWriter> writer;
  writer->SetInputData(grid);
  writer->SetFileName((dir_ / "grid.vtk").string().c_str());
  ASSERT_EQ(writer->Write(), 1);
  expect_error_naming([&] { read_mesh(dir_ / "grid.vtk"); },
                      "grid.vtk: legacy VTK file holds UNSTRUCTURED_GRID");
}

}  // namespace
}  // namespace medspring
