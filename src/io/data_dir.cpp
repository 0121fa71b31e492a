#include "medspring/io/data_dir.hpp"

#include <cstdlib>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"

#ifndef MEDSPRING_IO_DEFAULT_DATA_DIR
#error "MEDSPRING_IO_DEFAULT_DATA_DIR must be defined by the build (CMake cache variable MEDSPRING_DATA_DIR)"
#endif

namespace medspring {

std::filesystem::path data_dir() {
  if (const char* env = std::getenv("MEDSPRING_DATA"); env && *env) return env;
  return MEDSPRING_IO_DEFAULT_DATA_DIR;
}

std::filesystem::path find_data_file(const std::string& name) {
  const std::filesystem::path dir = data_dir();
  const std::filesystem::path file = dir / name;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw IoError(cat("data file ", name, " not found in ", dir.string(), " (set MEDSPRING_DATA)"));
  return file;
}

}  // namespace medspring
