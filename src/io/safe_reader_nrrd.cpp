// The NRRD .nrrd / .nhdr reader (safe_readers.hpp). Why our own: vtkNrrdReader loops forever on a NUL
// in the header (fuzz/regressions/).
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

RawVolume read_nrrd_file(const fs::path& path) {
  const std::string bytes = read_all(path);
  Cursor c(bytes, path);
  if (c.line().substr(0, 4) != "NRRD") bad(path, "not a NRRD file (no NRRD magic)");
  std::map<std::string, std::string> f;
  for (;;) {
    if (c.left() == 0) break;  // a header without data (detached)
    const std::string_view l = c.line();
    if (l.empty()) break;
    if (l.size() > 4096) bad(path, "NRRD: header line longer than 4096 bytes");
    if (std::any_of(l.begin(), l.end(), [](char ch) { return ch == '\0'; }))
      bad(path, "NRRD: NUL byte in the header");
    if (l.front() == '#') continue;
    const auto colon = l.find(": ");
    if (colon == std::string_view::npos) {
      if (l.find(":=") != std::string_view::npos) continue;  // key/value metadata
      bad(path, "NRRD: malformed header line '", shown(l), "'");
    }
    f[lower(l.substr(0, colon))] = std::string(l.substr(colon + 2));
  }
  auto field = [&](const char* k) {
    const auto it = f.find(k);
    return it == f.end() ? std::string() : it->second;
  };
  static const std::map<std::string, NumType> types = {{"signed char", kI8},
                                                       {"int8", kI8},
                                                       {"int8_t", kI8},
                                                       {"uchar", kU8},
                                                       {"unsigned char", kU8},
                                                       {"uint8", kU8},
                                                       {"uint8_t", kU8},
                                                       {"short", kI16},
                                                       {"short int", kI16},
                                                       {"signed short", kI16},
                                                       {"signed short int", kI16},
                                                       {"int16", kI16},
                                                       {"int16_t", kI16},
                                                       {"ushort", kU16},
                                                       {"unsigned short", kU16},
                                                       {"unsigned short int", kU16},
                                                       {"uint16", kU16},
                                                       {"uint16_t", kU16},
                                                       {"int", kI32},
                                                       {"signed int", kI32},
                                                       {"int32", kI32},
                                                       {"int32_t", kI32},
                                                       {"uint", kU32},
                                                       {"unsigned int", kU32},
                                                       {"uint32", kU32},
                                                       {"uint32_t", kU32},
                                                       {"longlong", kI64},
                                                       {"long long", kI64},
                                                       {"long long int", kI64},
                                                       {"signed long long", kI64},
                                                       {"signed long long int", kI64},
                                                       {"int64", kI64},
                                                       {"int64_t", kI64},
                                                       {"ulonglong", kU64},
                                                       {"unsigned long long", kU64},
                                                       {"unsigned long long int", kU64},
                                                       {"uint64", kU64},
                                                       {"uint64_t", kU64},
                                                       {"float", kF32},
                                                       {"double", kF64}};
  const auto ti = types.find(field("type"));
  if (ti == types.end()) bad(path, "NRRD: unsupported or missing type '", shown(field("type")), "'");
  const NumType t = ti->second;
  RawVolume out;
  std::uint64_t nd = 0;
  if (!parse_count(field("dimension"), nd) || nd < 1 || nd > 16)
    bad(path, "NRRD: dimension '", shown(field("dimension")), "'");
  if (nd < 2 || nd > 3) bad(path, nd, "-D NRRD; a label volume is 3-D");
  out.ndims = static_cast<int>(nd);
  out.dims = parse_dims(field("sizes"), out.ndims, path, "NRRD sizes");

  std::string_view data = std::string_view(bytes).substr(c.position());
  std::string external;
  if (std::string df = field("data file").empty() ? field("datafile") : field("data file"); !df.empty()) {
    external = read_all(data_file_of(path, df, "NRRD"));
    data = external;
  }
  std::uint64_t line_skip = 0;
  if (const std::string ls = field("line skip").empty() ? field("lineskip") : field("line skip"); !ls.empty())
    if (!parse_count(ls, line_skip)) bad(path, "NRRD: line skip '", shown(ls), "'");
  for (std::uint64_t k = 0; k < line_skip; ++k) {
    const auto nl = data.find('\n');
    if (nl == std::string_view::npos)
      bad(path, "NRRD: line skip ", line_skip, " is past the end of the data");
    data.remove_prefix(nl + 1);
  }
  double byte_skip = 0;
  if (const std::string bs = field("byte skip").empty() ? field("byteskip") : field("byte skip"); !bs.empty())
    if (!parse_number(bs, true, byte_skip) || byte_skip < -1) bad(path, "NRRD: byte skip '", shown(bs), "'");

  const std::size_t voxels = static_cast<std::size_t>(out.dims[0]) * out.dims[1] * out.dims[2];
  if (voxels > std::numeric_limits<std::size_t>::max() / 8) bad(path, "NRRD: too many voxels");
  const std::size_t need = voxels * static_cast<std::size_t>(t.size);
  const std::string enc = lower(field("encoding"));
  const std::string endian = lower(field("endian"));
  if (!endian.empty() && endian != "little" && endian != "big")
    bad(path, "NRRD: endian '", shown(endian), "'");
  const bool big = endian == "big";
  if (enc == "ascii" || enc == "text" || enc == "txt") {
    out.image = image_from_text(out.dims, t, data, path, "NRRD");
    return out;
  }
  if (byte_skip > 0) {
    if (byte_skip > static_cast<double>(data.size()))
      bad(path, "NRRD: byte skip is past the end of the data");
    data.remove_prefix(static_cast<std::size_t>(byte_skip));
  }
  std::string inflated;
  if (enc == "gzip" || enc == "gz") {
    inflated = inflate_prefix(data, need, path, "NRRD");
    data = inflated;
  } else if (enc != "raw") {
    bad(path, "NRRD: unsupported encoding '", shown(field("encoding")), "' (raw, gzip or ascii)");
  } else if (byte_skip == -1 && data.size() >= need) {
    data = data.substr(data.size() - need);
  }
  set_voxels(out, t, data, need, big, path, "NRRD");
  return out;
}

}  // namespace medspring::io_detail
