#include "process.hpp"

#include <sys/wait.h>

#include <cstdlib>
#include <deque>
#include <fstream>
#include <sstream>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"

namespace medspring::fem::detail {

namespace fs = std::filesystem;

fs::path find_tool(const std::string& name, const char* env_var, const std::string& hint) {
  if (const char* env = std::getenv(env_var); env && *env) {
    const fs::path p(env);
    std::error_code ec;
    if (!fs::is_regular_file(p, ec))
      throw IoError(cat(name, " not found: $", env_var, " = ", p.string(), " is no file"));
    return p;
  }
  const char* path_env = std::getenv("PATH");
  std::stringstream ss(path_env ? path_env : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(ss, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path p = fs::path(dir) / name;
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) {
      const auto perms = fs::status(p, ec).permissions();
      if ((perms & fs::perms::owner_exec) != fs::perms::none ||
          (perms & fs::perms::others_exec) != fs::perms::none)
        return p;
    }
  }
  throw IoError(cat(name, " not found on PATH: ", hint));
}

TempDir::TempDir(const std::string& prefix) {
  std::string templ = (fs::temp_directory_path() / (prefix + "-XXXXXX")).string();
  if (!::mkdtemp(templ.data())) throw IoError(cat("cannot create a temporary folder ", templ));
  path_ = templ;
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'')
      out += "'\\''";
    else
      out += c;
  }
  return out + "'";
}

int run_in(const fs::path& dir, const fs::path& exe, const std::string& args, const std::string& log_name) {
  const char* omp = std::getenv("OMP_NUM_THREADS");
  const std::string env = (omp && *omp) ? "" : "OMP_NUM_THREADS=1 ";
  const std::string cmd = "cd " + shell_quote(dir.string()) + " && " + env + shell_quote(exe.string()) + " " +
                          args + " > " + shell_quote(log_name) + " 2>&1 < /dev/null";
  const int status = std::system(cmd.c_str());
  if (status == -1 || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

std::string last_lines(const fs::path& file, int n) {
  std::ifstream in(file);
  std::deque<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    const auto b = line.find_first_not_of(" \t\r");
    if (b == std::string::npos) continue;
    lines.push_back(line.substr(b));
    if (static_cast<int>(lines.size()) > n) lines.pop_front();
  }
  std::string out;
  for (const auto& l : lines) out += (out.empty() ? "" : " | ") + l;
  return out.empty() ? "(no output)" : out;
}

}  // namespace medspring::fem::detail
