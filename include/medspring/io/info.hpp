// One-screen summaries of mesh, volume and centerline files (the CLI's `info` command).
//
//   FileInfo info = describe_file("kidney.obj", {.unit = LengthUnit::Metre});
//   std::cout << info.text();      // human-readable, <= ~20 lines
//   std::cout << info.to_json();   // one JSON object, same content
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "medspring/core/units.hpp"
#include "medspring/geometry/surface_mesh.hpp"

namespace medspring {

/// Axis-aligned box in mm (world coordinates).
struct Box3 {
  Vec3 min = Vec3::Zero(), max = Vec3::Zero();
  Vec3 size() const { return max - min; }
};

struct MeshInfo {
  MeshReport report;    // counts and validity (closed, manifold, components, Euler)
  Box3 bounds;          // mm
  double volume = 0.0;  // signed enclosed volume, mm^3 (meaningful when closed)
  double area = 0.0;    // mm^2
  double edge_min = 0.0, edge_mean = 0.0, edge_max = 0.0;  // unique edge lengths, mm
  Index dropped_cells = 0;                                 // line/vertex cells ignored on read
  Index triangulated_polygons = 0;
  Index merged_vertices = 0;
  /// Genus from the Euler characteristic, or -1 unless closed, manifold and one component.
  int genus() const;
};

struct VolumeInfo {
  std::array<Index, 3> dims{0, 0, 0};
  Vec3 spacing = Vec3::Ones();  // mm
  Vec3 origin = Vec3::Zero();   // mm, centre of voxel (0,0,0), RAS
  Mat3 direction = Mat3::Identity();
  Box3 bounds;                                                      // box of all voxel centres, mm
  std::vector<std::pair<std::int32_t, std::int64_t>> label_counts;  // (label, voxels), ascending label
  Box3 foreground_bounds;  // box of the centres of voxels with label != 0, mm
  std::int64_t foreground_voxels = 0;
  double foreground_volume = 0.0;  // mm^3
};

struct CenterlineInfo {
  std::string radius_array;  // name of the radius array ("" when the file has none)
  std::vector<Index> points_per_line;
  std::vector<double> line_lengths;  // mm
  Index total_points = 0;
  double radius_min = 0.0, radius_max = 0.0;  // mm (0 without radius array)
  Box3 bounds;                                // mm
};

struct FileInfo {
  std::filesystem::path path;
  std::string kind;      // "mesh", "volume" or "centerlines"
  std::string format;    // "OBJ", "STL", "PLY", "VTP", "VTK", "NIfTI", "MetaImage", "NRRD"
  std::string unit;      // unit the coordinates were read in, e.g. "m" (everything below is in mm)
  double load_ms = 0.0;  // wall time to read and analyse the file
  std::optional<MeshInfo> mesh;
  std::optional<VolumeInfo> volume;
  std::optional<CenterlineInfo> centerlines;

  /// A one-screen, human-readable summary.
  std::string text() const;
  /// The same content as one JSON object (keys in snake_case, lengths in mm).
  std::string to_json() const;
};

struct DescribeOptions {
  /// Unit of mesh and centerline coordinates (volumes carry their own spacing in mm).
  LengthUnit unit = LengthUnit::Millimetre;
  /// Name of the per-point radius array for centerline files.
  std::string radius_array = "MaximumInscribedSphereRadius";
};

/// Reads a mesh, volume or centerline file and summarises it. The kind follows the extension; a
/// .vtp/.vtk file is a mesh when it has polygons and centerlines when it has only lines. Throws what
/// the underlying reader throws (IoError naming the file).
FileInfo describe_file(const std::filesystem::path& path, const DescribeOptions& options = {});

}  // namespace medspring
