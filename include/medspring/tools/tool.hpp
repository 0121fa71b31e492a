// Rigid instruments (docs/tools.md): a shape and a pose. Every shape is one or two capsules (segment
// + radius; a sphere is a capsule of zero length), which is all the collision code needs.
//
//   Tool probe = Tool::sphere(5.0);                      // radius 5 mm
//   Tool shaft = Tool::capsule(2.0, 40.0);               // tip sphere r = 2 mm at the pose, shaft along +z
//   Tool jaws  = Tool::grasper(1.5, 12.0, 0.6);          // jaw radius, jaw length, opening angle (rad)
//   Pose pose{.position = {0, 0, 30}};
//   Capsule c[2];
//   int n = primitives(probe, pose, c);                  // 1 (sphere, capsule) or 2 (grasper jaws)
#pragma once

#include <Eigen/Geometry>
#include <string>

#include "medspring/core/types.hpp"

namespace medspring {

using Quat = Eigen::Quaterniond;

/// A rigid pose: the tool frame's origin (mm) and orientation (unit quaternion).
struct Pose {
  Vec3 position = Vec3::Zero();
  Quat rotation = Quat::Identity();
  Vec3 apply(const Vec3& local) const { return position + rotation * local; }
};

/// Throws InvalidInput naming `what` unless the position and quaternion are finite and the
/// quaternion is not zero; returns the pose with a normalised quaternion.
Pose checked_pose(const Pose& pose, const std::string& what);

enum class ToolKind { Sphere, Capsule, Grasper };
std::string to_string(ToolKind kind);

/// A tool shape in its own frame. The tool points along its local -z: the sphere is centred on the
/// origin; the capsule's tip sphere is centred on the origin and its shaft runs to (0, 0, length);
/// the grasper's two jaws hinge at the origin and run along (+-sin(a/2), 0, -cos(a/2)) for the
/// opening angle a, each a capsule of `radius` and `length`.
struct Tool {
  ToolKind kind = ToolKind::Sphere;
  double radius = 5.0;   // mm
  double length = 0.0;   // mm: capsule shaft, grasper jaw
  double opening = 0.0;  // rad, grasper only: angle between the jaws (0 = closed)

  static Tool sphere(double radius) { return {ToolKind::Sphere, radius, 0.0, 0.0}; }
  static Tool capsule(double radius, double length) { return {ToolKind::Capsule, radius, length, 0.0}; }
  static Tool grasper(double radius, double length, double opening) {
    return {ToolKind::Grasper, radius, length, opening};
  }
};

/// Throws InvalidInput naming `what` and the field for a non-positive or non-finite radius, a
/// negative length (or a zero one for a grasper), or an opening outside [0, pi].
void validate_tool(const Tool& tool, const std::string& what);

/// Parses "sphere:R", "capsule:R:L" or "grasper:R:L:OPENING_DEG" (mm, degrees). Throws InvalidInput.
Tool parse_tool(const std::string& text);

/// A capsule in world space: segment a-b and radius r (a == b: a sphere).
struct Capsule {
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();
  double r = 0;
};

/// The world-space capsules of `tool` at `pose` (1 for a sphere or capsule, 2 for a grasper: out[0]
/// the +x jaw, out[1] the -x jaw). Returns the count.
int primitives(const Tool& tool, const Pose& pose, Capsule out[2]);

}  // namespace medspring
