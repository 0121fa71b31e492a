#include "medspring/io/temp_folders.hpp"

#include <signal.h>

#include <cerrno>
#include <string>
#include <system_error>

#include "medspring/core/check.hpp"

namespace medspring {

namespace fs = std::filesystem;

namespace {

fs::path normalized(const fs::path& target) {
  fs::path a = fs::absolute(target).lexically_normal();
  if (a.filename().empty()) a = a.parent_path();  // "out/" -> "out"
  return a;
}

}  // namespace

fs::path temp_folder_for(const fs::path& target, long pid) {
  const fs::path t = normalized(target);
  return t.parent_path() / cat(".", t.filename().string(), ".tmp-", pid);
}

bool process_alive(long pid) {
  if (pid <= 0) return false;
  return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH;
}

std::vector<StaleTempFolder> remove_stale_temp_folders(const fs::path& target) {
  const fs::path t = normalized(target);
  const std::string prefix = cat(".", t.filename().string(), ".tmp-");
  std::vector<StaleTempFolder> removed;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(t.parent_path(), ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const long pid = std::stol(digits);
    std::error_code dir_ec;
    if (!e.is_directory(dir_ec) || process_alive(pid)) continue;
    std::error_code rm_ec;
    fs::remove_all(e.path(), rm_ec);
    if (!rm_ec) removed.push_back({e.path(), pid});
  }
  return removed;
}

void move_folder_into_place(const fs::path& stage, const fs::path& target_in, long pid) {
  const fs::path target = normalized(target_in);
  std::error_code ec;
  if (!fs::exists(target, ec)) {
    fs::rename(stage, target, ec);
    if (ec) throw IoError(cat(target.string(), ": cannot move the new folder into place: ", ec.message()));
    return;
  }
  const fs::path old = target.parent_path() / cat(".", target.filename().string(), ".old-", pid);
  fs::remove_all(old, ec);
  fs::rename(target, old, ec);
  if (ec) throw IoError(cat(target.string(), ": cannot move the old folder aside: ", ec.message()));
  fs::rename(stage, target, ec);
  if (ec) {
    std::error_code ec2;
    fs::rename(old, target, ec2);
    throw IoError(cat(target.string(), ": cannot move the new folder into place: ", ec.message()));
  }
  fs::remove_all(old, ec);
}

}  // namespace medspring
