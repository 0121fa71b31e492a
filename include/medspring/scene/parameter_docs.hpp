// The declared parameter sets (core/params.hpp) as tables: docs/parameters.md and
// `medspring info --params` print parameter_tables_markdown(); a test fails when they differ.
#pragma once

#include <string>
#include <vector>

#include "medspring/core/params.hpp"

namespace medspring {

/// One declared parameter struct: where it appears in a scene file and its rows at the defaults.
struct ParamSet {
  std::string title;        // "Hybrid kidney"
  std::string struct_name;  // C++ and Python type: "HybridSettings"
  std::string scene_path;   // where a scene file sets it: "model.parameters (kind hybrid)"
  std::string declared_in;  // header holding the declaration
  std::vector<ParamRow> rows;
};

/// Every declared set, in the order of docs/parameters.md.
std::vector<ParamSet> parameter_sets();

/// The whole of docs/parameters.md.
std::string parameter_tables_markdown();

struct Scene;

/// Sets one declared parameter of a parsed scene from text, by its scene path:
/// "integrator.dt", "model.parameters.k_spoke" (hybrid), "model.parameters.duffing.mode". Checks the
/// type and range; throws InvalidInput naming the path. For `medspring run --set PATH=VALUE`.
void set_scene_parameter(Scene& scene, const std::string& path, const std::string& value);

/// Applies "PATH=VALUE[,PATH=VALUE...]" with set_scene_parameter.
void apply_scene_settings(Scene& scene, const std::string& assignments);

}  // namespace medspring
