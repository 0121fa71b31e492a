// Private helpers of the io layer: VTK message capture, file checks, atomic writes, conversions.
// Not installed; only src/io includes it.
#pragma once

#include <vtkAlgorithm.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <filesystem>
#include <functional>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/core/types.hpp"
#include "medspring/geometry/polyline.hpp"
#include "medspring/io/mesh_io.hpp"

namespace medspring::io_detail {

/// Collects every message VTK emits on this thread while alive (errors, warnings), instead of
/// printing them. The first use installs a vtkOutputWindow that routes text to the innermost active
/// capture of the calling thread (and drops it when there is none) and turns vtkLogger's stderr
/// output off, so VTK never writes to stderr.
class VtkMessageCapture {
 public:
  VtkMessageCapture();
  ~VtkMessageCapture();
  VtkMessageCapture(const VtkMessageCapture&) = delete;
  VtkMessageCapture& operator=(const VtkMessageCapture&) = delete;

  void add(bool error, const char* text);
  bool has_errors() const { return !errors_.empty(); }
  const std::vector<std::string>& errors() const { return errors_; }
  const std::vector<std::string>& warnings() const { return warnings_; }
  /// The most useful error as one line: the first one not from the pipeline executive, stripped of
  /// VTK's source-file prefix and object address, e.g. "vtkSTLReader: Premature EOF while reading
  /// header". Empty when there was none.
  std::string first_error() const;

  /// Throws IoError("<file>: <first error>") when VTK reported an error or `algorithm` has a non-zero
  /// error code.
  void throw_if_failed(const std::filesystem::path& file, vtkAlgorithm* algorithm = nullptr) const;

 private:
  std::vector<std::string> errors_, warnings_;
  VtkMessageCapture* outer_ = nullptr;
};

/// Runs `f` (calls into VTK) and returns its result; a C++ exception thrown inside VTK (std::length_error
/// or std::bad_alloc from a size read from the file) becomes IoError naming the file.
template <class F>
auto guard_vtk(const std::filesystem::path& file, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const Error&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw IoError(cat(file.string(), ": out of memory reading the file (a size in it is too large)"));
  } catch (const std::exception& e) {
    throw IoError(cat(file.string(), ": ", e.what()));
  }
}

/// Lower-case extension with the dot; ".nii.gz" (and ".img.gz", ...) counted as one: "mesh.OBJ" ->
/// ".obj", "mask.nii.gz" -> ".nii.gz".
std::string lower_extension(const std::filesystem::path& path);

/// Path as text for messages.
inline std::string name_of(const std::filesystem::path& path) {
  return path.string();
}

/// Throws IoError unless `path` is an existing regular file; returns its size in bytes.
std::uintmax_t require_input_file(const std::filesystem::path& path);

/// Writes through a temporary "<path>.tmp-<pid><ext>" in the same folder (e.g. "a.vtp.tmp-42.vtp"),
/// then renames it to `path`.
/// `write` gets the temporary path and must throw on failure. On any failure the temporary is
/// removed and the target is left untouched. Throws IoError when the folder does not exist.
void atomic_write(const std::filesystem::path& path,
                  const std::function<void(const std::filesystem::path&)>& write);

/// Mesh file formats known by extension.
enum class MeshFormat { Obj, Stl, Ply, Vtp, Vtk };
/// Format of a mesh path by extension, or throws IoError naming the accepted extensions.
MeshFormat mesh_format(const std::filesystem::path& path, const char* what = "mesh");
const char* format_name(MeshFormat format);

/// Reads a PolyData file (any MeshFormat) with VTK after the format's pre-checks (OBJ syntax and
/// index ranges, binary STL size); checks that every cell index is in range. Throws IoError.
vtkSmartPointer<vtkPolyData> read_polydata(const std::filesystem::path& path, MeshFormat format);

/// Checks an OBJ file line by line where vtkOBJReader accepts garbage silently: non-numeric or
/// non-finite coordinates, face/line/point indices (and texture/normal indices) out of range, faces
/// of fewer than 3 vertices. Throws IoError "<file>:<line>: ...".
void check_obj_syntax(const std::filesystem::path& path);

/// Checks that a binary STL holds as many bytes as its triangle count says (VTK reads a truncated
/// file without complaint). ASCII STL is left to VTK.
void check_stl_size(const std::filesystem::path& path, std::uintmax_t size);

/// Polydata with double points and the given triangles / polylines, plus point arrays. Throws
/// InvalidInput for indices out of range or arrays of the wrong length.
vtkSmartPointer<vtkPolyData> make_polydata(const MatX3& points, const MatX3i* triangles,
                                           const std::vector<std::vector<Index>>* lines,
                                           const std::vector<PointArray>& point_data);

/// Writes polydata as .vtp (binary, zlib-compressed, appended) into `file` (not atomic by itself);
/// errors name `target` (the file the user asked for).
void write_vtp_file(const std::filesystem::path& file, vtkPolyData* poly,
                    const std::filesystem::path& target);

/// The conversion of read_mesh_with_report after reading (triangulate, drop, scale, check, weld).
MeshReadResult mesh_from_polydata(vtkPolyData* poly, const std::filesystem::path& path, MeshFormat format,
                                  const ReadMeshOptions& options);

/// The line cells of a polydata as centerlines (see read_centerlines), scaled by `scale`. With
/// require_radius false a missing radius array gives centerlines with empty radii instead of an
/// error; *found_radius (if given) tells which.
std::vector<Centerline> centerlines_from_polydata(vtkPolyData* poly, const std::filesystem::path& path,
                                                  double scale, const std::string& radius_array,
                                                  bool require_radius, bool* found_radius = nullptr);

}  // namespace medspring::io_detail
