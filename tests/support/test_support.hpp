// Helpers shared by the test suites.
#pragma once

#include <filesystem>
#include <random>
#include <string>

#include "medspring/core/types.hpp"

namespace medspring::testing {

/// The real-anatomy data folder: $MEDSPRING_DATA if set, else the configured default
/// (../shared/data beside the source tree). Empty path if neither exists.
std::filesystem::path data_dir();

/// Path of a file in data_dir(); GTEST_SKIP is the caller's choice when it is missing, but CI always
/// has the data, so tests on real anatomy use require_data_file which fails instead.
std::filesystem::path data_file(const std::string& name);

/// Like data_file, but fails the current test (ADD_FAILURE) when the file does not exist.
std::filesystem::path require_data_file(const std::string& name);

/// A fresh, empty temporary folder for one test, removed at exit of the process when every test passed
/// (kept after a failure, or always with MEDSPRING_KEEP_TEST_FILES=1).
std::filesystem::path temp_dir(const std::string& tag);

/// x with every coordinate moved by a uniform random amount in [-amp, amp] (std::mt19937 seeded with seed).
inline MatX3 jitter(const MatX3& x, double amp, unsigned seed) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> u(-amp, amp);
  MatX3 y = x;
  for (Index i = 0; i < y.size(); ++i) y.data()[i] += u(g);
  return y;
}

}  // namespace medspring::testing
