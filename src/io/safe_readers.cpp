// MedSpring's own readers for legacy VTK, PLY, MetaImage and NRRD, and the NIfTI pre-check
// (safe_readers.hpp). Why: VTK 9.1's vtkPolyDataReader dereferences a closed stream after a bad cell
// list, vtkPLYReader frees uninitialised pointers on a short file, metaio overflows a fixed buffer on
// a long header value, vtkNrrdReader loops forever on a NUL in the header, and vtkNIFTIImageReader
// dereferences null on an inconsistent header (fuzz/regressions/ keeps one input of each).
#include "safe_readers.hpp"

#include <vtkCellArray.h>
#include <vtkDataCompressor.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkLZ4DataCompressor.h>
#include <vtkLZMADataCompressor.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkType.h>
#include <vtkZLibDataCompressor.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <string_view>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "vtk_support.hpp"

namespace fs = std::filesystem;

namespace medspring::io_detail {

namespace {

template <class... Args>
[[noreturn]] void bad(const fs::path& path, const Args&... args) {
  throw IoError(cat(name_of(path), ": ", args...));
}

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) bad(path, "cannot be opened for reading");
  std::string s{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) bad(path, "read error");
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return std::tolower(c); });
  return out;
}

/// Printable for messages: at most 40 characters, control bytes as '?'.
std::string shown(std::string_view s) {
  std::string out(s.substr(0, 40));
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return s.size() > 40 ? out + "..." : out;
}

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

// --- numbers -----------------------------------------------------------------------------------------

/// A numeric type of a file: size in bytes, float or integer, signed, and the VTK type id.
struct NumType {
  int size = 0;
  bool is_float = false;
  bool is_signed = false;
  int vtk = 0;
};

constexpr NumType kI8{1, false, true, VTK_SIGNED_CHAR}, kU8{1, false, false, VTK_UNSIGNED_CHAR},
    kI16{2, false, true, VTK_SHORT}, kU16{2, false, false, VTK_UNSIGNED_SHORT}, kI32{4, false, true, VTK_INT},
    kU32{4, false, false, VTK_UNSIGNED_INT}, kI64{8, false, true, VTK_LONG_LONG},
    kU64{8, false, false, VTK_UNSIGNED_LONG_LONG}, kF32{4, true, true, VTK_FLOAT},
    kF64{8, true, true, VTK_DOUBLE};

/// Reads one binary value (little- or big-endian) as double (integers above 2^53 lose precision).
double decode(const char* p, const NumType& t, bool big_endian) {
  unsigned char b[8];
  for (int k = 0; k < t.size; ++k) b[k] = static_cast<unsigned char>(p[big_endian ? t.size - 1 - k : k]);
  std::uint64_t u = 0;
  for (int k = t.size - 1; k >= 0; --k) u = (u << 8) | b[k];
  if (t.is_float) {
    if (t.size == 4) {
      std::uint32_t u32 = static_cast<std::uint32_t>(u);
      float f;
      std::memcpy(&f, &u32, 4);
      return f;
    }
    double d;
    std::memcpy(&d, &u, 8);
    return d;
  }
  if (t.is_signed && t.size < 8 && (u >> (8 * t.size - 1)) != 0) u |= ~std::uint64_t{0} << (8 * t.size);
  return t.is_signed ? static_cast<double>(static_cast<std::int64_t>(u)) : static_cast<double>(u);
}

/// One text number; integers must be written as integers when `integer`.
bool parse_number(std::string_view tok, bool integer, double& out) {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  if (tok.empty()) return false;
  if (integer) {
    long long v = 0;
    const auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (ec != std::errc() || p != tok.data() + tok.size()) return false;
    out = static_cast<double>(v);
    return true;
  }
  const auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  return ec == std::errc() && p == tok.data() + tok.size();
}

bool parse_count(std::string_view tok, std::uint64_t& out) {
  if (tok.empty() || tok.front() == '-') return false;
  if (tok.front() == '+') tok.remove_prefix(1);
  const auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  return ec == std::errc() && p == tok.data() + tok.size();
}

/// A value read as double that must be an exact integer in [lo, hi].
bool exact_integer(double v, double lo, double hi) {
  return std::isfinite(v) && v == std::floor(v) && v >= lo && v <= hi;
}

// --- a cursor over a text-with-binary-blocks file ------------------------------------------------------

