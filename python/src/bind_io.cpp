// I/O layer (VTK at the edge): meshes, centerlines, label volumes, the data folder, file summaries.
// Paths are str or os.PathLike; units are a LengthUnit or its name ("mm", "cm", "m", "um").
#include "bind_common.hpp"
#include "medspring/core/units.hpp"
#include "medspring/io/centerline_io.hpp"
#include "medspring/io/data_dir.hpp"
#include "medspring/io/info.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/io/volume_io.hpp"

namespace medspring::python {

using namespace pybind11::literals;

namespace {

LengthUnit parse_unit(const std::string& text) {
  return parse_length_unit(text);
}

// {"name": array} with (V,) scalars or (V, 3) vectors per point.
std::vector<PointArray> point_arrays(py::handle obj, Index rows) {
  std::vector<PointArray> out;
  if (obj.is_none()) return out;
  if (!py::isinstance<py::dict>(obj))
    throw InvalidInput(cat("point_data: expected a dict {name: array of shape (", rows, ",) or (", rows,
                           ", 3)}; got ", describe_object(obj)));
  for (auto item : py::reinterpret_borrow<py::dict>(obj)) {
    const std::string name = py::str(item.first).cast<std::string>();
    const std::string what = "point_data['" + name + "']";
    py::array a = py::module_::import("numpy").attr("asarray")(item.second);
    if (a.ndim() == 2) {
      out.emplace_back(name, points_arg(item.second, what, rows, "V"));
    } else {
      out.emplace_back(name, vector_arg(item.second, what, rows, "V"));
    }
  }
  return out;
}

}  // namespace

void bind_io(py::module_& m) {
  py::enum_<LengthUnit> unit_cls(
      m, "LengthUnit",
      "Length unit of a file's coordinates (scaled to mm on load). Strings 'mm', 'cm', "
      "'m', 'um' are accepted.");
  unit_cls.value("Millimetre", LengthUnit::Millimetre)
      .value("Centimetre", LengthUnit::Centimetre)
      .value("Metre", LengthUnit::Metre)
      .value("Micrometre", LengthUnit::Micrometre);
  enum_accepts_strings(unit_cls, &parse_unit);
  m.def("to_mm", &to_mm, "unit"_a, "Millimetres per unit: mm -> 1, cm -> 10, m -> 1000, um -> 0.001.");

  // ---- Data folder ----
  m.def("data_dir", &data_dir,
        "$MEDSPRING_DATA when set and non-empty, else the folder configured at build time (not checked).");
  m.def("find_data_file", &find_data_file, "name"_a,
        "data_dir() / name when that file exists; raises IoError otherwise.");

  // ---- Meshes ----
  py::class_<MeshReadResult>(m, "MeshReadResult", "Everything read_mesh_with_report found in a file.")
      .def_readonly("mesh", &MeshReadResult::mesh, "SurfaceMesh, mm.")
      .def_readonly("report", &MeshReadResult::report, "MeshReport.")
      .def_readonly("format", &MeshReadResult::format, "'OBJ', 'STL', 'PLY', 'VTP' or 'VTK'.")
      .def_readonly("file_points", &MeshReadResult::file_points, "Points stored in the file.")
      .def_readonly("file_polygons", &MeshReadResult::file_polygons, "Polygon and strip cells in the file.")
      .def_readonly("triangulated_polygons", &MeshReadResult::triangulated_polygons,
                    "Cells that were not triangles (split).")
      .def_readonly("dropped_cells", &MeshReadResult::dropped_cells, "Line and vertex cells ignored.")
      .def_readonly("merged_vertices", &MeshReadResult::merged_vertices, "Vertices removed by welding.")
      .def_readonly("scale_to_mm", &MeshReadResult::scale_to_mm, "Factor applied to the file's coordinates.");
  m.def(
      "read_mesh_with_report",
      [](const std::filesystem::path& path, py::handle unit_obj, bool weld) {
        return read_mesh_with_report(path, {.unit = enum_arg<LengthUnit>(unit_obj, "unit"), .weld = weld});
      },
      "path"_a, "unit"_a = LengthUnit::Millimetre, "weld"_a = true,
      "Reads a triangle mesh (.obj .stl .ply .vtp .vtk), scales it from `unit` to mm and welds coincident "
      "vertices; returns a MeshReadResult. Raises IoError naming the file.");
  m.def(
      "read_mesh",
      [](const std::filesystem::path& path, py::handle unit_obj, bool weld) {
        return read_mesh(path, {.unit = enum_arg<LengthUnit>(unit_obj, "unit"), .weld = weld});
      },
      "path"_a, "unit"_a = LengthUnit::Millimetre, "weld"_a = true,
      "Reads a triangle mesh scaled to mm (see read_mesh_with_report). Raises IoError naming the file.");
  m.def(
      "write_vtp",
      [](const std::filesystem::path& path, const SurfaceMesh& mesh, py::handle point_data) {
        write_vtp(path, mesh, point_arrays(point_data, mesh.num_vertices()));
      },
      "path"_a, "mesh"_a, "point_data"_a = py::none(),
      "Writes a mesh as VTK XML PolyData with optional point arrays {name: (V,) or (V, 3)}; atomic.");
  m.def("write_obj", &write_obj, "path"_a, "mesh"_a, "Writes a mesh as Wavefront OBJ; atomic.");
  m.def("write_mesh", &write_mesh, "path"_a, "mesh"_a,
        "Writes a mesh in the format of the extension (.vtp .obj .stl .ply .vtk); atomic.");
  m.def(
      "write_polyline_vtp",
      [](const std::filesystem::path& path, py::handle points, const std::vector<std::vector<Index>>& lines,
         py::handle point_data) {
        const MatX3 P = points_arg(points, "points");
        write_polyline_vtp(path, P, lines, point_arrays(point_data, static_cast<Index>(P.rows())));
      },
      "path"_a, "points"_a, "lines"_a, "point_data"_a = py::none(),
      "Writes polylines: points (P, 3) mm, lines a list of index lists (>= 2 each), optional point arrays.");
  m.def(
      "write_segments_vtp",
      [](const std::filesystem::path& path, py::handle points, py::handle segments, py::handle point_data) {
        const MatX3 P = points_arg(points, "points");
        write_segments_vtp(path, P, edges_arg(segments, "segments", static_cast<Index>(P.rows())),
                           point_arrays(point_data, static_cast<Index>(P.rows())));
      },
      "path"_a, "points"_a, "segments"_a, "point_data"_a = py::none(),
      "Writes one two-point line per row of segments (S, 2).");
  m.def("write_pvd", &write_pvd, "path"_a, "time_and_file"_a,
        "Writes a ParaView collection (.pvd) of (time, file name) pairs; atomic.");

  // ---- Centerlines ----
  m.def(
      "read_centerlines",
      [](const std::filesystem::path& path, py::handle unit_obj, const std::string& radius_array) {
        return read_centerlines(path, enum_arg<LengthUnit>(unit_obj, "unit"), radius_array);
      },
      "path"_a, "unit"_a = LengthUnit::Millimetre, "radius_array"_a = "MaximumInscribedSphereRadius",
      "Reads every polyline of a .vtp / .vtk file as a Centerline (points and radii scaled to mm). Raises "
      "IoError naming the file.");
  m.def("write_centerlines", &write_centerlines, "path"_a, "lines"_a,
        "radius_array"_a = "MaximumInscribedSphereRadius",
        "Writes centerlines (mm) as VTK XML PolyData; atomic.");

  // ---- Volumes ----
  m.def(
      "read_label_volume",
      [](const std::filesystem::path& path, std::optional<double> threshold) {
        ReadVolumeOptions o;
        if (threshold) o.threshold = *threshold;
        return read_label_volume(path, o);
      },
      "path"_a, "threshold"_a = py::none(),
      "Reads a 3-D label volume (.nii .nii.gz .mha .mhd .nrrd .nhdr) in RAS+ mm; with a threshold the "
      "volume is binarised (1 where value >= threshold). Raises IoError naming the file.");
  m.def("write_label_volume", &write_label_volume, "path"_a, "volume"_a,
        "Writes a label volume as MetaImage (.mha, zlib-compressed, ITK's LPS frame); atomic.");

  // ---- File summaries ----
  py::class_<FileInfo>(m, "FileInfo", "A one-screen summary of a mesh, volume or centerline file.")
      .def_property_readonly(
          "path", [](const FileInfo& i) { return i.path; }, "The file.")
      .def_readonly("kind", &FileInfo::kind, "'mesh', 'volume' or 'centerlines'.")
      .def_readonly("format", &FileInfo::format,
                    "'OBJ', 'STL', 'PLY', 'VTP', 'VTK', 'NIfTI', 'MetaImage' or 'NRRD'.")
      .def_readonly("unit", &FileInfo::unit, "Unit the coordinates were read in (values below are in mm).")
      .def_readonly("load_ms", &FileInfo::load_ms, "Wall time to read and analyse the file, ms.")
      .def("text", &FileInfo::text, "Human-readable summary.")
      .def("to_json", &FileInfo::to_json, "The same content as one JSON object (str).")
      .def("__str__", &FileInfo::text);
  m.def(
      "describe_file",
      [](const std::filesystem::path& path, py::handle unit_obj, const std::string& radius_array) {
        const DescribeOptions options{.unit = enum_arg<LengthUnit>(unit_obj, "unit"),
                                      .radius_array = radius_array};
        py::gil_scoped_release release;
        return describe_file(path, options);
      },
      "path"_a, "unit"_a = LengthUnit::Millimetre, "radius_array"_a = "MaximumInscribedSphereRadius",
      "Reads a mesh, volume or centerline file and summarises it (FileInfo; .to_json() for a dict via "
      "json.loads). Raises IoError naming the file.");
}

}  // namespace medspring::python
