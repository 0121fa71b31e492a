#include "medspring/io/info.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/io/centerline_io.hpp"
#include "medspring/io/volume_io.hpp"
#include "vtk_support.hpp"

namespace fs = std::filesystem;

namespace medspring {

using namespace io_detail;

int MeshInfo::genus() const {
  if (!report.closed() || !report.manifold() || report.components != 1) return -1;
  return (2 - report.euler_characteristic) / 2;
}

namespace {

Box3 box_of(const MatX3& P) {
  Box3 b;
  if (P.rows() == 0) return b;
  b.min = P.colwise().minCoeff().transpose();
  b.max = P.colwise().maxCoeff().transpose();
  return b;
}

MeshInfo mesh_info(const MeshReadResult& r) {
  MeshInfo m;
  m.report = r.report;
  m.bounds = box_of(r.mesh.V);
  m.volume = signed_volume(r.mesh.V, r.mesh.F);
  m.area = surface_area(r.mesh.V, r.mesh.F);
  const MatX2i E = unique_edges(r.mesh.F);
  if (E.rows() > 0) {
    m.edge_min = std::numeric_limits<double>::infinity();
    double sum = 0;
    for (Index e = 0; e < E.rows(); ++e) {
      const double L = (r.mesh.V.row(E(e, 1)) - r.mesh.V.row(E(e, 0))).norm();
      m.edge_min = std::min(m.edge_min, L);
      m.edge_max = std::max(m.edge_max, L);
      sum += L;
    }
    m.edge_mean = sum / static_cast<double>(E.rows());
  }
  m.dropped_cells = r.dropped_cells;
  m.triangulated_polygons = r.triangulated_polygons;
  m.merged_vertices = r.merged_vertices;
  return m;
}

VolumeInfo volume_info(const LabelVolume& v) {
  VolumeInfo info;
  info.dims = v.dims;
  info.spacing = v.spacing;
  info.origin = v.origin;
  info.direction = v.direction;
  MatX3 corners(8, 3);
  for (int c = 0; c < 8; ++c)
    corners.row(c) = v.to_world(Vec3((c & 1) ? v.dims[0] - 1 : 0, (c & 2) ? v.dims[1] - 1 : 0,
                                     (c & 4) ? v.dims[2] - 1 : 0))
                         .transpose();
  info.bounds = box_of(corners);
  std::map<std::int32_t, std::int64_t> counts;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  std::size_t i = 0;
  for (Index k = 0; k < v.dims[2]; ++k)
    for (Index j = 0; j < v.dims[1]; ++j)
      for (Index x = 0; x < v.dims[0]; ++x, ++i) {
        const std::int32_t label = v.data[i];
        ++counts[label];
        if (label != 0) {
          const Vec3 p = v.to_world(Vec3(x, j, k));
          lo = lo.cwiseMin(p);
          hi = hi.cwiseMax(p);
        }
      }
  info.label_counts.assign(counts.begin(), counts.end());
  for (const auto& [label, n] : counts)
    if (label != 0) info.foreground_voxels += n;
  if (info.foreground_voxels > 0) info.foreground_bounds = {lo, hi};
  info.foreground_volume = static_cast<double>(info.foreground_voxels) * v.spacing.prod();
  return info;
}

CenterlineInfo centerline_info(const std::vector<Centerline>& lines, const std::string& radius_array,
                               bool radius) {
  CenterlineInfo c;
  c.radius_array = radius ? radius_array : std::string();
  c.radius_min = std::numeric_limits<double>::infinity();
  c.radius_max = 0;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& l : lines) {
    c.points_per_line.push_back(l.size());
    c.line_lengths.push_back(l.length());
    c.total_points += l.size();
    const Box3 b = box_of(l.points);
    lo = lo.cwiseMin(b.min);
    hi = hi.cwiseMax(b.max);
    if (radius && l.radii.size() > 0) {
      c.radius_min = std::min(c.radius_min, l.radii.minCoeff());
      c.radius_max = std::max(c.radius_max, l.radii.maxCoeff());
    }
  }
  if (!radius) c.radius_min = 0;
  if (!lines.empty()) c.bounds = {lo, hi};
  return c;
}

// --- text -------------------------------------------------------------------------------------------

std::string fixed(double x, int digits = 1) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << x;
  return os.str();
}

std::string vec(const Vec3& v, int digits = 1) {
  return cat("(", fixed(v(0), digits), ", ", fixed(v(1), digits), ", ", fixed(v(2), digits), ")");
}

std::string box_text(const Box3& b) {
  const Vec3 s = b.size();
  return cat("min ", vec(b.min), " max ", vec(b.max), ", size ", fixed(s(0)), " x ", fixed(s(1)), " x ",
             fixed(s(2)), " mm");
}

template <class T>
std::string join(const std::vector<T>& values, const std::string& sep, int digits = -1) {
  std::string out;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i) out += sep;
    if constexpr (std::is_floating_point_v<T>)
      out += digits >= 0 ? fixed(values[i], digits) : cat(values[i]);
    else
      out += cat(values[i]);
  }
  return out;
}

