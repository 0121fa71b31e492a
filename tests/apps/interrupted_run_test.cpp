// A `medspring run` killed with SIGKILL leaves its hidden temporary folder ".NAME.tmp-PID" beside the
// output; the next run into the same place removes it (its process is gone), says so on stderr, and
// keeps the temporary folders of live processes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A phantom kidney pressed and held for a long time (seconds of updates), recording frames.
const char* kLongScene = R"({
  "model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
  "loads": [{"node": 223, "direction": "towards_atom", "atom": 21, "magnitude": 0.5, "t_ramp": 10}],
  "duration": 200000,
  "record": {"every": 200}
})";

const char* kShortScene = R"({
  "model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
  "loads": [{"node": 223, "direction": "towards_atom", "atom": 21, "magnitude": 0.5, "t_ramp": 10}],
  "duration": 20,
  "record": {"every": 10}
})";

TEST(InterruptedRun, KilledRunLeavesATempFolderThatTheNextRunRemovesAndReports) {
  const fs::path dir = testing::temp_dir("interrupted-run");
  std::ofstream(dir / "long.json") << kLongScene;
  std::ofstream(dir / "short.json") << kShortScene;
  const fs::path out = dir / "result";

  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const std::string scene = (dir / "long.json").string(), target = out.string();
    ::execl(MEDSPRING_EXE, MEDSPRING_EXE, "run", scene.c_str(), "--out", target.c_str(), "--quiet",
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const fs::path tmp = dir / (".result.tmp-" + std::to_string(child));
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!fs::exists(tmp / "frames") && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(20ms);
  const bool started = fs::exists(tmp);
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(started) << tmp << " did not appear within 60 s";
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the run ended before it was killed";
  EXPECT_TRUE(fs::is_directory(tmp));  // what SIGKILL leaves behind
  EXPECT_FALSE(fs::exists(out));

  // a temporary folder of a live process (this test) is not touched
  const fs::path live = dir / (".result.tmp-" + std::to_string(::getpid()));
  fs::create_directories(live);

  const std::string cmd = std::string("'") + MEDSPRING_EXE + "' run '" + (dir / "short.json").string() +
                          "' --out '" + out.string() + "' --quiet 2> '" + (dir / "err").string() + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(dir / "err");
  const std::string err = slurp(dir / "err");
  EXPECT_NE(err.find("medspring: removed " + tmp.string() + ", left by an interrupted run (process " +
                     std::to_string(child) + " is gone)"),
            std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(tmp));
  EXPECT_TRUE(fs::is_directory(live));
  EXPECT_TRUE(fs::exists(out / "short.pvd"));
  fs::remove_all(live);
}

}  // namespace
}  // namespace medspring
