// Isosurfaces of segmentation masks (ALGORITHMS.md §4.4 "marching-cubes mesh"): VTK flying edges,
// windowed-sinc smoothing, largest component, world coordinates, outward orientation.
//
//   MaskVolume aorta = select_label(read_label_volume(find_data_file("aorta_totalseg_mask.nii.gz")), 1);
//   SurfaceMesh s = isosurface(aorta);   // mm, in the volume's world frame
#pragma once

#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/geometry/volume.hpp"

namespace medspring {

struct IsosurfaceSettings {
  /// Gaussian blur of the 0/1 mask before vtkFlyingEdges3D at iso-value 0.5, standard deviation in
  /// voxels. 0 = no blur: vtkDiscreteFlyingEdges3D on the labels (a blockier surface).
  double blur_sigma_voxels = 1.0;
  int smoothing_iterations = 30;  // vtkWindowedSincPolyDataFilter iterations (0 = no smoothing)
  double pass_band = 0.08;        // windowed-sinc pass band (0, 2]; smaller = smoother
  bool largest_component = true;  // keep only the largest connected surface
};

/// The boundary surface of the nonzero voxels of `mask`, in world millimetres (the volume's origin,
/// spacing and direction are honoured), closed (the volume is padded with empty voxels, so objects
/// touching the border get flat caps), welded (weld_vertices) and outward-oriented. Throws
/// InvalidInput for an inconsistent volume (data size, non-positive spacing, singular direction),
/// an empty mask or invalid settings.
SurfaceMesh isosurface(const MaskVolume& mask, const IsosurfaceSettings& settings = {});

}  // namespace medspring