// --- JSON -------------------------------------------------------------------------------------------

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += ch;
        }
    }
  }
  return out + "\"";
}

std::string json_number(double x) {
  if (!std::isfinite(x)) return "null";
  std::ostringstream os;
  os << std::setprecision(12) << x;
  return os.str();
}

std::string json_vec(const Vec3& v) {
  return cat("[", json_number(v(0)), ", ", json_number(v(1)), ", ", json_number(v(2)), "]");
}

std::string json_box(const Box3& b) {
  return cat("{\"min\": ", json_vec(b.min), ", \"max\": ", json_vec(b.max),
             ", \"size\": ", json_vec(b.size()), "}");
}

const char* json_bool(bool b) {
  return b ? "true" : "false";
}

}  // namespace

std::string FileInfo::text() const {
  std::ostringstream os;
  os << path.filename().string() << ": " << kind << " (" << format << "), coordinates read in " << unit
     << ", shown in mm; read in " << fixed(load_ms, 1) << " ms\n";
  if (mesh) {
    const MeshReport& r = mesh->report;
    os << "  " << r.summary() << "\n";
    os << "  Euler characteristic " << r.euler_characteristic;
    if (mesh->genus() >= 0) os << " (genus " << mesh->genus() << ")";
    os << ", " << (r.valid() ? "valid" : "NOT valid") << " for simulation\n";
    if (!r.first_problem.empty()) os << "  first problem: " << r.first_problem << "\n";
    os << "  bounds " << box_text(mesh->bounds) << "\n";
    os << "  volume " << fixed(mesh->volume / 1000.0, 2) << " cm^3 (signed; "
       << (r.closed() ? "closed" : "open") << " surface), area " << fixed(mesh->area / 100.0, 2) << " cm^2\n";
    os << "  edge length min " << fixed(mesh->edge_min, 3) << ", mean " << fixed(mesh->edge_mean, 3)
       << ", max " << fixed(mesh->edge_max, 3) << " mm\n";
    os << "  on read: " << mesh->dropped_cells << " line/vertex cells dropped, "
       << mesh->triangulated_polygons << " polygons triangulated, " << mesh->merged_vertices
       << " vertices merged\n";
  }
  if (volume) {
    const VolumeInfo& v = *volume;
    os << "  " << v.dims[0] << " x " << v.dims[1] << " x " << v.dims[2] << " voxels, spacing "
       << fixed(v.spacing(0), 3) << " x " << fixed(v.spacing(1), 3) << " x " << fixed(v.spacing(2), 3)
       << " mm (RAS world frame)\n";
    os << "  origin " << vec(v.origin, 2) << " mm, axis directions " << vec(v.direction.col(0), 3) << " "
       << vec(v.direction.col(1), 3) << " " << vec(v.direction.col(2), 3) << "\n";
    os << "  voxel centres " << box_text(v.bounds) << "\n";
    os << "  labels (" << v.label_counts.size() << "):";
    const std::size_t show = std::min<std::size_t>(v.label_counts.size(), 8);
    for (std::size_t i = 0; i < show; ++i)
      os << (i ? ", " : " ") << v.label_counts[i].first << ": " << v.label_counts[i].second;
    if (show < v.label_counts.size()) os << ", ... (" << v.label_counts.size() - show << " more)";
    os << " voxels\n";
    os << "  foreground " << v.foreground_voxels << " voxels, " << fixed(v.foreground_volume / 1000.0, 2)
       << " cm^3";
    if (v.foreground_voxels > 0) os << ", centres " << box_text(v.foreground_bounds);
    os << "\n";
  }
  if (centerlines) {
    const CenterlineInfo& c = *centerlines;
    os << "  " << c.points_per_line.size() << " lines, " << c.total_points << " points ("
       << join(c.points_per_line, ", ") << ")\n";
    os << "  lengths " << join(c.line_lengths, ", ", 1) << " mm\n";
    if (c.radius_array.empty())
      os << "  no radius array\n";
    else
      os << "  radius '" << c.radius_array << "' " << fixed(c.radius_min, 3) << " - "
         << fixed(c.radius_max, 3) << " mm\n";
    os << "  bounds " << box_text(c.bounds) << "\n";
  }
  return os.str();
}

