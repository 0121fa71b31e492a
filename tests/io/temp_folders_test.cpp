// Temporary output folders of killed runs (io/temp_folders.hpp): those of dead processes are removed,
// those of live processes and every other name are kept.
#include "medspring/io/temp_folders.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <iterator>
#include <string>

#include "medspring/core/error.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;

/// The id of a process that has exited and been reaped (so no process has it, barring reuse).
long dead_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return static_cast<long>(child);
}

TEST(TempFolders, NameIsHiddenBesideTheTarget) {
  EXPECT_EQ(temp_folder_for("/a/b/out", 12), fs::path("/a/b/.out.tmp-12"));
  EXPECT_EQ(temp_folder_for("/a/b/out/", 12), fs::path("/a/b/.out.tmp-12"));
}

TEST(TempFolders, ProcessAlive) {
  EXPECT_TRUE(process_alive(static_cast<long>(::getpid())));
  EXPECT_TRUE(process_alive(1));  // init: another user's process counts as alive
  EXPECT_FALSE(process_alive(dead_pid()));
  EXPECT_FALSE(process_alive(0));
  EXPECT_FALSE(process_alive(-5));
}

TEST(TempFolders, OnlyFoldersOfDeadProcessesAreRemoved) {
  const fs::path dir = testing::temp_dir("temp-folders");
  const fs::path out = dir / "out";
  const long dead = dead_pid();
  const long me = static_cast<long>(::getpid());
  const fs::path stale = temp_folder_for(out, dead);
  fs::create_directories(stale / "frames");
  std::ofstream(stale / "frames" / "half.vtp") << "half";
  const std::vector<fs::path> kept = {
      temp_folder_for(out, me),                   // a live process (this one)
      temp_folder_for(dir / "other", dead),       // another target's
      dir / ".out.tmp-12x",                       // not a process id
      dir / ".out.old-1",                         // not a temporary folder
      dir / ("out.tmp-" + std::to_string(dead)),  // not hidden: not ours
  };
  for (const auto& k : kept) fs::create_directories(k);
  std::ofstream(temp_folder_for(out, dead + 1000000)) << "a file, not a folder";

  const std::vector<StaleTempFolder> removed = remove_stale_temp_folders(out);
  ASSERT_EQ(removed.size(), 1u);
  EXPECT_EQ(removed[0].path, stale);
  EXPECT_EQ(removed[0].pid, dead);
  EXPECT_FALSE(fs::exists(stale));
  for (const auto& k : kept) EXPECT_TRUE(fs::is_directory(k)) << k;
  EXPECT_TRUE(fs::is_regular_file(temp_folder_for(out, dead + 1000000)));
  EXPECT_TRUE(remove_stale_temp_folders(out).empty());
  EXPECT_TRUE(remove_stale_temp_folders(dir / "missing" / "out").empty());  // no parent: no error
}

std::string read(const fs::path& f) {
  std::ifstream in(f);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(TempFolders, MoveIntoPlaceReplacesTheOldFolderWhole) {
  const fs::path dir = testing::temp_dir("move-into-place");
  const fs::path out = dir / "out";
  const long me = static_cast<long>(::getpid());
  for (const char* text : {"first", "second"}) {  // into an empty place, then over the first
    const fs::path stage = temp_folder_for(out, me);
    fs::create_directories(stage);
    std::ofstream(stage / "a.txt") << text;
    if (std::string(text) == "first") std::ofstream(stage / "only_first.txt") << "x";
    move_folder_into_place(stage, out, me);
    EXPECT_FALSE(fs::exists(stage));
    EXPECT_EQ(read(out / "a.txt"), text);
  }
  EXPECT_FALSE(fs::exists(out / "only_first.txt"));                                    // replaced, not merged
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}), 1);  // no .old- left
}

TEST(TempFolders, MoveIntoPlaceThatFailsPutsTheOldFolderBack) {
  const fs::path dir = testing::temp_dir("move-into-place-fails");
  const fs::path out = dir / "out";
  fs::create_directories(out);
  std::ofstream(out / "a.txt") << "old";
  try {
    move_folder_into_place(dir / ".out.tmp-missing", out, 7);  // no stage: the rename fails
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("out: cannot move the new folder into place"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(read(out / "a.txt"), "old");
  EXPECT_FALSE(fs::exists(dir / ".out.old-7"));
}

}  // namespace
}  // namespace medspring
