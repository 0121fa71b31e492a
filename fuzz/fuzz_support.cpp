#include "fuzz_support.hpp"

#include <unistd.h>

#include <fstream>
#include <system_error>

namespace fs = std::filesystem;

namespace medspring::fuzz {

namespace {

struct Scratch {
  fs::path dir;
  Scratch() {
    fs::path base;
    std::error_code ec;
    if (const char* env = std::getenv("MEDSPRING_FUZZ_TMP"); env && *env)
      base = env;
    else if (fs::is_directory("/dev/shm", ec) && ::access("/dev/shm", W_OK) == 0)
      base = "/dev/shm";
    else
      base = fs::temp_directory_path(ec);
    dir = base / ("medspring-fuzz-" + std::to_string(::getpid()));
    fs::create_directories(dir, ec);
    if (ec) {
      std::fprintf(stderr, "fuzz: cannot create %s: %s\n", dir.c_str(), ec.message().c_str());
      std::abort();
    }
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

}  // namespace

const fs::path& scratch_dir() {
  static Scratch s;
  return s.dir;
}

fs::path write_scratch(const std::uint8_t* data, std::size_t size, const std::string& ext) {
  fs::path p = scratch_dir() / ("input" + ext);
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  f.close();
  if (!f) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", p.c_str());
    std::abort();
  }
  return p;
}

bool verbose() {
  static const bool v = std::getenv("MEDSPRING_FUZZ_VERBOSE") != nullptr;
  return v;
}

void report_bug(const char* what, const std::string& detail) {
  std::fprintf(stderr, "\n==medspring-fuzz== BUG: %s\n==medspring-fuzz== %s\n", what, detail.c_str());
  std::fflush(stderr);
  std::abort();
}

}  // namespace medspring::fuzz
