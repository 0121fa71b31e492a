// The MetaImage .mha / .mhd reader (safe_readers.hpp). Why our own: metaio overflows a fixed buffer on
// a long header value (fuzz/regressions/).
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

RawVolume read_metaimage_file(const fs::path& path) {
  const std::string bytes = read_all(path);
  Cursor c(bytes, path);
  std::map<std::string, std::string> f;
  bool have_data_file = false;
  while (c.left() > 0) {
    const std::string_view l = c.line();
    if (std::all_of(l.begin(), l.end(), is_space)) continue;
    if (l.size() > 4096) bad(path, "MetaImage: header line longer than 4096 bytes");
    if (std::any_of(l.begin(), l.end(), [](char ch) { return ch == '\0'; }))
      bad(path, "not a MetaImage file (NUL byte in the header)");
    const auto eq = l.find('=');
    if (eq == std::string_view::npos)
      bad(path, "not a MetaImage file (header line '", shown(l), "' has no '=')");
    std::string_view k = l.substr(0, eq), v = l.substr(eq + 1);
    while (!k.empty() && is_space(k.back())) k.remove_suffix(1);
    while (!k.empty() && is_space(k.front())) k.remove_prefix(1);
    while (!v.empty() && is_space(v.back())) v.remove_suffix(1);
    while (!v.empty() && is_space(v.front())) v.remove_prefix(1);
    f[std::string(k)] = std::string(v);
    if (k == "ElementDataFile") {
      have_data_file = true;
      break;  // the header ends here; LOCAL data follow
    }
  }
  if (!have_data_file) bad(path, "not a MetaImage file (no ElementDataFile line)");
  auto field = [&](const char* k) {
    const auto it = f.find(k);
    return it == f.end() ? std::string() : it->second;
  };
  auto boolean = [&](const char* k) {
    const std::string v = lower(field(k));
    return v == "true" || v == "1";
  };
  const std::string object = field("ObjectType");
  if (!object.empty() && object != "Image")
    bad(path, "MetaImage ObjectType '", shown(object), "' is not Image");

  RawVolume out;
  std::uint64_t nd = 0;
  if (!parse_count(field("NDims"), nd) || nd < 1 || nd > 16)
    bad(path, "MetaImage: NDims '", shown(field("NDims")), "'");
  out.ndims = static_cast<int>(nd);
  if (nd < 2 || nd > 3) bad(path, nd, "-D MetaImage; a label volume is 3-D");
  out.dims = parse_dims(field("DimSize"), out.ndims, path, "MetaImage DimSize");
  std::uint64_t channels = 1;
  if (const std::string ch = field("ElementNumberOfChannels");
      !ch.empty() && (!parse_count(ch, channels) || channels < 1))
    bad(path, "MetaImage: ElementNumberOfChannels '", shown(ch), "'");
  out.channels = static_cast<int>(std::min<std::uint64_t>(channels, 1u << 20));
  if (channels != 1) bad(path, channels, " channels per voxel; a label volume needs 1");

  static const std::map<std::string, NumType> types = {
      {"MET_CHAR", kI8},       {"MET_UCHAR", kU8},       {"MET_SHORT", kI16}, {"MET_USHORT", kU16},
      {"MET_INT", kI32},       {"MET_UINT", kU32},       {"MET_LONG", kI32},  {"MET_ULONG", kU32},
      {"MET_LONG_LONG", kI64}, {"MET_ULONG_LONG", kU64}, {"MET_FLOAT", kF32}, {"MET_DOUBLE", kF64}};
  const auto ti = types.find(field("ElementType"));
  if (ti == types.end()) bad(path, "MetaImage: unsupported ElementType '", shown(field("ElementType")), "'");
  const NumType t = ti->second;

  auto vec = [&](const char* k, std::size_t n, std::vector<double> fallback) {
    const std::string text = field(k);
    if (text.empty()) return fallback;
    std::vector<double> v = parse_numbers(text);
    if (v.size() != n || !std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); }))
      bad(path, "MetaImage ", k, ": expected ", n, " finite numbers, got '", shown(text), "'");
    return v;
  };
  const auto n = static_cast<std::size_t>(nd);
  std::vector<double> spacing = vec("ElementSpacing", n, {});
  if (spacing.empty()) spacing = vec("ElementSize", n, std::vector<double>(n, 1.0));
  std::vector<double> origin = vec("Offset", n, {});
  if (origin.empty()) origin = vec("Position", n, {});
  if (origin.empty()) origin = vec("Origin", n, std::vector<double>(n, 0.0));
  std::vector<double> id(n * n, 0.0);
  for (std::size_t a = 0; a < n; ++a) id[a * n + a] = 1;
  std::vector<double> m = vec("TransformMatrix", n * n, {});
  if (m.empty()) m = vec("Rotation", n * n, {});
  if (m.empty()) m = vec("Orientation", n * n, id);
  for (std::size_t a = 0; a < n; ++a) {
    out.spacing(static_cast<Index>(a)) = spacing[a];
    out.origin(static_cast<Index>(a)) = origin[a];
    for (std::size_t b = 0; b < n; ++b)
      out.axes(static_cast<Index>(b), static_cast<Index>(a)) = m[a * n + b];  // row a = axis a
  }

  // the data: LOCAL (after the header) or a file beside the header
  const std::string data_name = field("ElementDataFile");
  std::string external;
  std::string_view data;
  if (data_name == "LOCAL" || data_name == "Local" || data_name == "local") {
    data = std::string_view(bytes).substr(c.position());
  } else {
    external = read_all(data_file_of(path, data_name, "MetaImage"));
    data = external;
  }
  if (const std::string hs = field("HeaderSize"); !hs.empty()) {
    double skip = 0;
    if (!parse_number(hs, true, skip) || skip < -1) bad(path, "MetaImage: HeaderSize '", shown(hs), "'");
    if (skip > 0) {
      if (skip > static_cast<double>(data.size()))
        bad(path, "MetaImage: HeaderSize ", hs, " is past the end of the data");
      data.remove_prefix(static_cast<std::size_t>(skip));
    }
  }
  const std::size_t voxels = static_cast<std::size_t>(out.dims[0]) * out.dims[1] * out.dims[2];
  const std::string binary = lower(field("BinaryData"));
  if (binary == "false" || binary == "0") {
    out.image = image_from_text(out.dims, t, data, path, "MetaImage");
    return out;
  }
  const bool big = boolean("BinaryDataByteOrderMSB") || boolean("ElementByteOrderMSB");
  if (voxels > std::numeric_limits<std::size_t>::max() / 8) bad(path, "MetaImage: too many voxels");
  const std::size_t need = voxels * static_cast<std::size_t>(t.size);
  std::string inflated;
  if (boolean("CompressedData")) {
    if (const std::string cs = field("CompressedDataSize"); !cs.empty()) {
      std::uint64_t size = 0;
      if (!parse_count(cs, size)) bad(path, "MetaImage: CompressedDataSize '", shown(cs), "'");
      if (size > data.size())
        bad(path, "MetaImage: truncated data (CompressedDataSize ", size, ", the file holds ", data.size(),
            " bytes)");
      data = data.substr(0, static_cast<std::size_t>(size));
    }
    inflated = inflate_prefix(data, need, path, "MetaImage");
    data = inflated;
  }
  set_voxels(out, t, data, need, big, path, "MetaImage");
  return out;
}

}  // namespace medspring::io_detail
