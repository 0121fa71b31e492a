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
#include <optional>
#include <string>
#include <vector>

#include "medspring/core/params.hpp"
#include "medspring/sim/tool_sim.hpp"
#include "medspring/tools/contact.hpp"

namespace medspring {

/// The names of tool shapes in scene files: "sphere", "capsule", "grasper".
ToolKind parse_enum(const std::string& text, ToolKind*);

/// One keyframe of a tool's "path" as a scene file writes it.
struct ToolKeyframeEntry {
  double t = 0;                                            // ms
  Vec3 position = Vec3::Zero();                            // mm
  Eigen::Vector4d rotation = Eigen::Vector4d(1, 0, 0, 0);  // quaternion [w, x, y, z]
  std::optional<double> opening_deg;                       // grasper opening from this keyframe on
};

template <ParamOf<ToolKeyframeEntry> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"t", "ms", "time of the keyframe (increasing along the path)"}.required(), s.t);
  v(ParamSpec{"position", "mm", "tool origin [x, y, z]"}.required(), s.position);
  v(ParamSpec{"rotation", "", "orientation as a quaternion [w, x, y, z] (normalised; not zero)"}, s.rotation);
  v(ParamSpec{"opening_deg", "deg", "grasper opening (null: the tool's own)"}.nonnegative().at_most(180),
    s.opening_deg);
}

/// One entry of "tools" as a scene file writes it: a shape and exactly one of path or path_file.
struct ToolEntry {
  ToolKind shape = ToolKind::Sphere;
  double radius = 5.0;       // mm
  double length = 0.0;       // mm
  double opening_deg = 0.0;  // deg
  std::vector<ToolKeyframeEntry> path;
  std::string path_file;
};

/// The declaration of ToolEntry (core/params.hpp): the keys of each entry of "tools" and of its path, the
/// tables in docs/parameters.md.
template <ParamOf<ToolEntry> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"shape", "", "sphere, capsule or grasper"}.required(), s.shape);
  v(ParamSpec{"radius", "mm", "radius of the sphere, of the capsule and of each grasper jaw"}
        .positive()
        .required(),
    s.radius);
  v(ParamSpec{"length", "mm", "capsule shaft, grasper jaw (> 0 for a grasper)"}.nonnegative(), s.length);
  v(ParamSpec{"opening_deg", "deg", "grasper: angle between the jaws (0 = closed)"}.nonnegative().at_most(
        180),
    s.opening_deg);
  v(ParamSpec{"path", "", "keyframes (give path or path_file)"}, s.path);
  v(ParamSpec{"path_file", "", "CSV of keyframes, relative to the scene (sim/tool_sim.hpp read_tool_path)"},
    s.path_file);
}

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
