// The check of a VTK XML file's binary data before vtkXMLPolyDataReader reads it (safe_readers.hpp):
// vtkXMLDataParser allocates whatever a size header says.
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

/// The value of attribute `name` in the XML start tag `tag` (nullopt when absent).
std::optional<std::string> find_xml_attribute(std::string_view tag, std::string_view name) {
  for (std::size_t at = tag.find(name); at != std::string_view::npos; at = tag.find(name, at + 1)) {
    if (at == 0 || !is_space(tag[at - 1])) continue;
    std::size_t i = at + name.size();
    while (i < tag.size() && is_space(tag[i])) ++i;
    if (i >= tag.size() || tag[i] != '=') continue;
    ++i;
    while (i < tag.size() && is_space(tag[i])) ++i;
    if (i >= tag.size() || (tag[i] != '"' && tag[i] != '\'')) continue;
    const std::size_t end = tag.find(tag[i], i + 1);
    if (end == std::string_view::npos) return std::string();
    return std::string(tag.substr(i + 1, end - i - 1));
  }
  return std::nullopt;
}

/// The value of attribute `name` in the XML start tag `tag` ("" when absent).
std::string xml_attribute(std::string_view tag, std::string_view name) {
  return find_xml_attribute(tag, name).value_or("");
}

/// The '>' that ends the start tag at `at` ('>' inside quoted attribute values do not count, as for
/// the XML parser); npos when the tag does not end.
std::size_t xml_tag_end(std::string_view text, std::size_t at) {
  char quote = 0;
  for (std::size_t i = at; i < text.size(); ++i) {
    const char c = text[i];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '>') {
      return i;
    }
  }
  return std::string_view::npos;
}

/// Where vtkXMLDataReader reads a DataArray from: the appended section when the tag has an `offset`
/// attribute (whatever its `format` says), inline base64 when `format` is "binary", inline text otherwise.
enum class XmlArrayMode { Appended, Binary, Ascii };
XmlArrayMode xml_array_mode(std::string_view tag) {
  if (find_xml_attribute(tag, "offset")) return XmlArrayMode::Appended;
  return xml_attribute(tag, "format") == "binary" ? XmlArrayMode::Binary : XmlArrayMode::Ascii;
}

/// Decodes base64 from `text` until `need` bytes are out, a '=' or a '<' (whitespace skipped).
std::string base64_prefix(std::string_view text, std::size_t need) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  std::string out;
  std::uint32_t acc = 0;
  int bits = 0;
  for (char c : text) {
    if (out.size() >= need || c == '=' || c == '<') break;
    const int v = value(c);
    if (v < 0) continue;
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<char>((acc >> bits) & 0xff));
    }
  }
  return out;
}

/// Base64 characters in `text` up to the first '<'.
std::size_t base64_length(std::string_view text) {
  std::size_t n = 0;
  for (char c : text) {
    if (c == '<') break;
    if (!is_space(c)) ++n;
  }
  return n;
}

/// The base64 characters of `text` up to the first '<', whitespace removed.
std::string base64_chars(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '<') break;
    if (!is_space(c)) out.push_back(c);
  }
  return out;
}

/// The element type of a VTK XML DataArray ("Int32", "UInt64", "Float32", ...).
std::optional<NumType> vtk_xml_type(const std::string& type) {
  static const std::map<std::string, NumType> types = {
      {"Int8", kI8},    {"UInt8", kU8},  {"Int16", kI16},  {"UInt16", kU16},  {"Int32", kI32},
      {"UInt32", kU32}, {"Int64", kI64}, {"UInt64", kU64}, {"Float32", kF32}, {"Float64", kF64}};
  const auto it = types.find(type);
  if (it == types.end()) return std::nullopt;
  return it->second;
}

/// How the binary DataArrays of one VTK XML file are written: header word size, byte order, compressor.
struct VtkXmlCodec {
  std::size_t H = 4;
  bool big = false;
  vtkSmartPointer<vtkDataCompressor> compressor;  // null: uncompressed
  bool unknown_compressor = false;

