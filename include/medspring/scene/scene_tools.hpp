// The "tools" and "contact" blocks of a scene (docs/tools.md):
//
//   "tools": [{"shape": "sphere", "radius": 8,
//              "path": [{"t": 0, "position": [0, 40, 10]}, {"t": 100, "position": [0, 34, 10]}]},
//             {"shape": "grasper", "radius": 1.5, "length": 12, "opening_deg": 60,
//              "path_file": "grasp.csv"}],
//   "contact": {"friction": 0.2, "stiffness": 0, "kappa": 1, "damping": 0.5}
//
// Path keyframes: "t" (ms), "position" [x, y, z] (mm), optional "rotation" [w, x, y, z] and
// "opening_deg"; or a CSV file (sim/tool_sim.hpp read_tool_path).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "medspring/sim/tool_sim.hpp"
#include "medspring/tools/contact.hpp"

namespace medspring {

struct SceneTool {
  Tool tool;
  ToolPath path;      // at least one keyframe (its first pose is the start pose)
  std::string where;  // "tools[k]" for messages
};

/// Parses a "tools" array. Throws InvalidInput "<origin>: tools[k].<field>: <problem>" (IoError for an
/// unreadable path_file). Relative path files are resolved against base_dir.
std::vector<SceneTool> parse_scene_tools(const std::string& json_text, const std::filesystem::path& base_dir,
                                         const std::string& origin);
/// Parses a "contact" object (friction, stiffness, kappa, damping, max_depth, grasp_angle_deg).
ContactSettings parse_scene_contact(const std::string& json_text, const std::string& origin);
/// The tools and contact settings as JSON text (scene_to_json).
std::string scene_tools_json(const std::vector<SceneTool>& tools);
std::string scene_contact_json(const ContactSettings& contact);

}  // namespace medspring
