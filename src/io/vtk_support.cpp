#include "vtk_support.hpp"

#include <unistd.h>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkDoubleArray.h>
#include <vtkErrorCode.h>
#include <vtkIdTypeArray.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkOBJReader.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSTLReader.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtksys/SystemTools.hxx>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "safe_readers.hpp"

namespace fs = std::filesystem;

namespace medspring::io_detail {

// ---------------------------------------------------------------------------------------------------
// VTK message capture

namespace {

thread_local VtkMessageCapture* tl_capture = nullptr;

// VTK's class macros leave an empty declaration (';') that -Wpedantic reports.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpedantic"

/// Routes VTK's messages to the calling thread's innermost VtkMessageCapture; drops them otherwise.
class CaptureOutputWindow : public vtkOutputWindow {
 public:
  static CaptureOutputWindow* New();
  vtkTypeMacro(CaptureOutputWindow, vtkOutputWindow);

  void DisplayText(const char* text) override {
    route(this->GetCurrentMessageType() == vtkOutputWindow::MESSAGE_TYPE_ERROR, text);
  }
  void DisplayErrorText(const char* text) override { route(true, text); }
  void DisplayWarningText(const char* text) override { route(false, text); }
  void DisplayGenericWarningText(const char* text) override { route(false, text); }
  void DisplayDebugText(const char*) override {}

 protected:
  CaptureOutputWindow() = default;
  ~CaptureOutputWindow() override = default;