class Cursor {
 public:
  Cursor(const std::string& bytes, const fs::path& path) : b_(bytes), path_(path) {}
  bool at_end() {
    skip_space();
    return pos_ >= b_.size();
  }
  std::size_t left() const { return b_.size() - pos_; }
  /// The next whitespace-delimited token ("" at the end).
  std::string_view token() {
    skip_space();
    const std::size_t start = pos_;
    while (pos_ < b_.size() && !is_space(b_[pos_])) ++pos_;
    return std::string_view(b_).substr(start, pos_ - start);
  }
  std::string_view need_token(const char* what) {
    const std::string_view t = token();
    if (t.empty()) bad(path_, "file ends before ", what);
    return t;
  }
  /// The rest of the current line (without the end of line) and moves past it.
  std::string_view line() {
    const std::size_t start = pos_;
    while (pos_ < b_.size() && b_[pos_] != '\n') ++pos_;
    std::string_view l = std::string_view(b_).substr(start, pos_ - start);
    if (pos_ < b_.size()) ++pos_;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    return l;
  }
  /// n raw bytes.
  const char* take(std::size_t n, const char* what) {
    if (left() < n) bad(path_, what, ": needs ", n, " bytes, the file has ", left(), " left");
    const char* p = b_.data() + pos_;
    pos_ += n;
    return p;
  }
  std::size_t position() const { return pos_; }
  void seek(std::size_t p) { pos_ = std::min(p, b_.size()); }

 private:
  void skip_space() {
    while (pos_ < b_.size() && is_space(b_[pos_])) ++pos_;
  }
  const std::string& b_;
  const fs::path& path_;
  std::size_t pos_ = 0;
};

// --- legacy VTK ----------------------------------------------------------------------------------------

bool legacy_type(std::string_view name, NumType& t) {
  static const std::map<std::string, NumType> types = {{"unsigned_char", kU8},
                                                       {"char", kI8},
                                                       {"signed_char", kI8},
                                                       {"unsigned_short", kU16},
                                                       {"short", kI16},
                                                       {"unsigned_int", kU32},
                                                       {"int", kI32},
                                                       {"unsigned_long", kU64},
                                                       {"long", kI64},
                                                       {"unsigned_long_long", kU64},
                                                       {"long_long", kI64},
                                                       {"float", kF32},
                                                       {"double", kF64},
                                                       {"vtkidtype", kI32},
                                                       {"vtktypeint8", kI8},
                                                       {"vtktypeuint8", kU8},
                                                       {"vtktypeint16", kI16},
                                                       {"vtktypeuint16", kU16},
                                                       {"vtktypeint32", kI32},
                                                       {"vtktypeuint32", kU32},
                                                       {"vtktypeint64", kI64},
                                                       {"vtktypeuint64", kU64},
                                                       {"vtktypefloat32", kF32},
                                                       {"vtktypefloat64", kF64}};
  const auto it = types.find(lower(name));
  if (it == types.end()) return false;
  t = it->second;
  return true;
}

class LegacyVtk {
 public:
  LegacyVtk(const fs::path& path, const std::string& bytes) : path_(path), c_(bytes, path) {}

  vtkSmartPointer<vtkPolyData> read() {
    header();
    auto poly = vtkSmartPointer<vtkPolyData>::New();
    bool have_points = false;
    vtkIdType npts = 0, ncells = 0;
    std::string section;  // "", "point_data" or "cell_data"
    std::uint64_t section_count = 0;
    while (!c_.at_end()) {
      const std::string key = lower(c_.token());
      if (key == "metadata") {
        skip_metadata();
      } else if (section.empty() && key == "field") {
        field(0, nullptr);
      } else if (section.empty() && key == "points") {
        if (have_points) bad(path_, "POINTS given twice");
        const std::uint64_t n = count("POINTS count");
        const NumType t = type("POINTS type");
        const std::vector<double> v = values(t, n, 3, "POINTS");
        vtkNew<vtkPoints> pts;
        pts->SetDataTypeToDouble();
        pts->SetNumberOfPoints(static_cast<vtkIdType>(n));
        for (std::uint64_t i = 0; i < n; ++i)
          pts->SetPoint(static_cast<vtkIdType>(i), v[3 * i], v[3 * i + 1], v[3 * i + 2]);
        poly->SetPoints(pts);
        npts = static_cast<vtkIdType>(n);
        have_points = true;
      } else if (section.empty() &&
                 (key == "vertices" || key == "lines" || key == "polygons" || key == "triangle_strips")) {
        vtkSmartPointer<vtkCellArray> cells = cell_array(key);
        if (key == "vertices") poly->SetVerts(cells);
        if (key == "lines") poly->SetLines(cells);
        if (key == "polygons") poly->SetPolys(cells);
        if (key == "triangle_strips") poly->SetStrips(cells);
        ncells = poly->GetNumberOfCells();
      } else if (key == "point_data" || key == "cell_data") {
        section = key;
        section_count = count(key == "point_data" ? "POINT_DATA count" : "CELL_DATA count");
        const std::uint64_t expected = static_cast<std::uint64_t>(key == "point_data" ? npts : ncells);
        if (section_count != expected)
          bad(path_, key == "point_data" ? "POINT_DATA " : "CELL_DATA ", section_count, " values for ",
              expected, key == "point_data" ? " points" : " cells");
      } else if (!section.empty()) {
        attribute(key, section_count, section == "point_data" ? poly->GetPointData() : nullptr);
      } else {
        bad(path_, "unknown legacy VTK keyword '", shown(key), "'");
      }
    }
    if (!have_points) bad(path_, "legacy VTK file has no POINTS");
    return poly;
  }

