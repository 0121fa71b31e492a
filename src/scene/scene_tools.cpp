#include "medspring/scene/scene_tools.hpp"

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "params_json.hpp"

namespace medspring {

namespace {

using json = nlohmann::json;

[[noreturn]] void fail(const std::string& origin, const std::string& path, const std::string& what) {
  throw InvalidInput(cat(origin, ": ", path, ": ", what));
}

constexpr double kDeg = std::numbers::pi / 180;

}  // namespace

ToolKind parse_enum(const std::string& text, ToolKind*) {
  for (ToolKind k : {ToolKind::Sphere, ToolKind::Capsule, ToolKind::Grasper})
    if (text == to_string(k)) return k;
  throw InvalidInput(cat("unknown shape '", text, "' (expected sphere, capsule or grasper)"));
}

std::vector<SceneTool> parse_scene_tools(const std::string& text, const std::filesystem::path& base_dir,
                                         const std::string& origin) {
  const json arr = json::parse(text);
  if (!arr.is_array()) fail(origin, "tools", "must be an array");
  std::vector<SceneTool> out;
  for (std::size_t k = 0; k < arr.size(); ++k) {
    const std::string where = cat("tools[", k, "]");
    ToolEntry e;  // declared in scene_tools.hpp: keys, types and ranges checked there
    try {
      params_from_json(arr[k], where, e);
    } catch (const InvalidInput& x) {
      throw InvalidInput(cat(origin, ": ", x.what()));
    }
    SceneTool t;
    t.where = where;
    t.tool = {e.shape, e.radius, e.length, e.opening_deg * kDeg};
    try {
      validate_tool(t.tool, where);
    } catch (const InvalidInput& x) {
      throw InvalidInput(cat(origin, ": ", x.what()));
    }
    if (arr[k].contains("path") == arr[k].contains("path_file"))
      fail(origin, where, "needs exactly one of path (keyframes) or path_file (CSV)");
    if (arr[k].contains("path_file")) {
      if (e.path_file.empty()) fail(origin, where + ".path_file", "must not be empty");
      std::filesystem::path p = e.path_file;
      if (p.is_relative()) p = base_dir / p;
      try {
        t.path = read_tool_path_file(p);
      } catch (const InvalidInput& x) {
        throw InvalidInput(cat(origin, ": ", where, ".path_file: ", x.what()));
      }
    } else {
      if (e.path.empty()) fail(origin, where + ".path", "must be a non-empty array of keyframes");
      for (std::size_t r = 0; r < e.path.size(); ++r) {
        const ToolKeyframeEntry& g = e.path[r];
        const std::string at = cat(where, ".path[", r, "]");
        ToolKeyframe f;
        f.t = g.t;
        f.pose.position = g.position;
        f.pose.rotation = Quat(g.rotation[0], g.rotation[1], g.rotation[2], g.rotation[3]);
        if (f.pose.rotation.coeffs().norm() < 1e-12) fail(origin, at + ".rotation", "is zero");
        f.pose.rotation.normalize();
        if (g.opening_deg) f.opening = *g.opening_deg * kDeg;
        if (r > 0 && !(f.t > t.path.back().t))
          fail(origin, at + ".t",
               cat(f.t, " ms is not after the previous keyframe's ", t.path.back().t, " ms"));
        t.path.push_back(f);
      }
    }
    out.push_back(std::move(t));
  }
  return out;
}

ContactSettings parse_scene_contact(const std::string& text, const std::string& origin) {
  json j = json::parse(text);
  ContactSettings s;
  try {
    // The grasp angle may be given in degrees (the form of scenes written before it was declared).
    if (j.is_object() && j.contains("grasp_angle_deg")) {
      if (j.contains("grasp_angle"))
        throw InvalidInput("contact.grasp_angle_deg: give grasp_angle (rad) or grasp_angle_deg, not both");
      const json& g = j["grasp_angle_deg"];
      const double deg = g.is_number() ? g.get<double>() : -1;
      if (!(deg >= 0 && deg < 180))
        throw InvalidInput(cat("contact.grasp_angle_deg: must be a number in [0, 180) (got ", g.dump(), ")"));
      j.erase("grasp_angle_deg");
      j["grasp_angle"] = deg * std::numbers::pi / 180;
    }
    params_from_json(j, "contact", s);  // declared in tools/contact.hpp
  } catch (const InvalidInput& e) {
    throw InvalidInput(cat(origin, ": ", e.what()));
  }
  return s;
}

std::string scene_tools_json(const std::vector<SceneTool>& tools) {
  json arr = json::array();
  for (const SceneTool& t : tools) {  // back to the declared entries (path_file read into keyframes)
    ToolEntry e{t.tool.kind, t.tool.radius, t.tool.length, t.tool.opening / kDeg, {}, {}};
    for (const ToolKeyframe& f : t.path) {
      const Quat& q = f.pose.rotation;
      ToolKeyframeEntry g{f.t, f.pose.position, Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()), std::nullopt};
      if (f.opening >= 0) g.opening_deg = f.opening / kDeg;
      e.path.push_back(g);
    }
    json j = params_to_json(e);
    j.erase("path_file");
    for (json& g : j["path"])
      if (g["opening_deg"].is_null()) g.erase("opening_deg");
    arr.push_back(j);
  }
  return arr.dump();
}

std::string scene_contact_json(const ContactSettings& s) {
  return params_to_json(s).dump();
}

}  // namespace medspring