 private:
  static void route(bool error, const char* text) {
    if (tl_capture && text) tl_capture->add(error, text);
  }
};
vtkStandardNewMacro(CaptureOutputWindow);

#pragma GCC diagnostic pop

void install_capture_window() {
  static std::once_flag once;
  std::call_once(once, [] {
    vtkNew<CaptureOutputWindow> window;
    vtkOutputWindow::SetInstance(window);
    // VTK 9 also sends errors through vtkLogger, which prints to stderr on its own.
    vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
  });
}

bool is_executive_message(const std::string& text) {
  return text.find("returned failure for request") != std::string::npos;
}

/// "ERROR: In /src/vtkSTLReader.cxx, line 249\nvtkSTLReader (0x55d): Premature EOF\n\n" ->
/// "vtkSTLReader: Premature EOF".
std::string clean_message(const std::string& text) {
  std::string s = text;
  if (s.rfind("ERROR: In ", 0) == 0 || s.rfind("Warning: In ", 0) == 0 ||
      s.rfind("Generic Warning: In ", 0) == 0) {
    const auto nl = s.find('\n');
    s = nl == std::string::npos ? std::string() : s.substr(nl + 1);
  }
  // "<Class> (0x...): " -> "<Class>: "
  const auto open = s.find(" (0x");
  if (open != std::string::npos) {
    const auto close = s.find("): ", open);
    const auto nl = s.find('\n');
    if (close != std::string::npos && (nl == std::string::npos || close < nl))
      s = s.substr(0, open) + ": " + s.substr(close + 3);
  }
  // first non-empty line, trimmed
  std::istringstream in(s);
  std::string line;
  while (std::getline(in, line)) {
    const auto b = line.find_first_not_of(" \t\r");
    if (b == std::string::npos) continue;
    const auto e = line.find_last_not_of(" \t\r");
    return line.substr(b, e - b + 1);
  }
  return {};
}

}  // namespace

VtkMessageCapture::VtkMessageCapture() {
  install_capture_window();
  outer_ = tl_capture;
  tl_capture = this;
}

VtkMessageCapture::~VtkMessageCapture() {
  tl_capture = outer_;
}

void VtkMessageCapture::add(bool error, const char* text) {
  (error ? errors_ : warnings_).emplace_back(text);
}

std::string VtkMessageCapture::first_error() const {
  for (const auto& e : errors_)
    if (!is_executive_message(e)) return clean_message(e);
  return errors_.empty() ? std::string() : clean_message(errors_.front());
}

void VtkMessageCapture::throw_if_failed(const fs::path& file, vtkAlgorithm* algorithm) const {
  if (has_errors()) throw IoError(cat(name_of(file), ": ", first_error()));
  if (algorithm && algorithm->GetErrorCode() != vtkErrorCode::NoError)
    throw IoError(cat(name_of(file), ": ", algorithm->GetClassName(), " failed (",
                      vtkErrorCode::GetStringFromErrorCode(algorithm->GetErrorCode()), ")"));
}

// ---------------------------------------------------------------------------------------------------
// Files

std::string lower_extension(const fs::path& path) {
  std::string name = path.filename().string();
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  const fs::path p(name);
  std::string ext = p.extension().string();
  if (ext == ".gz") ext = p.stem().extension().string() + ext;
  return ext;
}

std::uintmax_t require_input_file(const fs::path& path) {
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (!fs::exists(st)) throw IoError(cat(name_of(path), ": no such file"));
  if (fs::is_directory(st)) throw IoError(cat(name_of(path), ": is a folder, not a file"));
  if (!fs::is_regular_file(st)) throw IoError(cat(name_of(path), ": not a regular file"));
  std::ifstream probe(path, std::ios::binary);
  if (!probe) throw IoError(cat(name_of(path), ": cannot be opened for reading"));
  return fs::file_size(path, ec);
}

void atomic_write(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  if (path.filename().empty()) throw IoError(cat(name_of(path), ": not a file name"));
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw IoError(cat(name_of(path), ": folder ", name_of(folder), " does not exist"));
  // "<path>.tmp-<pid><ext>": some writers (vtkPLYWriter, metaio) append their extension to a name
  // that lacks it, so the temporary keeps it.
  fs::path tmp = path;
  tmp += cat(".tmp-", ::getpid(), path.extension().string());
  try {
    write(tmp);
    if (!fs::is_regular_file(tmp, ec)) throw IoError(cat(name_of(path), ": nothing was written"));
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw IoError(cat(name_of(path), ": cannot rename the temporary file into place (", ec.message(), ")"));
  }
}

MeshFormat mesh_format(const fs::path& path, const char* what) {
  const std::string ext = lower_extension(path);
  if (ext == ".obj") return MeshFormat::Obj;
  if (ext == ".stl") return MeshFormat::Stl;
  if (ext == ".ply") return MeshFormat::Ply;
  if (ext == ".vtp") return MeshFormat::Vtp;
  if (ext == ".vtk") return MeshFormat::Vtk;
  throw IoError(cat(name_of(path), ": unknown ", what, " file extension '", ext,
                    "' (expected .obj, .stl, .ply, .vtp or .vtk)"));
}

const char* format_name(MeshFormat format) {
  switch (format) {
    case MeshFormat::Obj:
      return "OBJ";
    case MeshFormat::Stl:
      return "STL";
    case MeshFormat::Ply:
      return "PLY";
    case MeshFormat::Vtp:
      return "VTP";
    case MeshFormat::Vtk:
      return "VTK";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------------------
// Pre-checks where VTK accepts garbage

namespace {

bool parse_double(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && ptr == token.data() + token.size();
}

bool parse_long(std::string_view token, long& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && ptr == token.data() + token.size();
}

void split_ws(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    std::size_t j = i;
    while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
    if (j > i) tokens.push_back(line.substr(i, j - i));
    i = j;
  }
}

/// One kind of OBJ element (v, vt or vn) counted while scanning, with the references made before
/// the element was defined (legal in OBJ; checked against the final count at the end).
struct ObjCounter {
  ObjCounter(const char* singular, const char* plural_name) : what(singular), plural(plural_name) {}
  const char* what;
  const char* plural;
  long count = 0;
  std::vector<std::pair<long, long>> forward;  // (line, index) of positive indices beyond the count so far
};

}  // namespace

void check_obj_syntax(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(cat(name_of(path), ": cannot be opened for reading"));
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const std::string file = name_of(path);
  ObjCounter v{"vertex", "vertices"}, vt{"texture coordinate", "texture coordinates"},
      vn{"normal", "normals"};
  auto fail = [&](long line, const auto&... msg) { throw IoError(cat(file, ":", line, ": ", msg...)); };

  // Checks one index of a face/line/point reference against `c`; `ref` is the whole reference.
  auto check_index = [&](long line, std::string_view token, std::string_view ref, ObjCounter& c) {
    long k = 0;
    if (!parse_long(token, k)) fail(line, "'", ref, "': ", c.what, " index '", token, "' is not an integer");
    if (k == 0) fail(line, "'", ref, "': ", c.what, " index 0 (OBJ indices start at 1)");
    if (k < 0) {
      if (-k > c.count)
        fail(line, "'", ref, "': relative ", c.what, " index ", k, " reaches before the first ", c.what, " (",
             c.count, " so far)");
    } else if (k > c.count) {
      c.forward.emplace_back(line, k);
    }
  };

  std::vector<std::string_view> tokens;
  long line_no = 0;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string_view raw(text.data() + start, end - start);
    start = end + 1;
    ++line_no;
    split_ws(raw, tokens);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    const std::string_view key = tokens[0];
    if (key == "v" || key == "vt" || key == "vn") {
      const std::size_t need = key == "vt" ? 1 : 3;
      if (tokens.size() - 1 < need)
        fail(line_no, "'", key, "' needs ", need, need == 1 ? " coordinate" : " coordinates", ", got ",
             tokens.size() - 1);
      for (std::size_t t = 1; t < tokens.size(); ++t) {
        double x = 0;
        if (tokens[t].front() == '#') break;
        if (!parse_double(tokens[t], x))
          fail(line_no, "'", key, "' coordinate '", tokens[t], "' is not a number");
        if (!std::isfinite(x)) fail(line_no, "'", key, "' coordinate '", tokens[t], "' is not finite");
      }
      ++(key == "v" ? v : key == "vt" ? vt : vn).count;
    } else if (key == "f" || key == "l" || key == "p") {
      const std::size_t need = key == "f" ? 3 : key == "l" ? 2 : 1;
      std::size_t refs = 0;
      for (std::size_t t = 1; t < tokens.size(); ++t) {
        const std::string_view ref = tokens[t];
        if (ref.front() == '#') break;
        ++refs;
        // v, v/t, v//n, v/t/n
        const auto s1 = ref.find('/');
        check_index(line_no, ref.substr(0, s1), ref, v);
        if (s1 != std::string_view::npos) {
          const auto rest = ref.substr(s1 + 1);
          const auto s2 = rest.find('/');
          const auto t_part = rest.substr(0, s2);
          if (!t_part.empty()) check_index(line_no, t_part, ref, vt);
          if (s2 != std::string_view::npos) {
            const auto n_part = rest.substr(s2 + 1);
            if (n_part.empty() || n_part.find('/') != std::string_view::npos)
              fail(line_no, "'", ref, "': malformed vertex reference");
            check_index(line_no, n_part, ref, vn);
          } else if (t_part.empty()) {
            fail(line_no, "'", ref, "': malformed vertex reference");
          }
        }
      }
      if (refs < need)
        fail(line_no, "'", key, "' needs at least ", need, need == 1 ? " vertex" : " vertices", ", got ",
             refs);
    }
  }
  for (const ObjCounter* c : {&v, &vt, &vn})
    for (const auto& [line, k] : c->forward)
      if (k > c->count)
        fail(line, c->what, " index ", k, " out of range (the file has ", c->count, " ",
             c->count == 1 ? c->what : c->plural, ")");
}

void check_stl_size(const fs::path& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(cat(name_of(path), ": cannot be opened for reading"));
  // The same test as vtkSTLReader::GetSTLFileType: a file is ASCII when vtksys calls its first 256
  // bytes text (under 5 % of them binary). A file that starts with "solid" but holds a few NUL bytes is
  // binary to VTK, so its triangle count must be checked too (fuzz/regressions/mesh_stl).
  const bool ascii = vtksys::SystemTools::DetectFileType(path.string().c_str()) == vtksys::SystemTools::FileTypeText;
  if (ascii) return;  // ASCII STL: vtkSTLReader's line parser reports every error
  if (size < 84)
    throw IoError(
        cat(name_of(path), ": not an STL file (", size, " bytes: too short for a binary STL header)"));
  std::uint32_t n = 0;
  in.clear();
  in.seekg(80);
  in.read(reinterpret_cast<char*>(&n), 4);  // little-endian triangle count (x86)
  const std::uintmax_t need = 84 + 50 * static_cast<std::uintmax_t>(n);
  if (size < need)
    throw IoError(cat(name_of(path), ": truncated binary STL: the header announces ", n, " triangles (", need,
                      " bytes), the file has ", size, " bytes"));
}

// ---------------------------------------------------------------------------------------------------
// Reading polydata

namespace {

void check_cell_indices(vtkCellArray* cells, vtkIdType npoints, const char* kind, const fs::path& path) {
  if (!cells) return;
  auto it = vtk::TakeSmartPointer(cells->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    it->GetCurrentCell(n, ids);
    for (vtkIdType k = 0; k < n; ++k)
      if (ids[k] < 0 || ids[k] >= npoints)
        throw IoError(cat(name_of(path), ": ", kind, " ", it->GetCurrentCellId(), " references point ",
                          ids[k], " out of range [0, ", npoints, ")"));
  }
}

template <class Reader>
vtkSmartPointer<vtkPolyData> run_reader(Reader* reader, const fs::path& path, VtkMessageCapture& capture) {
  guard_vtk(path, [&] { reader->Update(); });
  capture.throw_if_failed(path, reader);
  vtkSmartPointer<vtkPolyData> out = reader->GetOutput();
  if (!out) throw IoError(cat(name_of(path), ": ", reader->GetClassName(), " produced no output"));
  return out;
}

}  // namespace

vtkSmartPointer<vtkPolyData> read_polydata(const fs::path& path, MeshFormat format) {
  const std::uintmax_t size = require_input_file(path);
  if (size == 0) throw IoError(cat(name_of(path), ": file is empty"));
  VtkMessageCapture capture;
  const std::string file = path.string();
  vtkSmartPointer<vtkPolyData> poly;
  switch (format) {
    case MeshFormat::Obj: {
      check_obj_syntax(path);
      vtkNew<vtkOBJReader> reader;
      reader->SetFileName(file.c_str());
      poly = run_reader(reader.Get(), path, capture);
      break;
    }
    case MeshFormat::Stl: {
      check_stl_size(path, size);
      vtkNew<vtkSTLReader> reader;
      reader->SetFileName(file.c_str());
      reader->MergingOff();  // welding is done by the engine's weld_vertices (same rule for every format)
      poly = run_reader(reader.Get(), path, capture);
      break;
    }
    case MeshFormat::Ply:  // vtkPLYReader frees uninitialised pointers on a short file: our reader
      poly = read_ply(path);
      break;
    case MeshFormat::Vtp: {
      vtkNew<vtkXMLPolyDataReader> reader;
      if (!guard_vtk(path, [&] { return reader->CanReadFile(file.c_str()); })) {
        capture.throw_if_failed(path);
        throw IoError(cat(name_of(path), ": not a VTK XML PolyData file"));
      }
      check_vtk_xml(path);  // vtkXMLDataParser allocates whatever the size headers say
      reader->SetFileName(file.c_str());
      poly = run_reader(reader.Get(), path, capture);
      break;
    }
    case MeshFormat::Vtk:  // vtkPolyDataReader reads a closed stream after a bad cell list: our reader
      poly = read_vtk_legacy(path);
      break;
  }
  const vtkIdType n = poly->GetNumberOfPoints();
  check_cell_indices(poly->GetPolys(), n, "polygon", path);
  check_cell_indices(poly->GetStrips(), n, "triangle strip", path);
  check_cell_indices(poly->GetLines(), n, "line", path);
  check_cell_indices(poly->GetVerts(), n, "vertex cell", path);
  return poly;
}

// ---------------------------------------------------------------------------------------------------
// Writing polydata

vtkSmartPointer<vtkPolyData> make_polydata(const MatX3& points, const MatX3i* triangles,
                                           const std::vector<std::vector<Index>>* lines,
                                           const std::vector<PointArray>& point_data) {
  const Index n = static_cast<Index>(points.rows());
  require_finite_points(points, "points");
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  pts->SetNumberOfPoints(n);
  for (Index i = 0; i < n; ++i) pts->SetPoint(i, points(i, 0), points(i, 1), points(i, 2));
  poly->SetPoints(pts);
  if (triangles) {
    vtkNew<vtkCellArray> cells;
    cells->AllocateExact(triangles->rows(), 3 * triangles->rows());
    for (Index f = 0; f < triangles->rows(); ++f) {
      vtkIdType ids[3];
      for (int k = 0; k < 3; ++k) {
        const Index v = (*triangles)(f, k);
        require_index(v, n, cat("face ", f));
        ids[k] = v;
      }
      cells->InsertNextCell(3, ids);
    }
    poly->SetPolys(cells);
  }
  if (lines) {
    vtkNew<vtkCellArray> cells;
    for (std::size_t l = 0; l < lines->size(); ++l) {
      const auto& line = (*lines)[l];
      require(line.size() >= 2, "line ", l, ": needs at least 2 points, got ", line.size());
      std::vector<vtkIdType> ids(line.size());
      for (std::size_t k = 0; k < line.size(); ++k) {
        require_index(line[k], n, cat("line ", l, " point ", k));
        ids[k] = line[k];
      }
      cells->InsertNextCell(static_cast<vtkIdType>(ids.size()), ids.data());
    }
    poly->SetLines(cells);
  }
  std::set<std::string> names;
  for (const auto& a : point_data) {
    require(!a.name.empty(), "point array: name must not be empty");
    require(names.insert(a.name).second, "point array '", a.name, "': name used twice");
    vtkNew<vtkDoubleArray> arr;
    arr->SetName(a.name.c_str());
    if (const auto* s = std::get_if<VecX>(&a.values)) {
      require(s->size() == n, "point array '", a.name, "': ", s->size(), " values for ", n, " points");
      arr->SetNumberOfComponents(1);
      arr->SetNumberOfTuples(n);
      for (Index i = 0; i < n; ++i) arr->SetValue(i, (*s)(i));
    } else {
      const auto& m = std::get<MatX3>(a.values);
      require(m.rows() == n, "point array '", a.name, "': ", m.rows(), " rows for ", n, " points");
      arr->SetNumberOfComponents(3);
      arr->SetNumberOfTuples(n);
      for (Index i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) arr->SetValue(3 * static_cast<vtkIdType>(i) + c, m(i, c));
    }
    poly->GetPointData()->AddArray(arr);
  }
  return poly;
}

void write_vtp_file(const fs::path& file, vtkPolyData* poly, const fs::path& target) {
  VtkMessageCapture capture;
  vtkNew<vtkXMLPolyDataWriter> writer;
  const std::string name = file.string();
  writer->SetFileName(name.c_str());
  writer->SetInputData(poly);
  writer->SetDataModeToAppended();
  writer->SetCompressorTypeToZLib();
  writer->SetHeaderTypeToUInt64();
  const int ok = writer->Write();
  capture.throw_if_failed(target, writer);
  if (!ok) throw IoError(cat(name_of(target), ": vtkXMLPolyDataWriter failed"));
}

}  // namespace medspring::io_detail