 private:
  void header() {
    const std::string_view first = c_.line();
    const std::string_view magic = "# vtk DataFile Version";
    if (first.substr(0, magic.size()) != magic) bad(path_, "not a legacy VTK file (no '", magic, "' line)");
    double version = 0;
    std::string_view v = first.substr(magic.size());
    while (!v.empty() && is_space(v.front())) v.remove_prefix(1);
    while (!v.empty() && is_space(v.back())) v.remove_suffix(1);
    if (!parse_number(v, false, version) || !(version >= 1 && version < 100))
      bad(path_, "legacy VTK: unreadable file version '", shown(v), "'");
    major_ = static_cast<int>(version);
    c_.line();  // title
    const std::string mode = lower(c_.need_token("ASCII or BINARY"));
    if (mode != "ascii" && mode != "binary")
      bad(path_, "legacy VTK: expected ASCII or BINARY, got '", shown(mode), "'");
    binary_ = mode == "binary";
    const std::string dataset = lower(c_.need_token("DATASET"));
    if (dataset != "dataset") bad(path_, "not a legacy VTK POLYDATA file");
    std::string kind(c_.need_token("the dataset type"));
    std::transform(kind.begin(), kind.end(), kind.begin(), [](unsigned char ch) { return std::toupper(ch); });
    if (kind != "POLYDATA") bad(path_, "legacy VTK file holds ", shown(kind), ", not POLYDATA");
  }

  std::uint64_t count(const char* what) {
    const std::string_view t = c_.need_token(what);
    std::uint64_t n = 0;
    if (!parse_count(t, n)) bad(path_, what, ": '", shown(t), "' is not a count");
    return n;
  }

  NumType type(const char* what) {
    const std::string_view t = c_.need_token(what);
    NumType nt;
    if (!legacy_type(t, nt)) bad(path_, what, ": unsupported data type '", shown(t), "'");
    return nt;
  }

  /// n tuples of `comps` values of type t. Counts are checked against the bytes left before anything
  /// is allocated.
  std::vector<double> values(const NumType& t, std::uint64_t n, std::uint64_t comps, const char* what) {
    const std::uint64_t per = binary_ ? static_cast<std::uint64_t>(t.size) : 2;
    const std::uint64_t room = (c_.left() + 1) / per;
    if (comps == 0 || n > room / comps)
      bad(path_, what, ": ", n, " x ", comps, " values do not fit in the ", c_.left(), " bytes left");
    const std::uint64_t total = n * comps;
    std::vector<double> out(static_cast<std::size_t>(total));
    if (binary_) {
      c_.line();  // the rest of the keyword line; the data starts on the next one
      const char* p = c_.take(static_cast<std::size_t>(total * t.size), what);
      for (std::uint64_t k = 0; k < total; ++k) out[k] = decode(p + k * t.size, t, true);
    } else {
      for (std::uint64_t k = 0; k < total; ++k) {
        const std::string_view tok = c_.need_token(what);
        if (!parse_number(tok, !t.is_float, out[k]))
          bad(path_, what, ": value ", k, " '", shown(tok), "' is not ",
              t.is_float ? "a number" : "an integer");
      }
    }
    return out;
  }

