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

double number(const std::string& origin, const json& j, const std::string& path) {
  if (!j.is_number()) fail(origin, path, "must be a number");
  const double x = j.get<double>();
  if (!std::isfinite(x)) fail(origin, path, "must be finite");
  return x;
}

Vec3 vec3(const std::string& origin, const json& j, const std::string& path) {
  if (!j.is_array() || j.size() != 3) fail(origin, path, "must be [x, y, z]");
  return {number(origin, j[0], path + "[0]"), number(origin, j[1], path + "[1]"),
          number(origin, j[2], path + "[2]")};
}

void known(const std::string& origin, const json& j, const std::string& path,
           std::initializer_list<const char*> keys) {
  if (!j.is_object()) fail(origin, path, "must be an object");
  for (auto it = j.begin(); it != j.end(); ++it) {
    bool ok = false;
    std::string list;
    for (const char* k : keys) {
      ok = ok || it.key() == k;
      list += (list.empty() ? "" : ", ") + std::string(k);
    }
    if (!ok) fail(origin, path + "." + it.key(), cat("unknown key (expected one of: ", list, ")"));
  }
}

}  // namespace

std::vector<SceneTool> parse_scene_tools(const std::string& text, const std::filesystem::path& base_dir,
                                         const std::string& origin) {
  const json arr = json::parse(text);
  if (!arr.is_array()) fail(origin, "tools", "must be an array");
  std::vector<SceneTool> out;
  for (std::size_t k = 0; k < arr.size(); ++k) {
    const std::string where = cat("tools[", k, "]");
    const json& j = arr[k];
    known(origin, j, where, {"shape", "radius", "length", "opening_deg", "path", "path_file"});
    SceneTool t;
    t.where = where;
    const std::string shape =
        j.contains("shape") && j["shape"].is_string() ? j["shape"].get<std::string>() : "";
    if (shape == "sphere")
      t.tool.kind = ToolKind::Sphere;
    else if (shape == "capsule")
      t.tool.kind = ToolKind::Capsule;
    else if (shape == "grasper")
      t.tool.kind = ToolKind::Grasper;
    else
      fail(origin, where + ".shape", "is required: sphere, capsule or grasper");
    if (!j.contains("radius")) fail(origin, where + ".radius", "is required (mm)");
    t.tool.radius = number(origin, j["radius"], where + ".radius");
    if (j.contains("length")) t.tool.length = number(origin, j["length"], where + ".length");
    if (j.contains("opening_deg"))
      t.tool.opening = number(origin, j["opening_deg"], where + ".opening_deg") * std::numbers::pi / 180;
    try {
      validate_tool(t.tool, where);
    } catch (const InvalidInput& e) {
      throw InvalidInput(cat(origin, ": ", e.what()));
    }
    if (j.contains("path") == j.contains("path_file"))
      fail(origin, where, "needs exactly one of path (keyframes) or path_file (CSV)");
    if (j.contains("path_file")) {
      if (!j["path_file"].is_string()) fail(origin, where + ".path_file", "must be a file name");
      std::filesystem::path p = j["path_file"].get<std::string>();
      if (p.is_relative()) p = base_dir / p;
      try {
        t.path = read_tool_path_file(p);
      } catch (const InvalidInput& e) {
        throw InvalidInput(cat(origin, ": ", where, ".path_file: ", e.what()));
      }
    } else {
      const json& path = j["path"];
      if (!path.is_array() || path.empty())
        fail(origin, where + ".path", "must be a non-empty array of keyframes");
      for (std::size_t r = 0; r < path.size(); ++r) {
        const std::string at = cat(where, ".path[", r, "]");
        known(origin, path[r], at, {"t", "position", "rotation", "opening_deg"});
        ToolKeyframe f;
        if (!path[r].contains("t")) fail(origin, at + ".t", "is required (ms)");
        if (!path[r].contains("position")) fail(origin, at + ".position", "is required ([x, y, z] mm)");
        f.t = number(origin, path[r]["t"], at + ".t");
        f.pose.position = vec3(origin, path[r]["position"], at + ".position");
        if (path[r].contains("rotation")) {
          const json& q = path[r]["rotation"];
          if (!q.is_array() || q.size() != 4)
            fail(origin, at + ".rotation", "must be a quaternion [w, x, y, z]");
          f.pose.rotation =
              Quat(number(origin, q[0], at + ".rotation[0]"), number(origin, q[1], at + ".rotation[1]"),
                   number(origin, q[2], at + ".rotation[2]"), number(origin, q[3], at + ".rotation[3]"));
          if (f.pose.rotation.coeffs().norm() < 1e-12) fail(origin, at + ".rotation", "is zero");
          f.pose.rotation.normalize();
        }
        if (path[r].contains("opening_deg")) {
          const double deg = number(origin, path[r]["opening_deg"], at + ".opening_deg");
          if (deg < 0 || deg > 180)
            fail(origin, at + ".opening_deg", cat("must be in [0, 180] (got ", deg, ")"));
          f.opening = deg * std::numbers::pi / 180;
        }
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
  for (const SceneTool& t : tools) {
    json path = json::array();
    for (const ToolKeyframe& f : t.path) {
      json k = {
          {"t", f.t},
          {"position", {f.pose.position.x(), f.pose.position.y(), f.pose.position.z()}},
          {"rotation", {f.pose.rotation.w(), f.pose.rotation.x(), f.pose.rotation.y(), f.pose.rotation.z()}}};
      if (f.opening >= 0) k["opening_deg"] = f.opening * 180 / std::numbers::pi;
      path.push_back(k);
    }
    arr.push_back({{"shape", to_string(t.tool.kind)},
                   {"radius", t.tool.radius},
                   {"length", t.tool.length},
                   {"opening_deg", t.tool.opening * 180 / std::numbers::pi},
                   {"path", path}});
  }
  return arr.dump();
}

std::string scene_contact_json(const ContactSettings& s) {
  return params_to_json(s).dump();
}

}  // namespace medspring
