// `medspring build` end to end: the files it writes, its summary, and errors that leave nothing behind.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "medspring/io/centerline_io.hpp"
#include "medspring/io/volume_io.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;

struct CliRun {
  int code = -1;
  std::string out, err;
};

/// Runs `medspring <args>` with stdout and stderr captured in files of `dir`.
CliRun run_cli(const std::string& args, const fs::path& dir) {
  const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string cmd = std::string("\"") + MEDSPRING_CLI + "\" " + args + " >\"" + out.string() +
                          "\" 2>\"" + err.string() + "\"";
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  auto slurp = [](const fs::path& p) {
    std::ifstream f(p);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  };
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

TEST(CliBuild, CenterlineOfTheAortaMaskWritesFilesAndAJsonSummary) {
  const fs::path tmp = testing::temp_dir("cli-centerline");
  const fs::path mask = testing::require_data_file("aorta_totalseg_mask.nii.gz");
  const CliRun r = run_cli("build centerline --mask \"" + mask.string() + "\" --label 1 --out \"" +
                               (tmp / "aorta").string() + "\" --json",
                           tmp);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"atoms\": 40"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"open\""), std::string::npos) << r.out;
  for (const char* f : {"centerline.vtp", "curve.vtp", "surface.vtp", "summary.json"})
    EXPECT_TRUE(fs::exists(tmp / "aorta" / f)) << f;
  const auto lines = read_centerlines(tmp / "aorta" / "centerline.vtp");
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].size(), 40);
}

TEST(CliBuild, ErrorsExitNonZeroWithOneLineAndWriteNothing) {
  const fs::path tmp = testing::temp_dir("cli-errors");
  LabelVolume empty;
  empty.dims = {6, 6, 6};
  empty.data.assign(empty.size(), 0);
  write_label_volume(tmp / "empty.mha", empty);
  const CliRun r = run_cli("build kidney --mask \"" + (tmp / "empty.mha").string() + "\" --out \"" +
                               (tmp / "model").string() + "\"",
                           tmp);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("medspring build: error: empty.mha: mask is empty"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "model"));

  // a non-empty output folder is refused before any work, and left as it was
  fs::create_directories(tmp / "busy");
  std::ofstream(tmp / "busy" / "keep.txt") << "keep";
  const fs::path mask = testing::require_data_file("aorta_totalseg_mask.nii.gz");
  const CliRun busy = run_cli(
      "build centerline --mask \"" + mask.string() + "\" --out \"" + (tmp / "busy").string() + "\"", tmp);
  EXPECT_EQ(busy.code, 1);
  EXPECT_NE(busy.err.find("not empty; use --force"), std::string::npos) << busy.err;
  EXPECT_TRUE(fs::exists(tmp / "busy" / "keep.txt"));
  EXPECT_EQ(std::distance(fs::directory_iterator(tmp / "busy"), fs::directory_iterator()), 1);

  const CliRun unknown = run_cli("build organ --out x", tmp);
  EXPECT_EQ(unknown.code, 1);
  EXPECT_NE(unknown.err.find("unknown kind 'organ' (known: kidney, centerline)"), std::string::npos)
      << unknown.err;
}

}  // namespace
}  // namespace medspring
