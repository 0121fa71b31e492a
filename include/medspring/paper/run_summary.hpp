// The summary of one scene run as JSON (the keys of `medspring run`'s summary.json, docs/scenes.md):
// written once here for the CLI's runs to folders and for the study's hosts (the CLI, Python).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "medspring/scene/build.hpp"
#include "medspring/scene/runner.hpp"

namespace medspring::paper {

/// What a run to a folder adds to the summary; the defaults mean "none".
struct SummaryExtras {
  std::string frames_json = "[]";  // the recorded frames: [{"index", "time_ms", "file"[, "atoms_file"]}]
  std::string pvd, atoms_pvd;      // the .pvd series written (empty: none)
  std::string checkpoint;          // the checkpoint file (empty: none)
  double resumed_from_ms = std::numeric_limits<double>::quiet_NaN();
  bool has_static_curve = false;
  std::vector<StaticPoint> static_curve;
};

/// A JSON description of a built model (kind, counts, notes), as JSON text.
std::string describe_built_json(const BuiltScene& built);

/// The summary of a run of `built` (JSON text; non-finite numbers as null).
std::string run_summary_json(const BuiltScene& built, const SceneResult& result, const SummaryExtras& extras);

}  // namespace medspring::paper
