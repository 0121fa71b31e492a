// Output folders written under a temporary name and renamed into place when complete (the CLI's
// `run`, `paper`, `export`, `haptics`, `build`; io/output_folder.hpp): the temporary folder of
// process PID for the target folder NAME is the hidden sibling ".NAME.tmp-PID". A process killed with
// SIGKILL cannot remove it; the next write into the same place does, when that process is gone.
//
//   for (const auto& gone : remove_stale_temp_folders(out))
//     std::fprintf(stderr, "removed %s, left by an interrupted run\n", gone.path.c_str());
//   const auto tmp = temp_folder_for(out, ::getpid());
#pragma once

#include <filesystem>
#include <vector>

namespace medspring {

/// "<parent>/.<name>.tmp-<pid>" for the target folder "<parent>/<name>" (a trailing '/' is ignored).
std::filesystem::path temp_folder_for(const std::filesystem::path& target, long pid);

/// True unless no process `pid` exists (kill(pid, 0) fails with ESRCH). A process of another user
/// counts as alive.
bool process_alive(long pid);

struct StaleTempFolder {
  std::filesystem::path path;
  long pid = 0;  // the process that left it
};

/// Removes the temporary folders of `target` (".<name>.tmp-<digits>" beside it) whose process is gone,
/// and returns them. Folders of live processes, this one included, and every other name are kept.
/// Removal errors are ignored (the folder is then not reported); a missing parent is no error.
std::vector<StaleTempFolder> remove_stale_temp_folders(const std::filesystem::path& target);

/// Moves the complete folder `stage` to `target` (a sibling), replacing a folder already there: the old
/// one is renamed aside (".<name>.old-<pid>"), the new one moved in, then the old one removed; when
/// moving the new one in fails the old one is put back. Throws IoError "TARGET: cannot move the old
/// folder aside: ..." or "TARGET: cannot move the new folder into place: ...". The one folder swap of
/// every staged output (io/output_folder.hpp, the CLI's StagedOutput).
void move_folder_into_place(const std::filesystem::path& stage, const std::filesystem::path& target,
                            long pid);

}  // namespace medspring
