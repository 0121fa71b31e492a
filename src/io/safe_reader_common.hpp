// Private to the safe readers (safe_readers.hpp): the bounded cursor and the number, text and voxel
// helpers that every format's reader shares. Every read is checked against the bytes left; errors are
// IoError "<file>: <what is wrong>" (bad()).
#pragma once

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
#include "safe_readers.hpp"
#include "vtk_support.hpp"

namespace fs = std::filesystem;

namespace medspring::io_detail::reader {

template <class... Args>
[[noreturn]] void bad(const fs::path& path, const Args&... args) {
  throw IoError(cat(name_of(path), ": ", args...));
}

inline std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) bad(path, "cannot be opened for reading");
  std::string s{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) bad(path, "read error");
  return s;
}

inline std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return std::tolower(c); });
  return out;
}

/// Printable for messages: at most 40 characters, control bytes as '?'.
inline std::string shown(std::string_view s) {
  std::string out(s.substr(0, 40));
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return s.size() > 40 ? out + "..." : out;
}

inline bool is_space(char c) {
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

inline constexpr NumType kI8{1, false, true, VTK_SIGNED_CHAR}, kU8{1, false, false, VTK_UNSIGNED_CHAR},
    kI16{2, false, true, VTK_SHORT}, kU16{2, false, false, VTK_UNSIGNED_SHORT}, kI32{4, false, true, VTK_INT},
    kU32{4, false, false, VTK_UNSIGNED_INT}, kI64{8, false, true, VTK_LONG_LONG},
    kU64{8, false, false, VTK_UNSIGNED_LONG_LONG}, kF32{4, true, true, VTK_FLOAT},
    kF64{8, true, true, VTK_DOUBLE};

/// Reads one binary value (little- or big-endian) as double (integers above 2^53 lose precision).
inline double decode(const char* p, const NumType& t, bool big_endian) {
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
inline bool parse_number(std::string_view tok, bool integer, double& out) {
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

inline bool parse_count(std::string_view tok, std::uint64_t& out) {
  if (tok.empty() || tok.front() == '-') return false;
  if (tok.front() == '+') tok.remove_prefix(1);
  const auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  return ec == std::errc() && p == tok.data() + tok.size();
}

/// A value read as double that must be an exact integer in [lo, hi].
inline bool exact_integer(double v, double lo, double hi) {
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

// --- compressed data and voxels (MetaImage, NRRD) --------------------------------------------------------

/// Inflates a zlib or gzip stream (and the gzip members that follow it) until it ends or `max_out`
/// bytes came out; bytes after the last stream that do not start a gzip member are ignored, as zlib's
/// gzread does. A stream cut short gives what it holds (callers compare sizes). Throws IoError for
/// corrupt data.
inline std::string inflate_prefix(std::string_view in, std::size_t max_out, const fs::path& path,
                                  const char* what) {
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
inline vtkSmartPointer<vtkImageData> image_from_binary(const std::array<Index, 3>& dims, const NumType& t,
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
inline void set_voxels(RawVolume& out, const NumType& t, std::string_view data, std::size_t need,
                       bool big_endian, const fs::path& path, const char* format) {
  if (data.size() < need)
    bad(path, format, ": truncated data (", data.size(), " of ", need, " bytes for ", out.dims[0], " x ",
        out.dims[1], " x ", out.dims[2], " voxels)");
  out.image = image_from_binary(out.dims, t, data.data(), big_endian);
}

/// The same from text: `n` whitespace-separated numbers from `text`.
inline vtkSmartPointer<vtkImageData> image_from_text(const std::array<Index, 3>& dims, const NumType& t,
                                                     std::string_view text, const fs::path& path,
                                                     const char* what) {
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
inline std::array<Index, 3> parse_dims(std::string_view text, int ndims, const fs::path& path,
                                       const char* field) {
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

inline std::vector<double> parse_numbers(std::string_view text) {
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
inline fs::path data_file_of(const fs::path& header, std::string_view name, const char* what) {
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

}  // namespace medspring::io_detail::reader
