// Surface mesh files in and out: OBJ, STL (ASCII and binary), PLY, VTK XML PolyData (.vtp) and legacy
// VTK (.vtk, POLYDATA). Reading and writing go through VTK's readers and writers; VTK stays private
// to the io layer (this header uses only engine types).
//
//   SurfaceMesh kidney = read_mesh(find_data_file("kidney_left_hubmap_vhm.obj"), {.unit =
//   LengthUnit::Metre}); write_vtp("kidney.vtp", kidney, {{"displacement", U}, {"magnitude",
//   U.rowwise().norm()}});
//
// Errors: every function throws IoError whose message starts with the file name (and "file:line"
// where the line is known) for a missing file, an unknown extension, unreadable or malformed content,
// non-finite coordinates, out-of-range indices, or an empty result; InvalidInput for bad arguments
// (e.g. a point array whose row count is not the vertex count). VTK never prints to stderr: its
// messages become the text of the exception.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "medspring/core/units.hpp"
#include "medspring/geometry/surface_mesh.hpp"

namespace medspring {

struct ReadMeshOptions {
  /// Length unit of the file's coordinates; they are scaled to millimetres on load.
  LengthUnit unit = LengthUnit::Millimetre;
  /// Merge coincident vertices (weld_vertices with its default tolerance, 1e-9 x bbox diagonal) and
  /// drop unreferenced ones. STL stores every triangle's corners separately, so it needs this.
  bool weld = true;
};

/// Everything read_mesh_with_report found in a file besides the mesh.
struct MeshReadResult {
  SurfaceMesh mesh;                 // triangles, mm
  MeshReport report;                // validate_mesh(mesh)
  std::string format;               // "OBJ", "STL", "PLY", "VTP", "VTK"
  Index file_points = 0;            // points stored in the file
  Index file_polygons = 0;          // polygon and triangle-strip cells in the file
  Index triangulated_polygons = 0;  // of those, cells that were not triangles (split by vtkTriangleFilter)
  Index dropped_cells = 0;          // line and vertex cells, which a surface cannot use
  Index merged_vertices = 0;        // vertices removed by welding (duplicates and unreferenced)
  double scale_to_mm = 1.0;         // factor applied to the file's coordinates
};

/// Reads a triangle mesh, choosing the reader by extension (case-insensitive): .obj .stl .ply .vtp
/// .vtk. Polygons and strips are triangulated, lines and vertex cells dropped (counted), coordinates
/// scaled to mm, and vertices welded when options.weld is set. Throws IoError (see the file comment).
/// The mesh is not required to be closed or manifold: the report says what it is.
MeshReadResult read_mesh_with_report(const std::filesystem::path& path, const ReadMeshOptions& options = {});

/// read_mesh_with_report(path, options).mesh.
SurfaceMesh read_mesh(const std::filesystem::path& path, const ReadMeshOptions& options = {});

/// A named per-point array written alongside a mesh or polyline: #N scalars or #N x 3 vectors
/// (displacements, normals, ...).
struct PointArray {
  std::string name;
  std::variant<VecX, MatX3> values;

  PointArray() = default;
  /// From any Eigen vector (one column: scalars) or #N x 3 matrix expression, e.g.
  /// {"magnitude", U.rowwise().norm()}.
  template <class Derived>
  PointArray(std::string array_name, const Eigen::MatrixBase<Derived>& v) : name(std::move(array_name)) {
    if constexpr (Derived::ColsAtCompileTime == 1)
      values = VecX(v);
    else
      values = MatX3(v);
  }
};

/// Writes a triangle mesh as VTK XML PolyData (Float64 points, zlib-compressed binary) with optional
/// point arrays (each with #V rows). Atomic: the file is written to "<path>.tmp-<pid><ext>" in the
/// same folder and renamed into place; on failure nothing is left behind and an existing file at
/// `path` is untouched. Throws IoError (e.g. the folder does not exist) or
/// InvalidInput (invalid mesh indices, array size mismatch, empty or repeated array name).
void write_vtp(const std::filesystem::path& path, const SurfaceMesh& mesh,
               const std::vector<PointArray>& point_data = {});

/// Writes a triangle mesh as Wavefront OBJ (vtkOBJWriter; full double precision in the text).
/// Atomic like write_vtp.
void write_obj(const std::filesystem::path& path, const SurfaceMesh& mesh);

/// Writes a triangle mesh in the format named by the extension: .vtp, .obj, .stl (binary), .ply
/// (binary), .vtk (legacy binary). Atomic like write_vtp.
void write_mesh(const std::filesystem::path& path, const SurfaceMesh& mesh);

/// Writes polylines (centerlines, spokes) as VTK XML PolyData: `points` (#P x 3, mm), each entry of
/// `lines` one polyline of point indices (>= 2 of them; a segment is a line of two), optional point
/// arrays with #P rows. Atomic like write_vtp.
void write_polyline_vtp(const std::filesystem::path& path, const MatX3& points,
                        const std::vector<std::vector<Index>>& lines,
                        const std::vector<PointArray>& point_data = {});

/// write_polyline_vtp with one two-point line per row of `segments` (#S x 2 point indices).
void write_segments_vtp(const std::filesystem::path& path, const MatX3& points, const MatX2i& segments,
                        const std::vector<PointArray>& point_data = {});

/// Writes a ParaView collection (.pvd) listing (time, file) pairs, file names as given (relative
/// names are resolved by ParaView against the .pvd's folder). Atomic like write_vtp.
void write_pvd(const std::filesystem::path& path,
               const std::vector<std::pair<double, std::string>>& time_and_file);

}  // namespace medspring