  /// Cell ids: integers >= 0 that fit in vtkIdType.
  std::vector<vtkIdType> ids(const NumType& t, std::uint64_t n, const char* what) {
    if (t.is_float) bad(path_, what, ": cell data must be integers");
    const std::vector<double> v = values(t, n, 1, what);
    std::vector<vtkIdType> out(v.size());
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (!exact_integer(v[k], 0, 9.0e15)) bad(path_, what, ": value ", k, " (", v[k], ") is not a valid id");
      out[k] = static_cast<vtkIdType>(v[k]);
    }
    return out;
  }

  vtkSmartPointer<vtkCellArray> cell_array(const std::string& key) {
    const std::string what = cat(key, " cells");
    const std::uint64_t a = count(what.c_str()), b = count(what.c_str());
    vtkNew<vtkIdTypeArray> offsets, conn;
    if (major_ < 5) {  // "n size", then n lists "count id id ..." (size values in all)
      const std::vector<vtkIdType> v = ids(kI32, b, what.c_str());
      std::vector<vtkIdType> off{0}, cn;
      std::size_t k = 0;
      while (k < v.size()) {
        const auto m = static_cast<std::size_t>(v[k]);
        if (m > v.size() - k - 1)
          bad(path_, what, ": cell ", off.size() - 1, " lists ", m, " points past the end");
        cn.insert(cn.end(), v.begin() + static_cast<std::ptrdiff_t>(k + 1),
                  v.begin() + static_cast<std::ptrdiff_t>(k + 1 + m));
        off.push_back(static_cast<vtkIdType>(cn.size()));
        k += m + 1;
      }
      if (off.size() - 1 != a)
        bad(path_, what, ": ", off.size() - 1, " cells in the list, the header says ", a);
      fill(offsets, off);
      fill(conn, cn);
    } else {  // "offsets_count connectivity_count", OFFSETS type ..., CONNECTIVITY type ...
      if (lower(c_.need_token("OFFSETS")) != "offsets") bad(path_, what, ": expected OFFSETS");
      const std::vector<vtkIdType> off = ids(type("OFFSETS type"), a, what.c_str());
      if (lower(c_.need_token("CONNECTIVITY")) != "connectivity") bad(path_, what, ": expected CONNECTIVITY");
      const std::vector<vtkIdType> cn = ids(type("CONNECTIVITY type"), b, what.c_str());
      if (off.empty() ? !cn.empty() : off.front() != 0 || off.back() != static_cast<vtkIdType>(cn.size()))
        bad(path_, what, ": offsets must run from 0 to the connectivity size ", cn.size());
      for (std::size_t k = 1; k < off.size(); ++k)
        if (off[k] < off[k - 1]) bad(path_, what, ": offsets decrease at ", k);
      fill(offsets, off.empty() ? std::vector<vtkIdType>{0} : off);
      fill(conn, cn);
    }
    auto cells = vtkSmartPointer<vtkCellArray>::New();
    cells->SetData(offsets, conn);
    return cells;
  }

  static void fill(vtkIdTypeArray* a, const std::vector<vtkIdType>& v) {
    a->SetNumberOfTuples(static_cast<vtkIdType>(v.size()));
    for (std::size_t k = 0; k < v.size(); ++k) a->SetValue(static_cast<vtkIdType>(k), v[k]);
  }

  void keep(vtkPointData* pd, std::string_view name, const std::vector<double>& v, std::uint64_t comps) {
    if (!pd) return;
    vtkNew<vtkDoubleArray> arr;
    const std::string n(name);
    arr->SetName(n.c_str());
    arr->SetNumberOfComponents(static_cast<int>(comps));
    arr->SetNumberOfTuples(static_cast<vtkIdType>(v.size() / comps));
    for (std::size_t k = 0; k < v.size(); ++k) arr->SetValue(static_cast<vtkIdType>(k), v[k]);
    pd->AddArray(arr);
  }

  /// One attribute of POINT_DATA (pd given: kept) or CELL_DATA (skipped), n tuples.
  void attribute(const std::string& key, std::uint64_t n, vtkPointData* pd) {
    if (key == "scalars") {
      const std::string_view name = c_.need_token("SCALARS name");
      const NumType t = type("SCALARS type");
      std::uint64_t comps = 1;
      std::string next = lower(c_.need_token("LOOKUP_TABLE"));
      if (next != "lookup_table") {
        if (!parse_count(next, comps) || comps < 1 || comps > 4)
          bad(path_, "SCALARS ", shown(name), ": '", shown(next), "' is not a component count (1 to 4)");
        next = lower(c_.need_token("LOOKUP_TABLE"));
      }
      if (next != "lookup_table") bad(path_, "SCALARS ", shown(name), ": expected LOOKUP_TABLE");
      c_.need_token("the lookup table name");
      keep(pd, name, values(t, n, comps, "SCALARS"), comps);
    } else if (key == "color_scalars") {
      c_.need_token("COLOR_SCALARS name");
      const std::uint64_t comps = count("COLOR_SCALARS components");
      values(binary_ ? kU8 : kF32, n, comps, "COLOR_SCALARS");
    } else if (key == "lookup_table") {
      c_.need_token("LOOKUP_TABLE name");
      values(binary_ ? kU8 : kF32, count("LOOKUP_TABLE size"), 4, "LOOKUP_TABLE");
    } else if (key == "vectors" || key == "normals") {
      const std::string_view name = c_.need_token("array name");
      const NumType t = type("array type");
      keep(pd, name, values(t, n, 3, key == "vectors" ? "VECTORS" : "NORMALS"), 3);
    } else if (key == "texture_coordinates") {
      const std::string_view name = c_.need_token("TEXTURE_COORDINATES name");
      const std::uint64_t dim = count("TEXTURE_COORDINATES dimension");
      if (dim < 1 || dim > 3) bad(path_, "TEXTURE_COORDINATES: dimension ", dim, " (1 to 3)");
      const NumType t = type("TEXTURE_COORDINATES type");
      keep(pd, name, values(t, n, dim, "TEXTURE_COORDINATES"), dim);
    } else if (key == "tensors" || key == "tensors6") {
      c_.need_token("TENSORS name");
      values(type("TENSORS type"), n, key == "tensors" ? 9 : 6, "TENSORS");
    } else if (key == "global_ids" || key == "pedigree_ids" || key == "edge_flags") {
      c_.need_token("array name");
      values(type("array type"), n, 1, "ids");
    } else if (key == "field") {
      field(n, pd);
    } else {
      bad(path_, "unknown legacy VTK attribute '", shown(key), "'");
    }
  }

  /// FIELD name count, then count arrays "name components tuples type" + values.
  void field(std::uint64_t /*tuples_expected*/, vtkPointData* pd) {
    c_.need_token("FIELD name");
    const std::uint64_t arrays = count("FIELD array count");
    for (std::uint64_t a = 0; a < arrays; ++a) {
      const std::string_view name = c_.need_token("FIELD array name");
      if (name == "NULL_ARRAY") continue;
      const std::uint64_t comps = count("FIELD array components");
      const std::uint64_t tuples = count("FIELD array tuples");
      const NumType t = type("FIELD array type");
      const std::vector<double> v = values(t, tuples, comps, "FIELD array");
      if (pd && comps >= 1 && comps <= 9) keep(pd, name, v, comps);
      const std::size_t mark = c_.position();
      if (lower(c_.token()) == "metadata")
        skip_metadata();
      else
        c_.seek(mark);
    }
  }

  /// METADATA: lines up to the first empty one.
  void skip_metadata() {
    c_.line();
    while (c_.left() > 0) {
      const std::string_view l = c_.line();
      if (std::all_of(l.begin(), l.end(), is_space)) return;
    }
  }

  const fs::path& path_;
  Cursor c_;
  int major_ = 3;
  bool binary_ = false;
};

