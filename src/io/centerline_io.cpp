#include "medspring/io/centerline_io.hpp"

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkDataArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>

#include <cmath>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/io/mesh_io.hpp"
#include "vtk_support.hpp"

namespace fs = std::filesystem;

namespace medspring {

namespace io_detail {

std::vector<Centerline> centerlines_from_polydata(vtkPolyData* poly, const fs::path& path, double scale,
                                                  const std::string& radius_array, bool require_radius,
                                                  bool* found_radius) {
  const std::string file = name_of(path);
  if (poly->GetNumberOfLines() == 0)
    throw IoError(cat(file, ": no line cells (", poly->GetNumberOfPoints(), " points, ",
                      poly->GetNumberOfPolys(), " polygons): not a centerline file"));
  vtkPointData* pd = poly->GetPointData();
  vtkDataArray* radius = pd->GetArray(radius_array.c_str());
  if (!radius && require_radius) {
    std::string names;
    for (int a = 0; a < pd->GetNumberOfArrays(); ++a)
      names += cat(a ? ", " : "", "'", pd->GetArrayName(a) ? pd->GetArrayName(a) : "(unnamed)", "'");
    throw IoError(cat(file, ": no point array '", radius_array, "' (",
                      names.empty() ? std::string("the file has no point arrays") : "point arrays: " + names,
                      ")"));
  }
  if (radius && radius->GetNumberOfComponents() != 1)
    throw IoError(cat(file, ": point array '", radius_array, "' has ", radius->GetNumberOfComponents(),
                      " components; a radius needs 1"));
  if (found_radius) *found_radius = radius != nullptr;

  vtkDataArray* coords = poly->GetPoints()->GetData();
  std::vector<Centerline> lines;
  auto it = vtk::TakeSmartPointer(poly->GetLines()->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    it->GetCurrentCell(n, ids);
    const auto l = static_cast<Index>(lines.size());
    if (n < 2)
      throw IoError(
          cat(file, ": line ", l, " has ", n, " point", n == 1 ? "" : "s", "; a centerline needs 2"));
    Centerline c;
    c.name = cat("line ", l);
    c.points.resize(static_cast<Index>(n), 3);
    if (radius) c.radii.resize(static_cast<Index>(n));
    for (vtkIdType k = 0; k < n; ++k) {
      const auto i = static_cast<Index>(k);
      for (int d = 0; d < 3; ++d) c.points(i, d) = coords->GetComponent(ids[k], d) * scale;
      if (!c.points.row(i).allFinite())
        throw IoError(
            cat(file, ": line ", l, ", point ", k, " (point id ", ids[k], "): non-finite coordinates"));
      if (radius) {
        const double r = radius->GetComponent(ids[k], 0);
        if (!(std::isfinite(r) && r > 0))
          throw IoError(cat(file, ": line ", l, ", point ", k, " (point id ", ids[k], "): radius '",
                            radius_array, "' must be > 0 (got ", r, ")"));
        c.radii(i) = r * scale;
      }
    }
    lines.push_back(std::move(c));
  }
  return lines;
}

}  // namespace io_detail

using namespace io_detail;

std::vector<Centerline> read_centerlines(const fs::path& path, LengthUnit unit,
                                         const std::string& radius_array) {
  const std::string ext = lower_extension(path);
  if (ext != ".vtp" && ext != ".vtk")
    throw IoError(cat(name_of(path), ": unknown centerline file extension '", ext,
                      "' (centerlines are read from .vtp or .vtk PolyData files)"));
  const MeshFormat format = ext == ".vtp" ? MeshFormat::Vtp : MeshFormat::Vtk;
  const auto poly = read_polydata(path, format);
  return centerlines_from_polydata(poly, path, to_mm(unit), radius_array, true);
}

void write_centerlines(const fs::path& path, const std::vector<Centerline>& lines,
                       const std::string& radius_array) {
  require(!radius_array.empty(), "write_centerlines: radius array name must not be empty");
  Index total = 0;
  for (std::size_t l = 0; l < lines.size(); ++l) {
    require(lines[l].size() >= 2, "centerline ", l, ": needs at least 2 points, got ", lines[l].size());
    require(lines[l].radii.size() == lines[l].size(), "centerline ", l, ": ", lines[l].radii.size(),
            " radii for ", lines[l].size(), " points");
    total += lines[l].size();
  }
  MatX3 points(total, 3);
  VecX radii(total);
  std::vector<std::vector<Index>> cells(lines.size());
  Index next = 0;
  for (std::size_t l = 0; l < lines.size(); ++l) {
    const Index n = lines[l].size();
    points.middleRows(next, n) = lines[l].points;
    radii.segment(next, n) = lines[l].radii;
    for (Index k = 0; k < n; ++k) cells[l].push_back(next + k);
    next += n;
  }
  write_polyline_vtp(path, points, cells, {{radius_array, radii}});
}

}  // namespace medspring