std::string FileInfo::to_json() const {
  std::ostringstream os;
  os << "{\"path\": " << json_string(path.string()) << ", \"kind\": " << json_string(kind)
     << ", \"format\": " << json_string(format) << ", \"unit\": " << json_string(unit)
     << ", \"load_ms\": " << json_number(load_ms);
  if (mesh) {
    const MeshReport& r = mesh->report;
    os << ", \"mesh\": {\"vertices\": " << r.vertices << ", \"faces\": " << r.faces
       << ", \"edges\": " << r.edges << ", \"closed\": " << json_bool(r.closed())
       << ", \"manifold\": " << json_bool(r.manifold()) << ", \"valid\": " << json_bool(r.valid())
       << ", \"components\": " << r.components << ", \"euler_characteristic\": " << r.euler_characteristic
       << ", \"genus\": " << mesh->genus() << ", \"boundary_edges\": " << r.boundary_edges
       << ", \"nonmanifold_edges\": " << r.nonmanifold_edges
       << ", \"degenerate_faces\": " << r.degenerate_faces << ", \"duplicate_faces\": " << r.duplicate_faces
       << ", \"inconsistent_edges\": " << r.inconsistent_edges
       << ", \"isolated_vertices\": " << r.isolated_vertices
       << ", \"first_problem\": " << json_string(r.first_problem)
       << ", \"bounds\": " << json_box(mesh->bounds) << ", \"volume_mm3\": " << json_number(mesh->volume)
       << ", \"area_mm2\": " << json_number(mesh->area)
       << ", \"edge_length\": {\"min\": " << json_number(mesh->edge_min)
       << ", \"mean\": " << json_number(mesh->edge_mean) << ", \"max\": " << json_number(mesh->edge_max)
       << "}"
       << ", \"dropped_cells\": " << mesh->dropped_cells
       << ", \"triangulated_polygons\": " << mesh->triangulated_polygons
       << ", \"merged_vertices\": " << mesh->merged_vertices << "}";
  }
  if (volume) {
    const VolumeInfo& v = *volume;
    os << ", \"volume\": {\"dims\": [" << v.dims[0] << ", " << v.dims[1] << ", " << v.dims[2]
       << "], \"spacing\": " << json_vec(v.spacing) << ", \"origin\": " << json_vec(v.origin)
       << ", \"direction_columns\": [" << json_vec(v.direction.col(0)) << ", " << json_vec(v.direction.col(1))
       << ", " << json_vec(v.direction.col(2)) << "], \"frame\": \"RAS\", \"bounds\": " << json_box(v.bounds)
       << ", \"label_counts\": {";
    for (std::size_t i = 0; i < v.label_counts.size(); ++i)
      os << (i ? ", " : "") << "\"" << v.label_counts[i].first << "\": " << v.label_counts[i].second;
    os << "}, \"foreground_voxels\": " << v.foreground_voxels
       << ", \"foreground_volume_mm3\": " << json_number(v.foreground_volume);
    if (v.foreground_voxels > 0) os << ", \"foreground_bounds\": " << json_box(v.foreground_bounds);
    os << "}";
  }
  if (centerlines) {
    const CenterlineInfo& c = *centerlines;
    os << ", \"centerlines\": {\"lines\": " << c.points_per_line.size() << ", \"points\": " << c.total_points
       << ", \"points_per_line\": [" << join(c.points_per_line, ", ") << "], \"line_lengths\": [";
    for (std::size_t i = 0; i < c.line_lengths.size(); ++i)
      os << (i ? ", " : "") << json_number(c.line_lengths[i]);
    os << "], \"radius_array\": " << json_string(c.radius_array)
       << ", \"radius_min\": " << json_number(c.radius_min)
       << ", \"radius_max\": " << json_number(c.radius_max) << ", \"bounds\": " << json_box(c.bounds) << "}";
  }
  os << "}";
  return os.str();
}

FileInfo describe_file(const fs::path& path, const DescribeOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  FileInfo info;
  info.path = path;
  const std::string ext = lower_extension(path);
  if (ext == ".nii" || ext == ".nii.gz" || ext == ".mha" || ext == ".mhd" || ext == ".nrrd" ||
      ext == ".nhdr") {
    const LabelVolume v = read_label_volume(path);
    info.kind = "volume";
    info.format = ext == ".nii" || ext == ".nii.gz" ? "NIfTI"
                  : ext == ".mha" || ext == ".mhd"  ? "MetaImage"
                                                    : "NRRD";
    info.unit = "mm";
    info.volume = volume_info(v);
  } else {
    MeshFormat format;
    try {
      format = mesh_format(path);
    } catch (const IoError&) {
      throw IoError(cat(name_of(path), ": unknown file extension '", ext,
                        "' (meshes: .obj .stl .ply .vtp .vtk; volumes: .nii .nii.gz .mha .mhd .nrrd .nhdr)"));
    }
    const auto poly = read_polydata(path, format);
    info.format = format_name(format);
    info.unit = to_string(options.unit);
    if (poly->GetNumberOfPolys() + poly->GetNumberOfStrips() > 0) {
      info.kind = "mesh";
      info.mesh = mesh_info(mesh_from_polydata(poly, path, format, {.unit = options.unit}));
    } else if (poly->GetNumberOfLines() > 0) {
      info.kind = "centerlines";
      bool radius = false;
      const auto lines =
          centerlines_from_polydata(poly, path, to_mm(options.unit), options.radius_array, false, &radius);
      info.centerlines = centerline_info(lines, options.radius_array, radius);
    } else {
      throw IoError(
          cat(name_of(path), ": no polygons and no lines (", poly->GetNumberOfPoints(), " points)"));
    }
  }
  info.load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return info;
}

}  // namespace medspring
