// `medspring haptics --tool` and `medspring run` with a tools scene, end to end: outputs, trace columns,
// and bad input failing with one line and a non-zero exit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;
const fs::path kExamples = MEDSPRING_EXAMPLES_DIR;

struct Result {
  int rc = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Result medspring(const std::string& args) {
  static int n = 0;
  const fs::path dir = testing::temp_dir("cli-tools-" + std::to_string(n++));
  const std::string cmd = "'" + std::string(MEDSPRING_EXE) + "' " + args + " > '" + (dir / "out").string() +
                          "' 2> '" + (dir / "err").string() + "'";
  const int status = std::system(cmd.c_str());
  Result r;
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(dir / "out");
  r.err = slurp(dir / "err");
  return r;
}

TEST(ToolsCli, HapticsWithASphereWritesTheForceTorqueTrace) {
  const fs::path out = testing::temp_dir("cli-tools-haptics") / "run";
  const Result r =
      medspring("haptics kidney_phantom --trajectory '" + (kExamples / "probe_press_slide.csv").string() +
                "' --tool sphere:8 --friction 0.2 --duration 300 --json --out '" + out.string() + "'");
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("\"tool\": \"sphere\""), std::string::npos) << r.out;
  const std::string csv = slurp(out / "force_trace.csv");
  EXPECT_EQ(csv.rfind("time_ms,tool_x,tool_y,tool_z,reaction_x,reaction_y,reaction_z,torque_x", 0), 0u);
  int lines = 0;
  for (char c : csv) lines += c == '\n';
  EXPECT_EQ(lines, 301);
}

TEST(ToolsCli, BadToolsAndPathsFailWithOneLine) {
  const std::string traj = (kExamples / "probe_press_slide.csv").string();
  for (const char* tool : {"sphere:0", "sphere:-1", "cube:3", "sphere:nan"}) {
    const Result r = medspring("haptics kidney_phantom --trajectory '" + traj + "' --tool " + tool);
    EXPECT_NE(r.rc, 0) << tool;
    EXPECT_NE(r.err.find("tool"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  const fs::path bad = testing::temp_dir("cli-tools-bad") / "bad.csv";
  std::ofstream(bad) << "time_ms,x,y,z\n0,0,0,30\n10,0,oops,30\n";
  const Result r = medspring("haptics kidney_phantom --trajectory '" + bad.string() + "' --tool sphere:5");
  EXPECT_NE(r.rc, 0);
  EXPECT_NE(r.err.find("bad.csv:3: field 3 'oops' is not a finite number"), std::string::npos) << r.err;
  const fs::path inside = testing::temp_dir("cli-tools-inside") / "inside.csv";
  std::ofstream(inside) << "0,0,0,0\n10,0,0,1\n";  // the phantom's centre
  const Result in =
      medspring("haptics kidney_phantom --trajectory '" + inside.string() + "' --tool sphere:2");
  EXPECT_NE(in.rc, 0);
  EXPECT_NE(in.err.find("starts inside the organ"), std::string::npos) << in.err;
}

TEST(ToolsCli, RunWritesToolColumnsInTheTrace) {
  const fs::path out = testing::temp_dir("cli-tools-run") / "run";
  const Result r = medspring("run '" + (kExamples / "probe_press_slide.json").string() + "' --out '" +
                             out.string() + "' --quiet");
  ASSERT_EQ(r.rc, 0) << r.err;
  const std::string csv = slurp(out / "trace.csv");
  const std::string header = csv.substr(0, csv.find('\n'));
  for (const char* c :
       {"tool0_fx_N", "tool0_tz_Nmm", "tool0_area_mm2", "tool0_penetration_mm", "tool0_grasp_N"})
    EXPECT_NE(header.find(c), std::string::npos) << header;
}

}  // namespace
}  // namespace medspring
