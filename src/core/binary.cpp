#include "medspring/core/binary.hpp"

#include <atomic>
#include <fstream>
#include <iterator>
#include <random>
#include <system_error>

namespace medspring {

std::uint64_t fnv1a64(const void* data, std::size_t n, std::uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t k = 0; k < n; ++k) {
    h ^= p[k];
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::string hex64(std::uint64_t v) {
  static const char* digits = "0123456789abcdef";
  std::string s = "0x";
  for (int b = 15; b >= 0; --b) s += digits[(v >> (4 * b)) & 0xF];
  return s;
}

std::string frame_payload(const char* magic, std::uint32_t version, const std::string& payload) {
  ByteWriter out;
  for (int k = 0; k < 8; ++k) out.u8(static_cast<std::uint8_t>(magic[k]));
  out.u32(version);
  out.u32(0);  // flags (reserved)
  out.u64(payload.size());
  out.u64(fnv1a64(payload.data(), payload.size()));
  out.bytes() += payload;
  return std::move(out.bytes());
}

std::string_view unframe_payload(std::string_view bytes, const char* magic, std::uint32_t min_version,
                                 std::uint32_t max_version, const std::string& kind, const std::string& what,
                                 std::uint32_t* version) {
  if (bytes.size() < kFrameHeaderSize)
    throw IoError(cat(what, ": truncated ", kind, " (", bytes.size(), " bytes, the header alone has ",
                      kFrameHeaderSize, ")"));
  if (bytes.substr(0, 8) != std::string_view(magic, 8))
    throw IoError(cat(what, ": not a MedSpring ", kind, " (bad magic)"));
  ByteReader h(bytes.substr(8, kFrameHeaderSize - 8), what, kind);
  const std::uint32_t v = h.u32();
  if (v < min_version || v > max_version)
    throw IoError(cat(what, ": unsupported ", kind, " version ", v, " (this build reads version ",
                      min_version == max_version ? cat(max_version) : cat(min_version, "-", max_version),
                      ")"));
  if (version != nullptr) *version = v;
  const std::uint32_t flags = h.u32();
  if (flags != 0) throw IoError(cat(what, ": unsupported ", kind, " flags ", flags));
  const std::uint64_t size = h.u64();
  const std::uint64_t sum = h.u64();
  const std::string_view payload = bytes.substr(kFrameHeaderSize);
  if (payload.size() < size)
    throw IoError(cat(what, ": truncated ", kind, " (payload has ", payload.size(), " of ", size, " bytes)"));
  if (payload.size() > size)
    throw IoError(cat(what, ": corrupted ", kind, " (", payload.size() - size, " bytes after the payload)"));
  const std::uint64_t actual = fnv1a64(payload.data(), payload.size());
  if (actual != sum)
    throw IoError(
        cat(what, ": corrupted ", kind, " (checksum ", hex64(actual), ", the header says ", hex64(sum), ")"));
  return payload;
}

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes,
                           const std::string& kind) {
  namespace fs = std::filesystem;
  static std::atomic<unsigned> counter{0};
  std::random_device rd;
  const fs::path tmp = fs::path(path).concat(cat(".tmp-", rd(), "-", counter++));
  auto fail = [&](const std::string& why) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw IoError(cat(path.string(), ": cannot write ", kind, ": ", why));
  };
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) fail(cat("cannot create ", tmp.string()));
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    f.flush();
    if (!f) fail(cat("write to ", tmp.string(), " failed"));
    f.close();
    if (f.fail()) fail(cat("closing ", tmp.string(), " failed"));
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);  // atomic replacement on POSIX file systems
  if (ec) fail(cat("rename from ", tmp.string(), " failed: ", ec.message()));
}

std::string read_file_bytes(const std::filesystem::path& path, const std::string& kind) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw IoError(cat(path.string(), ": cannot open ", kind));
  std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw IoError(cat(path.string(), ": read error"));
  return bytes;
}

}  // namespace medspring