  std::uint64_t word(std::string_view h, std::size_t k) const {
    std::uint64_t v = 0;
    for (std::size_t b = 0; b < H; ++b)
      v = (v << 8) | static_cast<unsigned char>(h[k * H + (big ? b : H - 1 - b)]);
    return v;
  }

  /// The decoded bytes of one binary DataArray whose header starts at `data` (base64 characters
  /// when `base64`: one stream uncompressed; the header and the data two streams with a compressor, as
  /// vtkXMLWriter writes them), at
  /// most `limit` of them; nullopt when they cannot be decoded here (VTK's reader then fails on its own).
  std::optional<std::string> decode(std::string_view data, bool base64, std::size_t limit) const {
    std::string chars;
    if (base64) chars = base64_chars(data);
    // the header (n header bytes) and where the data starts
    auto header = [&](std::size_t n) -> std::optional<std::string> {
      std::string h =
          base64 ? base64_prefix(chars, n) : std::string(data.substr(0, std::min(n, data.size())));
      if (h.size() < n) return std::nullopt;
      return h;
    };
    auto payload = [&](std::size_t header_bytes, std::size_t n) -> std::string {
      if (!base64) return std::string(data.substr(std::min(header_bytes, data.size()), n));
      const std::size_t skip = (header_bytes + 2) / 3 * 4;
      return skip >= chars.size() ? std::string() : base64_prefix(std::string_view(chars).substr(skip), n);
    };
    if (unknown_compressor) return std::nullopt;
    if (!compressor) {
      const auto h = header(H);
      if (!h) return std::nullopt;
      const std::uint64_t n = word(*h, 0);
      if (n > limit) return std::nullopt;
      // uncompressed: the header and the data are one base64 stream
      std::string out;
      if (base64) {
        out = base64_prefix(chars, H + static_cast<std::size_t>(n));
        out.erase(0, std::min(H, out.size()));
      } else {
        out = payload(H, static_cast<std::size_t>(n));
      }
      if (out.size() < n) return std::nullopt;
      return out;
    }
    const auto h3 = header(3 * H);
    if (!h3) return std::nullopt;
    const std::uint64_t blocks = word(*h3, 0), block = word(*h3, 1), last = word(*h3, 2);
    if (blocks == 0) return std::string();
    if (blocks > limit || block == 0 || block > limit) return std::nullopt;
    const std::size_t header_bytes = (3 + static_cast<std::size_t>(blocks)) * H;
    const auto h = header(header_bytes);
    if (!h) return std::nullopt;
    std::uint64_t packed = 0;
    for (std::uint64_t k = 0; k < blocks; ++k) {
      packed += word(*h, 3 + k);
      if (packed > limit) return std::nullopt;
    }
    const std::string in = payload(header_bytes, static_cast<std::size_t>(packed));
    if (in.size() < packed) return std::nullopt;
    std::string out;
    std::size_t at = 0;
    for (std::uint64_t k = 0; k < blocks; ++k) {
      const std::size_t size = k + 1 == blocks && last != 0 ? last : block;
      const auto csize = static_cast<std::size_t>(word(*h, 3 + k));
      if (out.size() + size > limit) return std::nullopt;
      const std::size_t start = out.size();
      out.resize(start + size);
      const std::size_t got =
          compressor->Uncompress(reinterpret_cast<const unsigned char*>(in.data() + at), csize,
                                 reinterpret_cast<unsigned char*>(out.data() + start), size);
      if (got != size) return std::nullopt;
      at += csize;
    }
    return out;
  }

  /// The uncompressed byte count a binary DataArray's header declares (nullopt: unreadable header).
  std::optional<std::uint64_t> declared_bytes(std::string_view data, bool base64) const {
    if (unknown_compressor) return std::nullopt;
    const std::string h =
        base64 ? base64_prefix(data, 3 * H) : std::string(data.substr(0, std::min(3 * H, data.size())));
    if (!compressor) return h.size() >= H ? std::optional<std::uint64_t>(word(h, 0)) : std::nullopt;
    if (h.size() < 3 * H) return std::nullopt;
    const std::uint64_t blocks = word(h, 0), block = word(h, 1), last = word(h, 2);
    if (blocks == 0) return 0;
    const long double n =
        static_cast<long double>(block) * static_cast<long double>(blocks - 1) + (last ? last : block);
    return n >= 1.8e19L ? std::numeric_limits<std::uint64_t>::max() : static_cast<std::uint64_t>(n);
  }
};

