// Helpers of the mesh reader/writer tests (mesh_io_test.cpp, mesh_io_malformed_test.cpp,
// mesh_io_vtp_test.cpp): a SurfaceMesh as VTK polydata, and the fixture of the malformed-input tests.
#pragma once

#include <gtest/gtest.h>
#include <vtkCellArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <filesystem>

#include "medspring/geometry/surface_mesh.hpp"
#include "test_support.hpp"

namespace medspring::testing {

inline vtkSmartPointer<vtkPolyData> to_polydata(const SurfaceMesh& m) {
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

/// The fixture of the MalformedMesh tests (one type for the files that share the suite): a fresh
/// temporary folder.
class MalformedMeshTest : public ::testing::Test {
 protected:
  std::filesystem::path dir_ = temp_dir("io-bad");
};

}  // namespace medspring::testing
