// Where the real-anatomy data files live.
#pragma once

#include <filesystem>
#include <string>

namespace medspring {

/// $MEDSPRING_DATA when set and non-empty, else the folder configured at build time (CMake cache
/// variable MEDSPRING_DATA_DIR, default ../shared/data beside the source tree). Not checked to exist.
std::filesystem::path data_dir();

/// data_dir() / name when that file exists; throws IoError
/// "data file <name> not found in <dir> (set MEDSPRING_DATA)" otherwise.
std::filesystem::path find_data_file(const std::string& name);

}  // namespace medspring