// --- PLY -----------------------------------------------------------------------------------------------

bool ply_type(std::string_view name, NumType& t) {
  static const std::map<std::string, NumType> types = {
      {"char", kI8},   {"int8", kI8},     {"uchar", kU8},   {"uint8", kU8},
      {"short", kI16}, {"int16", kI16},   {"ushort", kU16}, {"uint16", kU16},
      {"int", kI32},   {"int32", kI32},   {"uint", kU32},   {"uint32", kU32},
      {"float", kF32}, {"float32", kF32}, {"double", kF64}, {"float64", kF64}};
  const auto it = types.find(std::string(name));
  if (it == types.end()) return false;
  t = it->second;
  return true;
}

struct PlyProperty {
  std::string name;
  bool list = false;
  NumType count_type, type;
};
struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> props;
};

}  // namespace

vtkSmartPointer<vtkPolyData> read_vtk_legacy(const fs::path& path) {
  const std::string bytes = read_all(path);
  return LegacyVtk(path, bytes).read();
}

vtkSmartPointer<vtkPolyData> read_ply(const fs::path& path) {
  const std::string bytes = read_all(path);
  Cursor c(bytes, path);
  if (c.line() != "ply") bad(path, "not a PLY file (no 'ply' header)");
  enum class Format { Ascii, Le, Be } format = Format::Ascii;
  bool have_format = false;
  std::vector<PlyElement> elements;
  for (;;) {
    if (c.left() == 0) bad(path, "PLY header has no end_header");
    const std::string_view l = c.line();
    std::vector<std::string_view> tok;
    for (std::size_t i = 0; i < l.size();) {
      while (i < l.size() && is_space(l[i])) ++i;
      std::size_t j = i;
      while (j < l.size() && !is_space(l[j])) ++j;
      if (j > i) tok.push_back(l.substr(i, j - i));
      i = j;
    }
    if (tok.empty() || tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "end_header") break;
    if (tok[0] == "format") {
      if (tok.size() < 2) bad(path, "PLY: 'format' needs a value");
      if (tok[1] == "ascii")
        format = Format::Ascii;
      else if (tok[1] == "binary_little_endian")
        format = Format::Le;
      else if (tok[1] == "binary_big_endian")
        format = Format::Be;
      else
        bad(path, "PLY: unknown format '", shown(tok[1]), "'");
      have_format = true;
    } else if (tok[0] == "element") {
      std::uint64_t n = 0;
      if (tok.size() != 3 || !parse_count(tok[2], n)) bad(path, "PLY: malformed line '", shown(l), "'");
      elements.push_back({std::string(tok[1]), n, {}});
    } else if (tok[0] == "property") {
      if (elements.empty()) bad(path, "PLY: property before any element");
      PlyProperty p;
      if (tok.size() == 5 && tok[1] == "list") {
        p.list = true;
        if (!ply_type(tok[2], p.count_type) || !ply_type(tok[3], p.type) || p.count_type.is_float)
          bad(path, "PLY: unsupported list types in '", shown(l), "'");
        p.name = tok[4];
      } else if (tok.size() == 3) {
        if (!ply_type(tok[1], p.type)) bad(path, "PLY: unsupported property type '", shown(tok[1]), "'");
        p.name = tok[2];
      } else {
        bad(path, "PLY: malformed line '", shown(l), "'");
      }
      elements.back().props.push_back(p);
    } else {
      bad(path, "PLY: unknown header line '", shown(l), "'");
    }
  }
  if (!have_format) bad(path, "PLY header has no format line");

  const bool binary = format != Format::Ascii, big = format == Format::Be;
  // one value of a property: binary bytes or an ascii token
  auto value = [&](const NumType& t, const char* what) -> double {
    if (binary) return decode(c.take(static_cast<std::size_t>(t.size), what), t, big);
    const std::string_view tok = c.need_token(what);
    double v = 0;
    if (!parse_number(tok, !t.is_float, v)) bad(path, "PLY ", what, ": '", shown(tok), "' is not a number");
    return v;
  };
  auto fits = [&](std::uint64_t n, std::uint64_t min_bytes) {
    return n <= c.left() / std::max<std::uint64_t>(min_bytes, 1);
  };

  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  vtkNew<vtkCellArray> polys;
  std::uint64_t vertices = 0;
  bool have_vertices = false;
  std::vector<vtkIdType> face;
  for (const PlyElement& e : elements) {
    std::uint64_t row_bytes = 0;  // smallest size of one instance
    for (const PlyProperty& p : e.props)
      row_bytes += binary ? static_cast<std::uint64_t>(p.list ? p.count_type.size : p.type.size) : 2;
    if (!e.props.empty() && !fits(e.count, row_bytes))
      bad(path, "PLY element '", shown(e.name), "': ", e.count, " instances do not fit in the ", c.left(),
          " bytes left");
    const bool is_vertex = e.name == "vertex" && !have_vertices;
    const bool is_face = e.name == "face";
    int ix = -1, iy = -1, iz = -1, ifaces = -1;
    for (std::size_t k = 0; k < e.props.size(); ++k) {
      const std::string& n = e.props[k].name;
      if (is_vertex && !e.props[k].list) {
        if (n == "x") ix = static_cast<int>(k);
        if (n == "y") iy = static_cast<int>(k);
        if (n == "z") iz = static_cast<int>(k);
      }
      if (is_face && e.props[k].list && (n == "vertex_indices" || n == "vertex_index"))
        ifaces = static_cast<int>(k);
    }
    if (is_vertex) {
      if (ix < 0 || iy < 0 || iz < 0) bad(path, "PLY element 'vertex' lacks x, y or z");
      pts->SetNumberOfPoints(static_cast<vtkIdType>(e.count));
      vertices = e.count;
      have_vertices = true;
    }
    if (is_face && ifaces < 0) bad(path, "PLY element 'face' has no vertex_indices list");
    double xyz[3] = {0, 0, 0};
    for (std::uint64_t i = 0; i < e.count; ++i) {
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const PlyProperty& p = e.props[k];
        if (!p.list) {
          const double v = value(p.type, "value");
          if (is_vertex && static_cast<int>(k) == ix) xyz[0] = v;
          if (is_vertex && static_cast<int>(k) == iy) xyz[1] = v;
          if (is_vertex && static_cast<int>(k) == iz) xyz[2] = v;
          continue;
        }
        const double m = value(p.count_type, "list length");
        if (!exact_integer(m, 0, 1e9) ||
            !fits(static_cast<std::uint64_t>(m), binary ? static_cast<std::uint64_t>(p.type.size) : 1))
          bad(path, "PLY element '", shown(e.name), "' ", i, ": list length ", m,
              " is invalid or past the end");
        const auto len = static_cast<std::size_t>(m);
        const bool keep_face = is_face && static_cast<int>(k) == ifaces;
        if (keep_face && len < 3) bad(path, "PLY face ", i, " has ", len, " vertices (a polygon needs 3)");
        face.clear();
        for (std::size_t j = 0; j < len; ++j) {
          const double v = value(p.type, "list value");
          if (!keep_face) continue;
          if (!exact_integer(v, 0, static_cast<double>(vertices) - 1))
            bad(path, "PLY face ", i, ": vertex index ", v, " out of range [0, ", vertices, ")");
          face.push_back(static_cast<vtkIdType>(v));
        }
        if (keep_face) polys->InsertNextCell(static_cast<vtkIdType>(face.size()), face.data());
      }
      if (is_vertex) pts->SetPoint(static_cast<vtkIdType>(i), xyz);
    }
  }
  if (!have_vertices) bad(path, "PLY file has no 'vertex' element");
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(pts);
  poly->SetPolys(polys);
  return poly;
}

