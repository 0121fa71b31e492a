// The PLY reader (safe_readers.hpp). Why our own: vtkPLYReader frees uninitialised pointers on a short
// file (fuzz/regressions/).
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

}  // namespace medspring::io_detail
