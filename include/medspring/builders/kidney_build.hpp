// From a real organ to a running hybrid kidney in one call (ALGORITHMS.md §4.4): balloon surface at an
// exact node count (§1.1), skeleton of the voxelised organ by distance mapping (§3, §3.6), spokes by the
// union rule (D-9) and the parameters of §9.
//
//   KidneyBuild k = build_kidney_model({.source = {.mesh = find_data_file("kidney_left_hubmap_vhm.obj"),
//                                                  .unit = LengthUnit::Metre}});
//   Simulation sim(k.model);                      // 458 surface nodes + 42 atoms
//   k.summary.hausdorff_mm, k.summary.valence6_fraction, k.summary.seconds
//   write_kidney_files(dir, k);                   // surface.vtp, centerline.vtp, spokes.vtp
//
// Errors: those of load_organ (empty mask, missing label, open or non-manifold mesh, ...) and
// InvalidInput for nodes below BalloonSettings::min_nodes, or too few for the shape (the balloon
// builder cannot keep the surface manifold, or the surface leaves skeleton atoms outside it),
// atoms < 2 or more atoms than surface nodes. Nothing is written by build_kidney_model.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "medspring/builders/organ_source.hpp"
#include "medspring/meshing/balloon.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/skeleton/voxelize.hpp"

namespace medspring {

struct KidneyBuildSettings {
  OrganSource source{};       // closed organ mesh (+ unit, close_holes) or label volume (+ label)
  Index nodes = 458;          // surface nodes of the model (§4.1); overrides balloon.target_nodes
  Index atoms = 42;           // centerline atoms (§4.1); overrides skeleton.atom_count
  HybridSettings model{};     // §9 kidney column: masses, damping, stiffnesses, K_a = 8, Duffing Strain
  BalloonSettings balloon{};  // balloon surface (CGAL remeshing, exact count, valence regularisation)
  VoxelizeSettings
      voxelize{};  // mesh input: voxelisation for the skeleton (§3.6: h_v = smallest extent / 48)
  SkeletonSettings skeleton{.end_mode = EndMode::Closed};  // §3; an organ has closed ends (D-8 trimming)
  IsosurfaceSettings isosurface{};  // mask input: the organ surface the balloon is fitted to
};

/// What build_kidney_model made, for the CLI summary and tests. Distances in mm, times in seconds.
struct KidneySummary {
  std::string input;                          // file name
  std::string input_kind;                     // "mesh" or "mask"
  Index input_vertices = 0, input_faces = 0;  // the organ surface (the isosurface for a mask)
  double organ_volume_mm3 = 0.0;              // enclosed by the organ surface
  double organ_diagonal_mm = 0.0;             // bounding-box diagonal of the organ surface
  double voxel_size_mm = 0.0;                 // grid of the skeleton (h_v for a mesh, spacing for a mask)
  Index object_voxels = 0;                    // organ voxels of that grid

  Index nodes = 0, edges = 0, faces = 0, atoms = 0;
  std::vector<Index> valence_histogram;  // [d] = surface nodes with d neighbours
  double valence6_fraction = 0.0;        // surface nodes with six neighbours / nodes
  double hausdorff_mm = 0.0;             // symmetric Hausdorff distance model surface <-> organ surface
  double mean_distance_mm = 0.0;         // symmetric mean surface distance

  Index atoms_outside_organ = 0;    // generalized winding number of the organ surface < 0.5 at the atom
  Index atoms_outside_mask = 0;     // atom not in an organ voxel of the skeleton's grid
  Index atoms_outside_model = 0;    // winding number of the model surface < 0.5 at the atom: always 0
                                    // (a surface that leaves atoms outside is refused: too few nodes)
  double skeleton_length_mm = 0.0;  // arc length of the trimmed centerline
  double atom_spacing_min_mm = 0.0, atom_spacing_max_mm = 0.0;  // distance between consecutive atoms
                                                                // (equal along the curve, not in space)
  double min_radius_mm = 0.0, max_radius_mm = 0.0;              // atom radii (§3.5.5)

  Index surface_springs = 0, centerline_springs = 0, spokes = 0;
  Index min_spokes_per_atom = 0, max_spokes_per_atom = 0;
  Index surface_nodes_without_spoke = 0;
  double dt_safe_ms = 0.0;  // stable explicit step of the model at rest (§2.2)

  double seconds = 0.0;               // whole build (reading the input included)
  double seconds_surface = 0.0;       // balloon surface (with its distance measurement)
  double seconds_skeleton = 0.0;      // voxelisation + centerline
  std::vector<std::string> notes;     // what was decided (components, holes, trimming, remeshing, ...)
  std::vector<std::string> warnings;  // implausible size (units?), atoms outside the organ, ...

  /// Human-readable summary, one item per line.
  std::string text() const;
};

/// The model and the pieces it was built from.
struct KidneyBuild {
  SurfaceMesh organ;        // the input organ surface (mm): the mesh, or the isosurface of the mask
  MaskVolume mask;          // the organ voxels the skeleton was extracted from
  SkeletonResult skeleton;  // the centerline (atoms, radii, curve), world mm
  BalloonReport balloon;    // the balloon builder's own report
  std::shared_ptr<const HybridKidney> model;  // surface = balloon, atoms = skeleton atoms
  KidneySummary summary;
};

/// Builds the hybrid kidney of settings.source (see the file comment). Deterministic.
KidneyBuild build_kidney_model(const KidneyBuildSettings& settings);

/// Writes the model into `dir` (which must exist): surface.vtp (the model surface with point arrays
/// "valence" and "spokes"), centerline.vtp (the atoms as one polyline, radius array
/// "MaximumInscribedSphereRadius", readable by read_centerlines) and spokes.vtp (one segment per
/// spoke; points = surface nodes then atoms; array "atom" = 1 on atoms). Each file is written atomically.
void write_kidney_files(const std::filesystem::path& dir, const KidneyBuild& build);

}  // namespace medspring