// --- compressed data -----------------------------------------------------------------------------------

namespace {

/// Inflates a zlib or gzip stream (and the gzip members that follow it) until it ends or `max_out`
/// bytes came out; bytes after the last stream that do not start a gzip member are ignored, as zlib's
/// gzread does. A stream cut short gives what it holds (callers compare sizes). Throws IoError for
/// corrupt data.
std::string inflate_prefix(std::string_view in, std::size_t max_out, const fs::path& path, const char* what) {
  std::string out;
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) bad(path, "zlib initialisation failed");
  std::size_t fed = 0;
  auto feed = [&] {
    const std::size_t more = std::min<std::size_t>(in.size() - fed, std::numeric_limits<uInt>::max());
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data() + fed));
    z.avail_in = static_cast<uInt>(more);
    fed += more;
  };
  feed();
  static thread_local char buf[1 << 16];
  while (out.size() < max_out) {
    const std::size_t room = std::min<std::size_t>(sizeof buf, max_out - out.size());
    z.next_out = reinterpret_cast<Bytef*>(buf);
    z.avail_out = static_cast<uInt>(room);
    const int rc = inflate(&z, Z_NO_FLUSH);
    out.append(buf, room - z.avail_out);
    if (rc == Z_STREAM_END) {
      if (z.avail_in == 0 && fed < in.size()) feed();
      const bool gzip_follows = z.avail_in >= 2 && z.next_in[0] == 0x1f && z.next_in[1] == 0x8b;
      if (!gzip_follows || inflateReset(&z) != Z_OK) break;
      continue;
    }
    if (rc == Z_OK || rc == Z_BUF_ERROR) {
      if (z.avail_in == 0 && fed < in.size()) {
        feed();
        continue;
      }
      if (rc == Z_BUF_ERROR || (z.avail_in == 0 && z.avail_out != 0)) break;  // input used up: cut short
      continue;
    }
    const std::string msg = z.msg ? z.msg : "error";
    inflateEnd(&z);
    bad(path, what, ": corrupt compressed data (zlib: ", msg, ")");
  }
  inflateEnd(&z);
  return out;
}

