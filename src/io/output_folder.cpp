#include "medspring/io/output_folder.hpp"

#include <unistd.h>

#include <system_error>

#include "medspring/core/check.hpp"
#include "medspring/io/temp_folders.hpp"

namespace medspring {

namespace fs = std::filesystem;

void check_output_folder(const fs::path& folder, bool overwrite) {
  require(!folder.empty(), "output folder: no path given");
  std::error_code ec;
  const fs::file_status st = fs::status(folder, ec);
  if (!fs::exists(st)) return;
  if (!fs::is_directory(st)) throw IoError(cat(folder.string(), ": exists and is not a folder"));
  if (!overwrite && !fs::is_empty(folder, ec))
    throw IoError(cat(folder.string(), ": output folder is not empty; use --force to replace it"));
}

void write_output_folder(const fs::path& folder_in, bool overwrite,
                         const std::function<void(const fs::path& dir)>& write) {
  check_output_folder(folder_in, overwrite);
  const fs::path folder = fs::absolute(folder_in).lexically_normal();
  const fs::path target = folder.has_filename() ? folder : folder.parent_path();  // "out/" -> "out"
  const fs::path parent = target.parent_path();
  const long pid = static_cast<long>(::getpid());
  const fs::path tmp = temp_folder_for(target, pid);

  // the first missing ancestor, removed again if anything fails
  fs::path created;
  for (fs::path p = parent; !p.empty() && !fs::exists(p); p = p.parent_path()) {
    created = p;
    if (p == p.parent_path()) break;
  }
  std::error_code ec;
  auto cleanup = [&] {
    fs::remove_all(tmp, ec);
    if (!created.empty()) fs::remove_all(created, ec);
  };
  try {
    fs::create_directories(parent);
    remove_stale_temp_folders(target);  // left by killed runs (the CLI reports them before calling this)
    fs::remove_all(tmp);
    fs::create_directory(tmp);
    write(tmp);
    move_folder_into_place(tmp, target, pid);
  } catch (const fs::filesystem_error& e) {
    cleanup();
    throw IoError(cat(target.string(), ": cannot write the output folder: ", e.code().message()));
  } catch (...) {
    cleanup();
    throw;
  }
}

}  // namespace medspring
