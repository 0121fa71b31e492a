// The legacy VTK POLYDATA reader (safe_readers.hpp). Why our own: VTK 9.1's vtkPolyDataReader
// dereferences a closed stream after a bad cell list (fuzz/regressions/).
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

namespace {

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

}  // namespace

vtkSmartPointer<vtkPolyData> read_vtk_legacy(const fs::path& path) {
  const std::string bytes = read_all(path);
  return LegacyVtk(path, bytes).read();
}

}  // namespace medspring::io_detail
