#include "medspring/io/data_dir.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>

#include "io_test_util.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;

/// Sets or unsets MEDSPRING_DATA for one scope and restores the previous value.
class ScopedDataEnv {
 public:
  explicit ScopedDataEnv(const std::optional<std::string>& value) {
    if (const char* old = std::getenv("MEDSPRING_DATA")) old_ = old;
    if (value)
      ::setenv("MEDSPRING_DATA", value->c_str(), 1);
    else
      ::unsetenv("MEDSPRING_DATA");
  }
  ~ScopedDataEnv() {
    if (old_)
      ::setenv("MEDSPRING_DATA", old_->c_str(), 1);
    else
      ::unsetenv("MEDSPRING_DATA");
  }

 private:
  std::optional<std::string> old_;
};

TEST(DataDir, EnvironmentVariableWins) {
  const fs::path dir = testing::temp_dir("datadir");
  testing::write_text(dir / "x.obj", "v 0 0 0\n");
  ScopedDataEnv env(dir.string());
  EXPECT_EQ(data_dir(), dir);
  EXPECT_EQ(find_data_file("x.obj"), dir / "x.obj");
}

TEST(DataDir, DefaultIsTheConfiguredFolderWithTheRealData) {
  ScopedDataEnv env(std::nullopt);
  EXPECT_EQ(data_dir(), testing::data_dir());  // both compiled from MEDSPRING_DATA_DIR
  EXPECT_TRUE(fs::is_regular_file(find_data_file("kidney_left_hubmap_vhm.obj")));
}

TEST(DataDir, EmptyEnvironmentVariableMeansUnset) {
  ScopedDataEnv env{std::string()};
  EXPECT_EQ(data_dir(), testing::data_dir());
}

TEST(DataDir, MissingFileNamesFileFolderAndTheVariable) {
  const fs::path dir = testing::temp_dir("datadir-missing");
  ScopedDataEnv env(dir.string());
  testing::expect_error_naming([] { find_data_file("nope.obj"); },
                               "data file nope.obj not found in " + dir.string() + " (set MEDSPRING_DATA)");
}

}  // namespace
}  // namespace medspring
