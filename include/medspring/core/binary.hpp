// Little-endian binary files of MedSpring (checkpoints, model packages): a framed payload
//   magic (8 bytes) | version u32 | flags u32 | payload size u64 | FNV-1a 64 of the payload | payload
// written atomically and read back with every length checked. Independent of the host byte order.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <string_view>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/core/types.hpp"

namespace medspring {

/// FNV-1a 64-bit hash of n bytes, continuing from `h` (default: the FNV offset basis).
std::uint64_t fnv1a64(const void* data, std::size_t n, std::uint64_t h = 0xcbf29ce484222325ULL);

/// "0x" + 16 hex digits.
std::string hex64(std::uint64_t v);

/// Appends little-endian values to a byte string.
class ByteWriter {
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int b = 0; b < 4; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
  }
  void u64(std::uint64_t v) {
    for (int b = 0; b < 8; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v) {
    std::uint64_t u;
    std::memcpy(&u, &v, sizeof u);
    u64(u);
  }
  void flag(bool v) { u8(v ? 1 : 0); }
  /// u32 length + bytes (truncated to max_len).
  void str(std::string_view s, std::size_t max_len = 4096) {
    s = s.substr(0, max_len);
    u32(static_cast<std::uint32_t>(s.size()));
    out_.append(s.data(), s.size());
  }
  void doubles(const double* p, Index n) {
    for (Index k = 0; k < n; ++k) f64(p[k]);
  }
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

/// Reads little-endian values; every failure throws IoError "<what>: malformed <kind>: ... (at payload
/// byte N)".
class ByteReader {
 public:
  ByteReader(std::string_view bytes, std::string what, std::string kind)
      : b_(bytes), what_(std::move(what)), kind_(std::move(kind)) {}
  std::uint8_t u8() {
    need(1);
    return static_cast<std::uint8_t>(b_[pos_++]);
  }
  std::uint32_t u32() {
    need(4);
    std::uint32_t v = 0;
    for (int b = 0; b < 4; ++b) v |= std::uint32_t{static_cast<std::uint8_t>(b_[pos_++])} << (8 * b);
    return v;
  }
  std::uint64_t u64() {
    need(8);
    std::uint64_t v = 0;
    for (int b = 0; b < 8; ++b) v |= std::uint64_t{static_cast<std::uint8_t>(b_[pos_++])} << (8 * b);
    return v;
  }
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  std::int64_t i64() { return static_cast<std::int64_t>(u64()); }
  double f64() {
    const std::uint64_t u = u64();
    double v;
    std::memcpy(&v, &u, sizeof v);
    return v;
  }
  bool flag(const char* field) {
    const std::uint8_t v = u8();
    if (v > 1) fail(cat(field, ": expected 0 or 1 (got ", int{v}, ")"));
    return v == 1;
  }
  std::string str(const char* field, std::size_t max_len = 4096) {
    const std::uint32_t n = u32();
    if (n > max_len) fail(cat(field, ": length ", n, " exceeds ", max_len));
    need(n);
    std::string s(b_.substr(pos_, n));
    pos_ += n;
    return s;
  }
  /// A count (u64) of items of `item_bytes` each that must fit in the remaining bytes.
  Index count(const char* field, std::size_t item_bytes) {
    const std::uint64_t n = u64();
    if (n > static_cast<std::uint64_t>(std::numeric_limits<Index>::max()) ||
        (item_bytes > 0 && n > left() / item_bytes))
      fail(cat(field, ": count ", n, " does not fit in the remaining ", left(), " bytes"));
    return static_cast<Index>(n);
  }
  void doubles(double* p, Index n) {
    for (Index k = 0; k < n; ++k) p[k] = f64();
  }
  std::size_t left() const { return b_.size() - pos_; }
  std::size_t position() const { return pos_; }
  /// Fails unless every byte was read.
  void finish() const {
    if (left() != 0) fail(cat(left(), " unread bytes at the end of the payload"));
  }
  [[noreturn]] void fail(const std::string& msg) const {
    throw IoError(cat(what_, ": malformed ", kind_, ": ", msg, " (at payload byte ", pos_, ")"));
  }

 private:
  void need(std::size_t n) const {
    if (left() < n) fail(cat("needs ", n, " more bytes, ", left(), " left"));
  }
  std::string_view b_;
  std::string what_, kind_;
  std::size_t pos_ = 0;
};

/// Size of the frame header: magic, version, flags, payload size, checksum.
inline constexpr std::size_t kFrameHeaderSize = 8 + 4 + 4 + 8 + 8;

/// Header + payload. `magic` has 8 characters.
std::string frame_payload(const char* magic, std::uint32_t version, const std::string& payload);

/// The payload of framed bytes, after checking magic, version, flags, size and checksum. Throws
/// IoError "<what>: truncated <kind> ...", "not a MedSpring <kind> (bad magic)", "unsupported <kind>
/// version", "corrupted <kind> (checksum ...)".
/// Versions min_version..max_version are accepted; the one read is stored in *version when given.
std::string_view unframe_payload(std::string_view bytes, const char* magic, std::uint32_t min_version,
                                 std::uint32_t max_version, const std::string& kind, const std::string& what,
                                 std::uint32_t* version = nullptr);

/// Writes bytes to `path` atomically: a temporary file beside it, renamed over `path`. On failure the
/// temporary file is removed, `path` is unchanged and IoError "<path>: cannot write <kind>: ..." is thrown.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes,
                           const std::string& kind);

/// The whole file (IoError "<path>: cannot open <kind>" / "read error").
std::string read_file_bytes(const std::filesystem::path& path, const std::string& kind);

}  // namespace medspring
