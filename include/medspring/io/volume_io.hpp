// Label volumes (segmentations) from NIfTI, MetaImage and NRRD files.
//
// World frame: every volume is returned in RAS+ millimetres (+x toward the subject's Right, +y
// Anterior, +z Superior), which is the frame of NIfTI's qform/sform and of the project's anatomy
// meshes (aorta_totalseg_ct.obj was made with the NIfTI affine). So a
// voxel centre maps exactly as the NIfTI affine maps it (nibabel's `img.affine`).
//  - NIfTI (.nii, .nii.gz): sform when sform_code > 0, else qform when qform_code > 0 (with qfac),
//    else spacing only (NIfTI "method 1"), as nibabel does.
//  - MetaImage (.mha, .mhd): stored in ITK's LPS frame (Offset, TransformMatrix, ElementSpacing);
//    x and y are negated on read and on write, so a mask saved by ITK/3D Slicer lines up.
//  - NRRD (.nrrd, .nhdr): "space directions"/"space origin" in the declared `space`: LPS and LAS are
//    converted to RAS, RAS kept; without a space field the coordinates are taken as stored.
// The voxel data keep VTK's memory order (x fastest); LabelVolume::direction holds the rotation.
//
//   LabelVolume mask = read_label_volume(find_data_file("aorta_totalseg_mask.nii.gz"));
//   MaskVolume aorta = select_label(mask, 1);
#pragma once

#include <filesystem>
#include <limits>

#include "medspring/geometry/volume.hpp"

namespace medspring {

struct ReadVolumeOptions {
  /// When set (not NaN), the volume is binarised: label 1 where value >= threshold, 0 elsewhere
  /// (e.g. 0.5 for a probability map). When not set, integer voxel types are read as they are (values
  /// must fit in int32), and floating-point voxels (or values after NIfTI scl_slope/scl_inter scaling)
  /// must be integers within 1e-6.
  double threshold = std::numeric_limits<double>::quiet_NaN();
};

/// Reads a single-component 3-D label volume by extension (case-insensitive): .nii .nii.gz .mha .mhd
/// .nrrd .nhdr. Throws IoError naming the file for a missing file, an unsupported extension, an
/// unreadable or malformed file, a 4-D or multi-component image, an empty volume, labels that do not
/// fit in int32, or non-integer values without a threshold (the message names the voxel).
LabelVolume read_label_volume(const std::filesystem::path& path, const ReadVolumeOptions& options = {});

/// Writes a label volume as MetaImage (.mha, one file, zlib-compressed; stored as uchar, short or int,
/// whichever holds the labels), in ITK's LPS frame with the direction in TransformMatrix. Atomic
/// like write_vtp. Throws IoError for another extension or a write failure, InvalidInput for a
/// volume whose data size does not match its dims or whose spacing is not positive.
void write_label_volume(const std::filesystem::path& path, const LabelVolume& volume);

}  // namespace medspring
