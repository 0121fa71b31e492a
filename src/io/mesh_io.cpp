#include "medspring/io/mesh_io.hpp"

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkOBJWriter.h>
#include <vtkPLYWriter.h>
#include <vtkPoints.h>
#include <vtkPolyDataWriter.h>
#include <vtkSTLWriter.h>
#include <vtkPolyData.h>
#include <vtkTriangleFilter.h>

#include <cmath>
#include <fstream>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "vtk_support.hpp"

namespace fs = std::filesystem;

namespace medspring {

namespace io_detail {

MeshReadResult mesh_from_polydata(vtkPolyData* poly, const fs::path& path, MeshFormat format,
                                  const ReadMeshOptions& options) {
  MeshReadResult res;
  res.format = format_name(format);
  res.scale_to_mm = to_mm(options.unit);
  res.file_points = static_cast<Index>(poly->GetNumberOfPoints());
  const vtkIdType polys = poly->GetNumberOfPolys(), strips = poly->GetNumberOfStrips();
  res.file_polygons = static_cast<Index>(polys + strips);
  res.dropped_cells = static_cast<Index>(poly->GetNumberOfLines() + poly->GetNumberOfVerts());
  if (polys + strips == 0)
    throw IoError(cat(name_of(path), ": no polygons (", res.file_points, " points, ",
                      poly->GetNumberOfLines(), " lines, ", poly->GetNumberOfVerts(),
                      " vertex cells): not a surface mesh"));

  Index non_triangles = static_cast<Index>(strips);
  {
    auto it = vtk::TakeSmartPointer(poly->GetPolys()->NewIterator());
    for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
      vtkIdType n = 0;
      const vtkIdType* ids = nullptr;
      it->GetCurrentCell(n, ids);
      if (n != 3) ++non_triangles;
    }
  }
  res.triangulated_polygons = non_triangles;

  vtkSmartPointer<vtkPolyData> tri = poly;
  if (non_triangles > 0) {
    VtkMessageCapture capture;
    // geometry only: the mesh uses no attribute arrays, and vtkTriangleFilter copies them by index
    // without checking their length (an OBJ with more normals than vertices crashed it; fuzz_mesh_obj)
    vtkNew<vtkPolyData> geometry;
    geometry->SetPoints(poly->GetPoints());
    geometry->SetPolys(poly->GetPolys());
    geometry->SetStrips(poly->GetStrips());
    vtkNew<vtkTriangleFilter> filter;
    filter->SetInputData(geometry);
    filter->PassVertsOff();
    filter->PassLinesOff();
    filter->Update();
    capture.throw_if_failed(path, filter);
    tri = filter->GetOutput();
  }

  SurfaceMesh& mesh = res.mesh;
  const vtkIdType np = tri->GetNumberOfPoints();
  mesh.V.resize(static_cast<Index>(np), 3);
  vtkDataArray* coords = tri->GetPoints()->GetData();
  for (vtkIdType i = 0; i < np; ++i)
    for (int c = 0; c < 3; ++c) mesh.V(static_cast<Index>(i), c) = coords->GetComponent(i, c);
  if (const Index bad = first_nonfinite_row(mesh.V); bad >= 0)
    throw IoError(cat(name_of(path), ": point ", bad, " has non-finite coordinates (", mesh.V(bad, 0), ", ",
                      mesh.V(bad, 1), ", ", mesh.V(bad, 2), ")"));
  mesh.V *= res.scale_to_mm;

  std::vector<Index> faces;
  faces.reserve(static_cast<std::size_t>(3 * tri->GetNumberOfPolys()));
  auto it = vtk::TakeSmartPointer(tri->GetPolys()->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    it->GetCurrentCell(n, ids);
    if (n != 3) continue;  // vtkTriangleFilter leaves only triangles; degenerate input cells vanish
    for (int k = 0; k < 3; ++k) faces.push_back(static_cast<Index>(ids[k]));
  }
  mesh.F = Eigen::Map<const MatX3i>(faces.data(), static_cast<Index>(faces.size() / 3), 3);
  if (mesh.num_faces() == 0) throw IoError(cat(name_of(path), ": no triangles after triangulation"));

  if (options.weld) {
    const Index before = mesh.num_vertices();
    weld_vertices(mesh);
    res.merged_vertices = before - mesh.num_vertices();
    if (mesh.num_faces() == 0)
      throw IoError(cat(name_of(path), ": every triangle is degenerate after welding"));
  }
  res.report = validate_mesh(mesh);
  return res;
}

}  // namespace io_detail

using namespace io_detail;

MeshReadResult read_mesh_with_report(const fs::path& path, const ReadMeshOptions& options) {
  const MeshFormat format = mesh_format(path);
  const vtkSmartPointer<vtkPolyData> poly = read_polydata(path, format);
  return mesh_from_polydata(poly, path, format, options);
}

