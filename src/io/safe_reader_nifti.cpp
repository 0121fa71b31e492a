// The NIfTI-1 / NIfTI-2 pre-check (safe_readers.hpp). Why: vtkNIFTIImageReader dereferences null on an
// inconsistent header (fuzz/regressions/).
#include <vtkCellArray.h>
#include <vtkDataCompressor.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkLZ4DataCompressor.h>
#include <vtkLZMADataCompressor.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>

#include <map>
#include <optional>

#include "safe_reader_common.hpp"
#include "safe_readers.hpp"
#include "vtk_support.hpp"

namespace fs = std::filesystem;

namespace medspring::io_detail {

using namespace reader;

void check_nifti(const fs::path& path) {
  const std::string file = read_all(path);
  const bool gz = file.size() >= 2 && static_cast<unsigned char>(file[0]) == 0x1f &&
                  static_cast<unsigned char>(file[1]) == 0x8b;
  std::string inflated;
  std::string_view b = file;
  if (gz) {
    inflated = inflate_prefix(file, 544, path, "NIfTI");
    b = inflated;
  }
  if (b.size() < 348) bad(path, "NIfTI file is truncated (", b.size(), " bytes, the header alone has 348)");
  auto i32 = [&](std::size_t at, bool swap) {
    return static_cast<std::int32_t>(decode(b.data() + at, kI32, swap));
  };
  bool swap = false;
  int version = 0;
  for (const bool s : {false, true}) {
    if (i32(0, s) == 348) version = 1, swap = s;
    if (i32(0, s) == 540) version = 2, swap = s;
    if (version) break;
  }
  if (version == 0) bad(path, "not a NIfTI-1 or NIfTI-2 file (header size field)");
  if (version == 2 && b.size() < 540)
    bad(path, "NIfTI file is truncated (", b.size(), " bytes, the header alone has 540)");
  const bool v1 = version == 1;
  if (v1 ? b.substr(344, 4) != std::string_view("n+1\0", 4)
         : b.substr(4, 8) != std::string_view("n+2\0\r\n\x1a\n", 8))
    bad(path, "not a single-file NIfTI-", version, " image (magic)");
  // vtkNIFTIImageReader takes a NIfTI-2 magic at byte 4 ('n+2'..'n+9', 'ni2'..'ni9') before the size
  // field and would read this 348-byte header as a 540-byte one
  if (v1 && b[4] == 'n' && (b[5] == '+' || b[5] == 'i') && b[6] >= '2' && b[6] <= '9' && b[7] == '\0')
    bad(path, "NIfTI: a NIfTI-1 header (348 bytes) with the NIfTI-", b[6], " magic '", b.substr(4, 3),
        "' at byte 4");
  // dim[0..7], datatype, bitpix, vox_offset
  double dim[8];
  for (int a = 0; a < 8; ++a)
    dim[a] = v1 ? decode(b.data() + 40 + 2 * a, kI16, swap) : decode(b.data() + 16 + 8 * a, kI64, swap);
  const int datatype = static_cast<int>(decode(b.data() + (v1 ? 70 : 12), kI16, swap));
  const int bitpix = static_cast<int>(decode(b.data() + (v1 ? 72 : 14), kI16, swap));
  const double vox_offset = v1 ? decode(b.data() + 108, kF32, swap) : decode(b.data() + 168, kI64, swap);
  if (!(dim[0] >= 1 && dim[0] <= 7)) bad(path, "NIfTI: dim[0] = ", dim[0], " (1 to 7 dimensions)");
  double voxels = 1;
  for (int a = 1; a <= static_cast<int>(dim[0]); ++a) {
    if (!(dim[a] >= 1 && dim[a] <= 1e9)) bad(path, "NIfTI: dim[", a, "] = ", dim[a], " (must be >= 1)");
    voxels *= dim[a];
  }
  static const std::map<int, int> bits = {{2, 8},   {4, 16},   {8, 32},   {16, 32},   {64, 64},
                                          {256, 8}, {512, 16}, {768, 32}, {1024, 64}, {1280, 64}};
  const auto it = bits.find(datatype);
  if (it == bits.end())
    bad(path, "NIfTI: unsupported datatype ", datatype, " (a label volume needs scalar voxels)");
  if (bitpix != it->second) bad(path, "NIfTI: bitpix ", bitpix, " does not match datatype ", datatype);
  const double header = v1 ? 348 : 540;
  if (!(std::isfinite(vox_offset) && vox_offset >= header && vox_offset <= 1e12))
    bad(path, "NIfTI: vox_offset ", vox_offset, " (must be >= ", header, ")");
  const double need = std::floor(vox_offset) + voxels * it->second / 8;
  if (need > 1e13) bad(path, "NIfTI: ", voxels, " voxels is too many");
  std::size_t have = file.size();
  if (gz) have = inflate_prefix(file, static_cast<std::size_t>(need), path, "NIfTI").size();
  if (static_cast<double>(have) < need)
    bad(path, "NIfTI file is truncated (", have, " bytes, the header announces ", need, ")");
}

}  // namespace medspring::io_detail