/// A vtkImageData of `dims` with one component of type t, filled from `count` binary values at p
/// (byte-swapped when the file's order differs from the host's, which is little-endian here).
vtkSmartPointer<vtkImageData> image_from_binary(const std::array<Index, 3>& dims, const NumType& t,
                                                const char* p, bool big_endian) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(dims[0], dims[1], dims[2]);
  image->AllocateScalars(t.vtk, 1);
  const std::size_t n = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  char* dst = static_cast<char*>(image->GetScalarPointer());
  std::memcpy(dst, p, n * static_cast<std::size_t>(t.size));
  if (big_endian && t.size > 1)
    for (std::size_t i = 0; i < n; ++i) std::reverse(dst + i * t.size, dst + (i + 1) * t.size);
  return image;
}

/// out.image from the binary voxels at the start of `data` (`need` bytes), or an IoError "<format>:
/// truncated data" when the file holds fewer.
void set_voxels(RawVolume& out, const NumType& t, std::string_view data, std::size_t need, bool big_endian,
                const fs::path& path, const char* format) {
  if (data.size() < need)
    bad(path, format, ": truncated data (", data.size(), " of ", need, " bytes for ", out.dims[0], " x ",
        out.dims[1], " x ", out.dims[2], " voxels)");
  out.image = image_from_binary(out.dims, t, data.data(), big_endian);
}

