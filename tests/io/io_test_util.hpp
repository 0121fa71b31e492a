// Helpers shared by the io tests.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "medspring/core/error.hpp"
#include "medspring/geometry/surface_mesh.hpp"

namespace medspring::testing {

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Runs `f`, expecting an IoError or InvalidInput whose message contains `needle` (e.g. the file
/// name and line), and nothing printed to stderr (VTK must stay quiet). Returns the message.
inline std::string expect_error_naming(const std::function<void()>& f, const std::string& needle) {
  ::testing::internal::CaptureStderr();
  std::string message;
  bool thrown = false;
  try {
    f();
  } catch (const IoError& e) {
    message = e.what();
    thrown = true;
  } catch (const InvalidInput& e) {
    message = e.what();
    thrown = true;
  }
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_TRUE(thrown) << "no IoError/InvalidInput thrown (expected one naming '" << needle << "')";
  EXPECT_NE(message.find(needle), std::string::npos)
      << "message: " << message << "\nexpected to contain: " << needle;
  EXPECT_EQ(err, "") << "something was printed to stderr";
  return message;
}

/// |a - b| <= 2^-24 |a| for every coordinate: b is a rounded to float (what a Float32 file stores).
inline void expect_float_rounding_of(const MatX3& a, const MatX3& b) {
  ASSERT_EQ(a.rows(), b.rows());
  for (Index i = 0; i < a.rows(); ++i)
    for (int c = 0; c < 3; ++c)
      ASSERT_LE(std::abs(a(i, c) - b(i, c)), std::ldexp(std::abs(a(i, c)), -24))
          << "vertex " << i << " axis " << c;
}

}  // namespace medspring::testing
