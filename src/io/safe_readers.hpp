// Private to the io layer: MedSpring's own readers for the formats whose VTK 9.1 readers crash, hang
// or run out of memory on malformed files (found by fuzzing, issue 9; docs/reliability.md), and the
// checks that run before a file is handed to the VTK readers that are kept.
//
// Every reader validates the whole structure before it allocates: counts are checked against the
// bytes left in the file, list lengths and cell offsets against their bounds. Errors are IoError
// "<file>: <what is wrong>".
#pragma once

#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <array>
#include <filesystem>
#include <string>

#include "medspring/core/types.hpp"

namespace medspring::io_detail {

/// Legacy VTK POLYDATA (versions 1.0 to 5.1, ASCII or BINARY): points, the four cell kinds (legacy
/// count-prefixed lists or 5.x OFFSETS/CONNECTIVITY), and the point-data arrays (SCALARS, VECTORS,
/// NORMALS, TEXTURE_COORDINATES, FIELD arrays) as named double arrays. Cell data, field data, lookup
/// tables and METADATA blocks are parsed and skipped. Another DATASET is an IoError naming it.
vtkSmartPointer<vtkPolyData> read_vtk_legacy(const std::filesystem::path& path);

/// PLY (ascii, binary_little_endian, binary_big_endian): the x, y, z properties of element "vertex"
/// and the vertex_indices (or vertex_index) lists of element "face" (each >= 3 vertices); other
/// elements and properties are skipped.
vtkSmartPointer<vtkPolyData> read_ply(const std::filesystem::path& path);

/// A 3-D single-component image read by MedSpring's MetaImage or NRRD reader: voxels in file order
/// (x fastest) as a vtkImageData of the file's scalar type, dims and the voxel-to-world geometry as
/// the file states it (LPS for MetaImage; the declared space for NRRD; no conversion applied).
struct RawVolume {
  vtkSmartPointer<vtkImageData> image;
  std::array<Index, 3> dims{0, 0, 0};
  Vec3 spacing = Vec3::Ones();
  Vec3 origin = Vec3::Zero();
  Mat3 axes = Mat3::Identity();  // columns: unit direction of voxel axes i, j, k (MetaImage)
  int channels = 1;              // MetaImage ElementNumberOfChannels
  int ndims = 3;
};

/// MetaImage .mha / .mhd: header "Key = Value" lines up to ElementDataFile; data LOCAL (after the
/// header) or in one file beside the header (.mhd), raw or zlib-compressed (CompressedData), binary
/// (either byte order) or ASCII. LIST and file-pattern data files are rejected.
RawVolume read_metaimage_file(const std::filesystem::path& path);

/// NRRD .nrrd / .nhdr: the voxels (type, sizes, endian, encoding raw | gzip | ascii, "data file" for a
/// detached header, byte skip / line skip). The geometry fields are left to the caller.
RawVolume read_nrrd_file(const std::filesystem::path& path);

/// Checks the binary data of a VTK XML file (.vtp) before vtkXMLPolyDataReader reads it: for every
/// DataArray in "appended" (raw or base64) or "binary" format, the size header (or, with a compressor,
/// the block count, block sizes and compressed sizes) must fit in the bytes the file holds, and the
/// uncompressed size must be one the compressed bytes can give. vtkXMLDataParser allocates whatever the
/// header says first.
void check_vtk_xml(const std::filesystem::path& path);

/// Checks a NIfTI-1 or NIfTI-2 file (.nii or .nii.gz, either byte order) before vtkNIFTIImageReader
/// reads it: header size and magic, dimensions (1 to 7, each >= 1), a datatype VTK reads with the
/// matching bitpix, vox_offset, and a data block as long as the header says (gzip streams are
/// decompressed to count). vtkNIFTIImageReader dereferences null pointers on such files.
void check_nifti(const std::filesystem::path& path);

}  // namespace medspring::io_detail
