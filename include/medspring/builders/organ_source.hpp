// Where a model's anatomy comes from: a closed organ surface mesh or a labelled volume (segmentation),
// loaded, checked and reduced to one object (ALGORITHMS.md §3.1.1, §3.6, §3.7) for the builders.
//
//   LoadedOrgan kidney = load_organ({.mesh = find_data_file("kidney_left_hubmap_vhm.obj"),
//                                    .unit = LengthUnit::Metre});
//   LoadedOrgan aorta = load_organ({.mask = find_data_file("aorta_totalseg_mask.nii.gz"), .label = 1},
//                                  {.surface = false});
//
// Errors (one line naming the file): IoError from the readers; InvalidInput for both or neither of
// mesh and mask given, an empty mask, a label that is not in the volume (the message lists the labels
// present), several labels without a label chosen, an open surface (unless holes are closed or
// open tubes allowed), a non-manifold or inconsistently oriented surface.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "medspring/core/units.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/geometry/volume.hpp"
#include "medspring/meshing/isosurface.hpp"

namespace medspring {

/// The input of a builder: exactly one of `mesh` and `mask`.
struct OrganSource {
  std::filesystem::path mesh{};              // surface mesh (.obj .stl .ply .vtp .vtk), or
  std::filesystem::path mask{};              // label volume (.nii .nii.gz .mha .mhd .nrrd), world mm (RAS+)
  std::optional<std::int32_t> label{};       // mask: the organ's label; unset = the only non-zero label
  LengthUnit unit = LengthUnit::Millimetre;  // mesh: unit of the file's coordinates (scaled to mm)
  Index close_holes = 0;                     // mesh: close holes of up to this many edges (0 = refuse open)
};

/// How load_organ treats what it finds.
struct LoadOrganOptions {
  bool allow_open_tube = false;     // mesh: accept boundary loops (an open vessel; capped later, §3.6)
  bool surface = true;              // mask: also compute the boundary surface (isosurface)
  IsosurfaceSettings isosurface{};  // mask: how the boundary surface is made
};

/// An organ reduced to one object, in millimetres.
struct LoadedOrgan {
  std::string name;        // the file name, for messages
  bool from_mask = false;  // true: `mask` is the (selected, largest-component) segmentation
  SurfaceMesh surface;     // the organ boundary: the input mesh (largest component, outward), or the
                           // isosurface of the mask (empty when LoadOrganOptions::surface is false)
  MaskVolume mask;         // mask input: 1 = organ voxel (largest 26-connected component); empty for a mesh
  std::int32_t label = 0;  // mask input: the label used
  Index components = 1;    // connected components found (mesh: by faces; mask: 26-connected)
  Index holes_closed = 0;  // mesh: holes closed by close_holes
  std::vector<std::string> notes;     // what was decided ("3 components: the largest used", ...)
  std::vector<std::string> warnings;  // e.g. an implausible size (wrong unit?)
};

/// Loads and checks the organ of `source` (see the file comment for the errors). A mesh is reduced to
/// its largest component (by enclosed volume), optionally has its small holes closed, must be closed
/// (or an open tube when allowed), manifold and consistently oriented, and is turned outward. A mask
/// has its label selected and is reduced to its largest 26-connected component. A size (bounding-box
/// diagonal) under 5 mm or over 1000 mm adds a warning naming the likely unit error.
LoadedOrgan load_organ(const OrganSource& source, const LoadOrganOptions& options = {});

/// True when world point p (mm) lies in an object voxel of `mask` (the voxel whose centre is nearest).
bool mask_contains(const MaskVolume& mask, const Vec3& p);

/// Distance (mm) from p to the nearest object voxel, each voxel taken as the box of its spacing around
/// its centre: 0 inside an object voxel. Searches the voxels within `search_voxels` of p's voxel and
/// returns +inf when none is an object voxel.
double distance_outside_mask(const MaskVolume& mask, const Vec3& p, Index search_voxels = 2);

/// The largest 26-connected component of the non-zero voxels of `mask` (ties: the component met first
/// in raster order), as a 0/1 mask on the same grid. `components` receives the number of components.
MaskVolume largest_component(const MaskVolume& mask, Index* components = nullptr);

}  // namespace medspring
