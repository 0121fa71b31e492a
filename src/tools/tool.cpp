#include "medspring/tools/tool.hpp"

#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

#include "medspring/core/check.hpp"

namespace medspring {

Pose checked_pose(const Pose& pose, const std::string& what) {
  require(pose.position.allFinite(), what, ": position must be finite (got ", pose.position.x(), ", ",
          pose.position.y(), ", ", pose.position.z(), ")");
  require(pose.rotation.coeffs().allFinite() && pose.rotation.coeffs().norm() > 1e-12, what,
          ": rotation must be a finite non-zero quaternion");
  Pose p = pose;
  p.rotation.normalize();
  return p;
}

std::string to_string(ToolKind kind) {
  switch (kind) {
    case ToolKind::Sphere:
      return "sphere";
    case ToolKind::Capsule:
      return "capsule";
    case ToolKind::Grasper:
      return "grasper";
  }
  return "?";
}

void validate_tool(const Tool& tool, const std::string& what) {
  require_positive(tool.radius, what, ".radius (mm)");
  require_nonnegative(tool.length, what, ".length (mm)");
  if (tool.kind == ToolKind::Grasper) {
    require_positive(tool.length, what, ".length (mm) of the grasper's jaws");
    require(std::isfinite(tool.opening) && tool.opening >= 0 && tool.opening <= std::numbers::pi, what,
            ".opening: must be in [0, pi] rad (got ", tool.opening, ")");
  }
}

Tool parse_tool(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream ss(text);
  std::string p;
  while (std::getline(ss, p, ':')) parts.push_back(p);
  require(!parts.empty(), "tool '", text, "': expected sphere:R, capsule:R:L or grasper:R:L:DEG");
  auto number = [&](std::size_t i, const char* name) {
    const std::string& f = parts[i];
    char* end = nullptr;
    const double v = std::strtod(f.c_str(), &end);
    require(!f.empty() && end && *end == '\0' && std::isfinite(v), "tool '", text, "': ", name, " '", f,
            "' is not a finite number");
    return v;
  };
  Tool t;
  if (parts[0] == "sphere" && parts.size() == 2) {
    t = Tool::sphere(number(1, "radius"));
  } else if (parts[0] == "capsule" && parts.size() == 3) {
    t = Tool::capsule(number(1, "radius"), number(2, "length"));
  } else if (parts[0] == "grasper" && parts.size() == 4) {
    t = Tool::grasper(number(1, "radius"), number(2, "length"),
                      number(3, "opening") * std::numbers::pi / 180);
  } else {
    throw InvalidInput(
        cat("tool '", text, "': expected sphere:R, capsule:R:L or grasper:R:L:DEG (mm, degrees)"));
  }
  validate_tool(t, cat("tool '", text, "'"));
  return t;
}

int primitives(const Tool& tool, const Pose& pose, Capsule out[2]) {
  switch (tool.kind) {
    case ToolKind::Sphere:
      out[0] = {pose.position, pose.position, tool.radius};
      return 1;
    case ToolKind::Capsule:
      out[0] = {pose.position, pose.apply(Vec3(0, 0, tool.length)), tool.radius};
      return 1;
    case ToolKind::Grasper: {
      const double s = std::sin(0.5 * tool.opening), c = std::cos(0.5 * tool.opening);
      out[0] = {pose.position, pose.apply(tool.length * Vec3(s, 0, -c)), tool.radius};
      out[1] = {pose.position, pose.apply(tool.length * Vec3(-s, 0, -c)), tool.radius};
      return 2;
    }
  }
  return 0;
}

}  // namespace medspring
