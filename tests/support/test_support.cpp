#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <system_error>
#include <vector>

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

namespace {

/// The folders made by temp_dir, removed when the process exits — unless a test failed (they are then
/// kept for a look) or MEDSPRING_KEEP_TEST_FILES is set.
struct TempDirs {
  std::vector<std::filesystem::path> dirs;
  ~TempDirs() {
    if (const char* keep = std::getenv("MEDSPRING_KEEP_TEST_FILES"); keep && *keep) return;
    if (::testing::UnitTest::GetInstance()->Failed()) return;
    std::error_code ec;
    for (const auto& d : dirs) std::filesystem::remove_all(d, ec);
  }
};

}  // namespace

std::filesystem::path temp_dir(const std::string& tag) {
  static TempDirs made;
  std::random_device rd;
  auto p = std::filesystem::temp_directory_path() / ("medspring-test-" + tag + "-" + std::to_string(rd()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  made.dirs.push_back(p);
  return p;
}

}  // namespace medspring::testing