SurfaceMesh read_mesh(const fs::path& path, const ReadMeshOptions& options) {
  return read_mesh_with_report(path, options).mesh;
}

namespace {

vtkSmartPointer<vtkPolyData> mesh_polydata(const SurfaceMesh& mesh,
                                           const std::vector<PointArray>& point_data) {
  require(mesh.num_faces() > 0, "mesh: no triangles to write");
  return make_polydata(mesh.V, &mesh.F, nullptr, point_data);
}

/// Runs a VTK writer on `poly` into `file`, turning its messages and failures into IoError(path).
template <class Writer>
void run_writer(Writer* writer, vtkPolyData* poly, const fs::path& file, const fs::path& target) {
  VtkMessageCapture capture;
  const std::string name = file.string();
  writer->SetFileName(name.c_str());
  writer->SetInputData(poly);
  const int ok = writer->Write();
  capture.throw_if_failed(target, writer);
  if (!ok) throw IoError(cat(name_of(target), ": ", writer->GetClassName(), " failed"));
}

}  // namespace

void write_vtp(const fs::path& path, const SurfaceMesh& mesh, const std::vector<PointArray>& point_data) {
  const auto poly = mesh_polydata(mesh, point_data);
  atomic_write(path, [&](const fs::path& tmp) { write_vtp_file(tmp, poly, path); });
}

void write_obj(const fs::path& path, const SurfaceMesh& mesh) {
  const auto poly = mesh_polydata(mesh, {});
  atomic_write(path, [&](const fs::path& tmp) {
    vtkNew<vtkOBJWriter> writer;
    run_writer(writer.Get(), poly, tmp, path);
  });
}

void write_mesh(const fs::path& path, const SurfaceMesh& mesh) {
  switch (mesh_format(path)) {
    case MeshFormat::Vtp:
      write_vtp(path, mesh);
      return;
    case MeshFormat::Obj:
      write_obj(path, mesh);
      return;
    case MeshFormat::Stl: {
      const auto poly = mesh_polydata(mesh, {});
      atomic_write(path, [&](const fs::path& tmp) {
        vtkNew<vtkSTLWriter> writer;
        writer->SetFileTypeToBinary();
        run_writer(writer.Get(), poly, tmp, path);
      });
      return;
    }
    case MeshFormat::Ply: {
      const auto poly = mesh_polydata(mesh, {});
      atomic_write(path, [&](const fs::path& tmp) {
        vtkNew<vtkPLYWriter> writer;
        writer->SetFileTypeToBinary();
        run_writer(writer.Get(), poly, tmp, path);
      });
      return;
    }
    case MeshFormat::Vtk: {
      const auto poly = mesh_polydata(mesh, {});
      atomic_write(path, [&](const fs::path& tmp) {
        vtkNew<vtkPolyDataWriter> writer;
        writer->SetFileTypeToBinary();
        run_writer(writer.Get(), poly, tmp, path);
      });
      return;
    }
  }
}

void write_polyline_vtp(const fs::path& path, const MatX3& points,
                        const std::vector<std::vector<Index>>& lines,
                        const std::vector<PointArray>& point_data) {
  const auto poly = make_polydata(points, nullptr, &lines, point_data);
  atomic_write(path, [&](const fs::path& tmp) { write_vtp_file(tmp, poly, path); });
}

void write_segments_vtp(const fs::path& path, const MatX3& points, const MatX2i& segments,
                        const std::vector<PointArray>& point_data) {
  std::vector<std::vector<Index>> lines(static_cast<std::size_t>(segments.rows()));
  for (Index s = 0; s < segments.rows(); ++s)
    lines[static_cast<std::size_t>(s)] = {segments(s, 0), segments(s, 1)};
  write_polyline_vtp(path, points, lines, point_data);
}

namespace {

std::string xml_escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace

void write_pvd(const fs::path& path, const std::vector<std::pair<double, std::string>>& time_and_file) {
  for (std::size_t i = 0; i < time_and_file.size(); ++i) {
    require_finite(time_and_file[i].first, cat("pvd entry ", i, ": time"));
    require(!time_and_file[i].second.empty(), "pvd entry ", i, ": file name must not be empty");
  }
  atomic_write(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError(cat(name_of(path), ": cannot open for writing"));
    out.precision(17);
    out << "<?xml version=\"1.0\"?>\n"
        << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
        << "  <Collection>\n";
    for (const auto& [t, file] : time_and_file)
      out << "    <DataSet timestep=\"" << t << "\" group=\"\" part=\"0\" file=\"" << xml_escape(file)
          << "\"/>\n";
    out << "  </Collection>\n"
        << "</VTKFile>\n";
    out.close();
    if (!out) throw IoError(cat(name_of(path), ": write failed"));
  });
}

}  // namespace medspring
