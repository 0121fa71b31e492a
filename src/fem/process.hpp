// Subprocess helpers of the fem layer (private): executables on PATH, temporary folders, running a
// tool with its output captured to a log file.
#pragma once

#include <filesystem>
#include <string>

namespace medspring::fem::detail {

/// The executable: $env_var if set and non-empty, else `name` searched on PATH. Throws IoError
/// "<name> not found: <hint>" when there is none.
std::filesystem::path find_tool(const std::string& name, const char* env_var, const std::string& hint);

/// A fresh private folder under the system temp folder, removed by the destructor (unless kept).
class TempDir {
 public:
  explicit TempDir(const std::string& prefix);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// Runs `exe args` in folder `dir` with stdout and stderr to dir/log_name; returns the exit status
/// (-1 if it could not be started or was killed by a signal). OMP_NUM_THREADS is set to 1 unless set.
int run_in(const std::filesystem::path& dir, const std::filesystem::path& exe, const std::string& args,
           const std::string& log_name);

/// The last `n` non-empty lines of a text file, joined by " | " (for error messages).
std::string last_lines(const std::filesystem::path& file, int n);

/// Single-quoted for /bin/sh.
std::string shell_quote(const std::string& s);

}  // namespace medspring::fem::detail
