// Malformed mesh files (io/mesh_io.hpp): missing, empty and unknown files; OBJ, STL, PLY and legacy VTK
// syntax errors, each named with the file (and line). VTK XML: mesh_io_vtp_test.cpp.
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
#include "medspring/io/mesh_io.hpp"
#include "mesh_io_test_util.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;
using testing::expect_error_naming;
using testing::to_polydata;
using testing::write_text;
using MalformedMesh = testing::MalformedMeshTest;

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