void check_vtk_xml(const fs::path& path) {
  const std::string bytes = read_all(path);
  const std::string_view file(bytes);
  const std::size_t root = file.find("<VTKFile");
  if (root == std::string_view::npos) return;  // not VTK XML: the reader says so
  const std::size_t root_end = xml_tag_end(file, root);
  if (root_end == std::string_view::npos) bad(path, "VTK XML: unterminated <VTKFile> tag");
  const std::string_view root_tag = file.substr(root, root_end - root);
  const std::string header_type = xml_attribute(root_tag, "header_type");
  const std::size_t H = header_type == "UInt64" ? 8 : 4;
  const std::string compressor = xml_attribute(root_tag, "compressor");
  const bool compressed = !compressor.empty();
  // the most a compressed byte can expand to: zlib ~1032:1, LZ4 255:1; LZMA more (16384:1 bounds real files)
  const double ratio = compressor == "vtkZLibDataCompressor"  ? 1100
                       : compressor == "vtkLZ4DataCompressor" ? 260
                                                              : 16384;
  const bool big = xml_attribute(root_tag, "byte_order") == "BigEndian";

  // the appended section: data from the '_' after <AppendedData ...> to the end of the file
  const std::size_t appended_tag = file.find("<AppendedData");
  std::size_t appended = std::string_view::npos;
  bool appended_base64 = false;
  if (appended_tag != std::string_view::npos) {
    const std::size_t gt = xml_tag_end(file, appended_tag);
    if (gt == std::string_view::npos) bad(path, "VTK XML: unterminated <AppendedData> tag");
    appended_base64 = xml_attribute(file.substr(appended_tag, gt - appended_tag), "encoding") == "base64";
    appended = file.find('_', gt);
    if (appended == std::string_view::npos) bad(path, "VTK XML: <AppendedData> without its '_' marker");
    ++appended;
  }
  const std::string_view xml = file.substr(0, appended_tag);  // DataArray tags live before the raw data

  VtkXmlCodec codec;
  codec.H = H;
  codec.big = big;
  if (compressor == "vtkZLibDataCompressor")
    codec.compressor = vtkSmartPointer<vtkZLibDataCompressor>::New();
  else if (compressor == "vtkLZ4DataCompressor")
    codec.compressor = vtkSmartPointer<vtkLZ4DataCompressor>::New();
  else if (compressor == "vtkLZMADataCompressor")
    codec.compressor = vtkSmartPointer<vtkLZMADataCompressor>::New();
  else
    codec.unknown_compressor = compressed;  // VTK refuses a compressor it does not know
  auto word = [&](std::string_view h, std::size_t k) { return codec.word(h, k); };
  // header: the decoded header bytes available; left: data bytes after the header
  auto check = [&](const std::string& name, auto&& header_bytes, auto&& left_after) {
    const std::string_view what = name;
    std::string h = header_bytes(3 * H);
    if (!compressed) {
      if (h.size() < H) bad(path, "VTK XML: DataArray '", what, "': truncated size header");
      const std::uint64_t n = word(h, 0);
      if (n > left_after(H))
        bad(path, "VTK XML: DataArray '", what, "' declares ", n, " bytes, the file holds ", left_after(H));
      return;
    }
    if (h.size() < 3 * H) bad(path, "VTK XML: DataArray '", what, "': truncated compression header");
    const std::uint64_t blocks = word(h, 0), block = word(h, 1), last = word(h, 2);
    // vtkXMLDataParser divides by the block size whenever it reads a value, also from a header with no
    // blocks (fuzz_mesh_vtp); VTK's writers always write the block size, also for an empty array
    if (block == 0 || (blocks > 0 && last > block))
      bad(path, "VTK XML: DataArray '", what, "': compression header with block size ", block,
          " and last block size ", last);
    if (blocks > left_after(3 * H) / H)
      bad(path, "VTK XML: DataArray '", what, "' declares ", blocks,
          " compressed blocks, more than the file holds");
    const std::size_t header = (3 + static_cast<std::size_t>(blocks)) * H;
    h = header_bytes(header);
    if (h.size() < header) bad(path, "VTK XML: DataArray '", what, "': truncated compression header");
    std::uint64_t packed = 0;
    for (std::uint64_t k = 0; k < blocks; ++k)
      packed += std::min<std::uint64_t>(word(h, 3 + k), std::uint64_t(1) << 62);
    if (packed > left_after(header))
      bad(path, "VTK XML: DataArray '", what, "' declares ", packed, " compressed bytes, the file holds ",
          left_after(header));
    const long double unpacked =
        blocks == 0 ? 0.0L : static_cast<long double>(block) * (blocks - 1) + (last ? last : block);
    const long double limit = static_cast<long double>(ratio) * static_cast<long double>(packed) + 65536.0L;
    if (static_cast<long double>(block) > limit || unpacked > limit)
      bad(path, "VTK XML: DataArray '", what, "' declares ",
          static_cast<double>(std::max<long double>(unpacked, block)), " uncompressed bytes from ", packed,
          " compressed bytes");
  };

  // Counts VTK allocates for before it reads a byte: each element needs at least one byte of data (of
  // uncompressed data: `ratio` per byte of the file), so a count the file cannot hold is refused here.
  const std::uint64_t max_count =
      static_cast<std::uint64_t>(compressed ? ratio : 1.0) * static_cast<std::uint64_t>(file.size()) + 1024;
  auto count = [&](std::string_view tag, const char* attribute, const char* element) -> std::uint64_t {
    const std::string text = xml_attribute(tag, attribute);
    if (text.empty()) return 0;
    std::uint64_t v = 0;
    const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
    if (r.ec != std::errc() || r.ptr != text.data() + text.size())
      bad(path, "VTK XML: ", element, " ", attribute, " '", shown(text), "' is not a count (0 to 2^64 - 1)");
    if (v > max_count)
      bad(path, "VTK XML: ", element, " ", attribute, " = ", v, ": more than a ", file.size(),
          "-byte file can hold");
    return v;
  };
  // VTK allocates the whole output for the sum over the pieces: the sums are bounded as each count is
  constexpr const char* kPieceCounts[] = {"NumberOfPoints", "NumberOfVerts", "NumberOfLines",
                                          "NumberOfStrips", "NumberOfPolys", "NumberOfCells"};
  std::uint64_t totals[std::size(kPieceCounts)] = {};
  for (std::size_t at = xml.find("<Piece"); at != std::string_view::npos; at = xml.find("<Piece", at + 1)) {
    const std::size_t gt = xml_tag_end(xml, at);
    if (gt == std::string_view::npos) bad(path, "VTK XML: unterminated <Piece> tag");
    for (std::size_t k = 0; k < std::size(kPieceCounts); ++k) {
      totals[k] += count(xml.substr(at, gt - at), kPieceCounts[k], "Piece");
      if (totals[k] > max_count)
        bad(path, "VTK XML: the pieces' ", kPieceCounts[k], " add up to ", totals[k], ": more than a ",
            file.size(), "-byte file can hold");
    }
  }

  for (std::size_t at = xml.find("<DataArray"); at != std::string_view::npos;
       at = xml.find("<DataArray", at + 1)) {
    const std::size_t gt = xml_tag_end(xml, at);
    if (gt == std::string_view::npos) bad(path, "VTK XML: unterminated <DataArray> tag");
    const std::string_view tag = xml.substr(at, gt - at);
    const XmlArrayMode mode = xml_array_mode(tag);
    const std::string name = xml_attribute(tag, "Name");
    count(tag, "NumberOfTuples", "DataArray");
    if (count(tag, "NumberOfComponents", "DataArray") > 4096)
      bad(path, "VTK XML: DataArray '", name, "' has more than 4096 components");
    if (mode == XmlArrayMode::Appended) {
      if (appended == std::string_view::npos)
        bad(path, "VTK XML: DataArray '", name, "' is appended, the file has no <AppendedData>");
      std::uint64_t offset = 0;
      const std::string off = xml_attribute(tag, "offset");
      const auto r = std::from_chars(off.data(), off.data() + off.size(), offset);
      if (r.ec != std::errc() || r.ptr != off.data() + off.size())
        bad(path, "VTK XML: DataArray '", name, "': offset '", shown(off), "'");
      if (offset > file.size() - appended)
        bad(path, "VTK XML: DataArray '", name, "': offset ", offset, " is past the end of the file");
      const std::string_view data = file.substr(appended + static_cast<std::size_t>(offset));
      if (appended_base64) {
        const std::uint64_t chars = base64_length(data);
        check(
            name, [&](std::size_t n) { return base64_prefix(data, n); },
            [&](std::size_t used) { return chars * 3 / 4 >= used ? chars * 3 / 4 - used + 3 : 0; });
      } else {
        check(
            name, [&](std::size_t n) { return std::string(data.substr(0, n)); },
            [&](std::size_t used) { return data.size() >= used ? data.size() - used : 0; });
      }
    } else if (mode == XmlArrayMode::Binary) {
      const std::string_view data = xml.substr(gt + 1);
      const std::uint64_t chars = base64_length(data);
      check(
          name, [&](std::size_t n) { return base64_prefix(data, n); },
          [&](std::size_t used) { return chars * 3 / 4 >= used ? chars * 3 / 4 - used + 3 : 0; });
    }
  }

  // Cell arrays. vtkXMLUnstructuredDataReader reads a cell block's "offsets" first and then sizes the
  // connectivity array by the last offset: an offset of 3e9 in a small file made it allocate 24 GB
  // before it found the connectivity short. The last offset is decoded here and must fit in the
  // connectivity array the file declares.
  const auto decode_limit = static_cast<std::size_t>(std::min<long double>(
      static_cast<long double>(compressed ? ratio : 1.0) * static_cast<long double>(file.size()) + 65536.0L,
      1e12L));

  // one DataArray: its type, its format, and where its data starts (binary and appended)
  struct ArrayRef {
    std::string type;
    XmlArrayMode mode = XmlArrayMode::Ascii;
    std::string_view data;  // binary / appended: header + data; ascii: the text
    bool base64 = false;
  };
  auto array_named = [&](std::string_view section, std::size_t base,
                         const char* wanted) -> std::optional<ArrayRef> {
    for (std::size_t at = section.find("<DataArray"); at != std::string_view::npos;
         at = section.find("<DataArray", at + 1)) {
      const std::size_t gt = xml_tag_end(section, at);
      if (gt == std::string_view::npos) return std::nullopt;
      const std::string_view tag = section.substr(at, gt - at);
      if (xml_attribute(tag, "Name") != wanted) continue;
      ArrayRef a;
      a.type = xml_attribute(tag, "type");
      a.mode = xml_array_mode(tag);
      if (a.mode == XmlArrayMode::Appended) {
        if (appended == std::string_view::npos) return std::nullopt;
        std::uint64_t offset = 0;
        const std::string off = xml_attribute(tag, "offset");
        std::from_chars(off.data(), off.data() + off.size(), offset);
        a.data = file.substr(
            appended + static_cast<std::size_t>(std::min<std::uint64_t>(offset, file.size() - appended)));
        a.base64 = appended_base64;
      } else {
        a.data = xml.substr(base + gt + 1);
        a.base64 = a.mode == XmlArrayMode::Binary;
        if (a.mode == XmlArrayMode::Ascii) a.data = a.data.substr(0, a.data.find('<'));
      }
      return a;
    }
    return std::nullopt;
  };
  auto ascii_tokens = [](std::string_view text, std::vector<std::string_view>* keep) {
    std::uint64_t n = 0;
    for (std::size_t i = 0; i < text.size();) {
      while (i < text.size() && is_space(text[i])) ++i;
      const std::size_t start = i;
      while (i < text.size() && !is_space(text[i])) ++i;
      if (i > start) {
        ++n;
        if (keep) keep->push_back(text.substr(start, i - start));
      }
    }
    return n;
  };

  int piece_index = 0;
  for (std::size_t at = xml.find("<Piece"); at != std::string_view::npos;
       at = xml.find("<Piece", at + 1), ++piece_index) {
    const std::size_t gt = xml_tag_end(xml, at);
    const std::size_t end = std::min(xml.find("</Piece>", at), xml.size());
    const std::string_view piece_tag = xml.substr(at, gt - at);
    const std::string_view piece = xml.substr(at, end - at);
    for (const char* kind : {"Verts", "Lines", "Strips", "Polys"}) {
      const std::uint64_t cells = count(piece_tag, cat("NumberOf", kind).c_str(), "Piece");
      if (cells == 0) continue;
      const std::string open = cat("<", kind), close = cat("</", kind, ">");
      std::size_t s = piece.find(open);
      while (s != std::string_view::npos && s + open.size() < piece.size() && piece[s + open.size()] != '>' &&
             !is_space(piece[s + open.size()]))
        s = piece.find(open, s + 1);
      if (s == std::string_view::npos) continue;
      const std::size_t e = std::min(piece.find(close, s), piece.size());
      const std::string_view section = piece.substr(s, e - s);
      const std::size_t base = at + s;  // offset of `section` in `xml`
      const auto offsets = array_named(section, base, "offsets");
      const auto connectivity = array_named(section, base, "connectivity");
      if (!offsets || !connectivity) continue;  // VTK's reader names what is missing
      // Bit arrays hold 0 and 1 only; other names VTK refuses itself (floats are converted: checked)
      const auto ot = vtk_xml_type(offsets->type), ct = vtk_xml_type(connectivity->type);
      if (!ot || !ct) continue;

      // The offsets VTK may take as the connectivity length: the cell ends (n values; VTK reads the last)
      // or, in the layout with a leading 0, n + 1 values. The largest of the first n + 1 values counts.
      double last = 0;     // the largest offset
      double invalid = 0;  // the first negative or NaN offset
      bool any = false, bad_value = false;
      auto take = [&](double v) {
        if (!(v >= 0)) {
          if (!bad_value) invalid = v;
          bad_value = true;
        } else if (!any || v > last) {
          last = v;
        }
        any = true;
      };
      if (offsets->mode == XmlArrayMode::Ascii) {
        std::vector<std::string_view> tokens;
        ascii_tokens(offsets->data, &tokens);
        if (tokens.size() < cells) continue;
        for (std::size_t k = 0; k < std::min<std::size_t>(tokens.size(), cells + 1); ++k) {
          double v = 0;
          if (!parse_number(tokens[k], false, v)) break;  // VTK's reading stops here too
          take(v);
        }
      } else {
        const auto decoded = codec.decode(offsets->data, offsets->base64, decode_limit);
        const std::size_t size = static_cast<std::size_t>(ot->size);
        // Offsets this check cannot decode (a '=' inside the base64 text, a short stream) are not
        // skipped: VTK's decoder reads past them and took 2.9e9 as the last offset (fuzz_mesh_vtp).
        if (!decoded && !codec.unknown_compressor)
          bad(path, "VTK XML: piece ", piece_index, ": ", kind,
              " offsets: binary data that does not decode to the size its header declares");
        if (!decoded || decoded->size() / size < cells) continue;
        for (std::size_t k = 0; k < std::min<std::size_t>(decoded->size() / size, cells + 1); ++k)
          take(decode(decoded->data() + k * size, *ot, big));
      }
      if (!any) continue;
      if (bad_value)
        bad(path, "VTK XML: piece ", piece_index, ": ", kind, " offsets hold ", invalid,
            " (offsets are >= 0)");
      // the connectivity values the file declares
      std::uint64_t capacity = 0;
      if (connectivity->mode == XmlArrayMode::Ascii) {
        capacity = ascii_tokens(connectivity->data, nullptr);
      } else {
        const auto n = codec.declared_bytes(connectivity->data, connectivity->base64);
        if (!n) continue;
        capacity = *n / static_cast<std::uint64_t>(ct->size);
      }
      if (last > static_cast<double>(capacity))
        bad(path, "VTK XML: piece ", piece_index, ": ", kind, " offsets end at ", last,
            " connectivity values, the connectivity array holds ", capacity);
    }
  }
}

}  // namespace medspring::io_detail
