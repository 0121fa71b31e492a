#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

namespace medspring::testing {

std::filesystem::path data_dir() {
  if (const char* env = std::getenv("MEDSPRING_DATA"); env && *env) return env;
  return MEDSPRING_DEFAULT_DATA_DIR;
}

std::filesystem::path data_file(const std::string& name) {
  return data_dir() / name;
}

std::filesystem::path require_data_file(const std::string& name) {
  auto p = data_file(name);
  if (!std::filesystem::exists(p)) ADD_FAILURE() << "missing data file " << p << " (set MEDSPRING_DATA)";
  return p;
}

std::filesystem::path temp_dir(const std::string& tag) {
  std::random_device rd;
  auto p = std::filesystem::temp_directory_path() / ("medspring-test-" + tag + "-" + std::to_string(rd()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

}  // namespace medspring::testing
