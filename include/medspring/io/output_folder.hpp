// Writing a command's output files all at once (`medspring build`, `accuracy`, ...): into a temporary
// folder beside the target, renamed into place when every file is complete, so that a failure leaves
// nothing half-written. In the io layer (it needs only io/temp_folders.hpp), so that a build without the
// CGAL edge (MEDSPRING_WITH_CGAL=OFF: no builders layer) links the CLI.
//
//   check_output_folder(out, force);          // before the (slow) build: refuse early
//   write_output_folder(out, force, [&](const std::filesystem::path& dir) {
//     write_vtp(dir / "surface.vtp", build.model->surface());
//   });
#pragma once

#include <filesystem>
#include <functional>

namespace medspring {

/// Throws IoError naming the folder when `folder` is a file, or a folder that is not empty while
/// `overwrite` is false ("... is not empty; use --force to replace it").
void check_output_folder(const std::filesystem::path& folder, bool overwrite);

/// check_output_folder, then calls write(tmp) on a fresh hidden folder ".<name>.tmp-<pid>" beside
/// `folder` (io/temp_folders.hpp; those of dead processes, left by a killed run, are removed first)
/// and renames it to `folder` (missing parent folders are created). An existing `folder` (empty, or
/// any with `overwrite`) is replaced only after every file is written. On any exception the temporary
/// folder (and parent folders created here) are removed, `folder` is left as it was, and the exception
/// propagates.
void write_output_folder(const std::filesystem::path& folder, bool overwrite,
                         const std::function<void(const std::filesystem::path& dir)>& write);

}  // namespace medspring