/// The same from text: `n` whitespace-separated numbers from `text`.
vtkSmartPointer<vtkImageData> image_from_text(const std::array<Index, 3>& dims, const NumType& t,
                                              std::string_view text, const fs::path& path, const char* what) {
  const std::size_t n = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  if (n > (text.size() + 1) / 2)
    bad(path, what, ": ", n, " text values cannot fit in ", text.size(), " bytes");
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(dims[0], dims[1], dims[2]);
  image->AllocateScalars(t.vtk, 1);
  vtkDataArray* a = image->GetPointData()->GetScalars();
  std::size_t i = 0;
  for (std::size_t k = 0; k < n; ++k) {
    while (i < text.size() && is_space(text[i])) ++i;
    std::size_t j = i;
    while (j < text.size() && !is_space(text[j])) ++j;
    double v = 0;
    if (j == i || !parse_number(text.substr(i, j - i), !t.is_float, v))
      bad(path, what, ": voxel value ", k, " is missing or not a number");
    a->SetComponent(static_cast<vtkIdType>(k), 0, v);
    i = j;
  }
  return image;
}

/// Dimensions from text: 2 or 3 counts >= 1 (a third of 1 for 2-D), whose product fits in memory sizes.
std::array<Index, 3> parse_dims(std::string_view text, int ndims, const fs::path& path, const char* field) {
  std::array<Index, 3> d{1, 1, 1};
  std::size_t i = 0;
  double voxels = 1;
  for (int a = 0; a < ndims; ++a) {
    while (i < text.size() && is_space(text[i])) ++i;
    std::size_t j = i;
    while (j < text.size() && !is_space(text[j])) ++j;
    std::uint64_t v = 0;
    if (!parse_count(text.substr(i, j - i), v) || v < 1 || v > (1u << 30))
      bad(path, field, ": '", shown(text), "' needs ", ndims, " sizes >= 1");
    d[static_cast<std::size_t>(a)] = static_cast<Index>(v);
    voxels *= static_cast<double>(v);
    i = j;
  }
  if (voxels > 1e12) bad(path, field, ": ", shown(text), " is too many voxels");
  return d;
}

std::vector<double> parse_numbers(std::string_view text) {
  std::vector<double> out;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (is_space(text[i]) || text[i] == ',')) ++i;
    std::size_t j = i;
    while (j < text.size() && !is_space(text[j]) && text[j] != ',') ++j;
    if (j > i) {
      double v = 0;
      if (!parse_number(text.substr(i, j - i), false, v)) return {};
      out.push_back(v);
    }
    i = j;
  }
  return out;
}

/// The data file named by a header: beside the header unless absolute; a regular file (not a device
/// or a pipe that could block); one file only.
fs::path data_file_of(const fs::path& header, std::string_view name, const char* what) {
  const std::string n(name);
  if (n.find('%') != std::string::npos || lower(n).rfind("list", 0) == 0)
    bad(header, what, ": data file lists and patterns ('", shown(n), "') are not supported");
  fs::path p(n);
  if (p.is_relative()) p = header.parent_path() / p;
  std::error_code ec;
  if (!fs::is_regular_file(p, ec))
    bad(header, what, ": data file ", p.string(), " does not exist or is not a file");
  return p;
}

}  // namespace

// --- MetaImage -------------------------------------------------------------------------------------------

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

// --- NRRD ------------------------------------------------------------------------------------------------

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

// --- VTK XML binary data ------------------------------------------------------------------------------

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

// --- NIfTI -----------------------------------------------------------------------------------------------

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
