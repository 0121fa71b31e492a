// The accuracy summary that `medspring paper` puts in its report (docs/accuracy.md): read from the
// accuracy.json of a previous `medspring accuracy` run, which that command also keeps as the latest one
// beside the FEM cache, so `paper` never runs CalculiX itself.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace medspring::cli {

/// $MEDSPRING_FEM_CACHE, else $XDG_CACHE_HOME/medspring/fem, else ~/.cache/medspring/fem, +
/// accuracy-latest.json.
std::filesystem::path latest_accuracy_path();

/// Keeps `accuracy` as the latest run (written under a temporary name and renamed); false when the folder
/// cannot be written (the run's own output is unaffected).
bool keep_latest_accuracy(const nlohmann::json& accuracy);

/// The report section: per organ and model kind, mean held-out contact and RMS errors (default and
/// calibrated), update time and the FEM solve time; `source` names where the results came from.
std::string accuracy_summary_markdown(const nlohmann::json& accuracy, const std::string& source);

}  // namespace medspring::cli
