// The distance-mapping centerline of a real vessel or organ (ALGORITHMS.md §3) from a segmentation or
// a surface mesh, with radii, ends handled per §3.1 (a vessel cut by the scan has open ends) and the
// checks that say whether it can be trusted.
//
//   CenterlineBuild c = build_centerline({.source = {.mask = find_data_file("aorta_totalseg_mask.nii.gz"),
//                                                    .label = 1}});
//   c.centerline();                          // 40 atoms with radii, world mm
//   c.summary.ends[0], c.summary.atoms_outside_mask, c.summary.max_radius_deviation_mm
//   write_centerline_files(dir, c);          // centerline.vtp (+ surface.vtp)
//
// Errors: those of load_organ (empty mask, missing label, non-manifold mesh, ...), InvalidInput for
// atoms < 2 and those of extract_centerline. Nothing is written by build_centerline.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "medspring/builders/organ_source.hpp"
#include "medspring/skeleton/voxelize.hpp"

namespace medspring {

struct CenterlineBuildSettings {
  OrganSource source{};         // label volume (+ label), or a mesh (closed, or an open tube: capped, §3.6)
  Index atoms = 40;             // evenly spaced atoms (§3.5.4; vessel 40); overrides skeleton.atom_count
  SkeletonSettings skeleton{};  // §3; end_mode Auto: ends cut by the volume border are open (§3.1)
  VoxelizeSettings voxelize{};  // mesh input (§3.6)
  bool surface = true;          // mask input: also make the lumen surface (isosurface) for the output
  IsosurfaceSettings isosurface{};
};

/// What build_centerline made. Distances in mm, times in seconds.
struct CenterlineSummary {
  std::string input;       // file name
  std::string input_kind;  // "mesh" or "mask"
  Index atoms = 0;
  double length_mm = 0.0;  // arc length of the atoms' curve, first to last atom
  double atom_spacing_min_mm = 0.0, atom_spacing_max_mm = 0.0;  // distance between consecutive atoms
  double min_radius_mm = 0.0, max_radius_mm = 0.0, mean_radius_mm = 0.0;
  std::array<std::string, 2> ends{};     // "open", "closed" or "capped" (start, end)
  std::vector<Index> open_end_sizes;     // voxels of the open ends on the volume border
  Index components = 0;                  // connected components of the object
  Index object_voxels = 0;               // voxels of the component used
  double voxel_size_mm = 0.0;            // smallest spacing of the grid
  Index atoms_outside_mask = 0;          // atoms not in an object voxel (the voxel whose centre is nearest)
  double max_distance_outside_mm = 0.0;  // largest distance of an atom to the nearest object voxel's box
                                         // (a warning when above half a voxel)
  double max_radius_deviation_mm = 0.0;  // largest |r_i - (DFB(C_i) - h/2)|, DFB of the object on its own
                                         // grid (§3.2), trilinear at the atom; atoms on the linear
                                         // extension to a cap (§3.6) are left out
  double seconds = 0.0;
  std::vector<std::string> notes;
  std::vector<std::string> warnings;

  std::string text() const;
};

struct CenterlineBuild {
  SkeletonResult skeleton;  // atoms, radii, raw path, curve (world mm)
  MaskVolume mask;          // the object the centerline was extracted from (mask, or voxelised mesh)
  SurfaceMesh surface;      // the boundary: the input mesh or the isosurface (empty if not asked for)
  CenterlineSummary summary;

  Centerline centerline() const { return skeleton.centerline(); }
};

/// Extracts the centerline of settings.source (see the file comment). Deterministic.
CenterlineBuild build_centerline(const CenterlineBuildSettings& settings);

/// Writes centerline.vtp (the atoms as one polyline with the radius array "MaximumInscribedSphereRadius",
/// readable by read_centerlines), curve.vtp (the smoothed, trimmed curve the atoms lie on) and, when the
/// build holds one, surface.vtp, into the existing folder `dir`.
void write_centerline_files(const std::filesystem::path& dir, const CenterlineBuild& build);

}  // namespace medspring
