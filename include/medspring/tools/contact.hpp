// Contact of rigid tools with a deforming triangle surface (docs/tools.md): collision against the
// deformed triangles through a bounding volume hierarchy refitted every update, and a penalty
// response that keeps the surface outside the tools.
//
//   ContactModel contact(body.faces(), body.rest_surface(), {.min_mass = 0.3, .dt = 0.5});
//   Index probe = contact.add_tool(Tool::sphere(5), pose);
//   contact.set_pose(probe, next_pose);                    // between updates
//   contact.update(surface);                               // collision + forces on the surface nodes
//   contact.forces();                                      // per-node forces on the tissue (N)
//   contact.state(probe).force, .torque;                   // reaction on the tool
//
// Response: one contact per (tool capsule, triangle) whose closest point lies less than r from the
// capsule's axis; its normal force on the tissue is A_t (k_p d + c_p d') (never pulling), with A_t the
// triangle's rest area, d the penetration, d' its rate; optional regularised Coulomb friction
// |f_t| <= mu f_n opposing the slip. Forces go to the triangle's three nodes by barycentric weights.
// The penalty is explicit and held over one update, so k_p is bounded by the stable-step condition
// k_p max_i(sum of the rest areas around node i) dt^2 / m_min <= kappa (the automatic k_p sits on it).
// Because that bound caps the stiffness, a pure penalty would leave a steady penetration of
// f_i / k_i; an augmented-Lagrangian multiplier per contact node (lambda_i <- max(0, lambda_i +
// multiplier k_i d_i) every update with d_i the node's signed depth inside the tool, along the node's
// contact normal, reset when the node leaves the contact) removes it: under a steady press the nodes
// settle on the tool's surface and lambda_i carries the tissue's force.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "medspring/core/params.hpp"
#include "medspring/tools/surface_bvh.hpp"
#include "medspring/tools/tool.hpp"

namespace medspring {

struct ContactSettings {
  double min_mass = 0.3;   // g: the smallest mass a surface force acts on (stability bound)
  double dt = 0.5;         // ms: the update the forces are held over
  double stiffness = 0.0;  // k_p, N/mm^3 (pressure per mm of penetration); 0 = automatic (kappa)
  double kappa = 1.0;      // automatic k_p: k_p max_i(A_i) dt^2 / m_min = kappa (symplectic bound 4)
  double damping = 0.25;   // c_p = damping k_p dt (N ms/mm^3)
  double multiplier =
      0.25;               // augmented Lagrangian: lambda_i += multiplier k_i d_i per update (0: pure penalty)
  double friction = 0.0;  // Coulomb coefficient mu (0: frictionless)
  double slip_velocity = 0.01;  // mm/ms: below it friction is viscous (regularised Coulomb)
  double max_depth = 2.0;       // contacts are reported up to a depth of max_depth x r (tunnelling guard)
  double grasp_angle = 0.15;    // rad: a grasper with opening <= this holds what its jaws touch
  bool substep = false;  // re-evaluate the normal penalty forces at every substep of the model (substep())
};

/// The declaration of ContactSettings (core/params.hpp): the scene's "contact" block, validation, the
/// Python properties and keywords, `run --set contact.NAME=VALUE`, the table in docs/parameters.md.
/// A scene may give the grasp angle in degrees as "grasp_angle_deg" (scene_tools.cpp).
template <ParamOf<ContactSettings> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"friction", "", "Coulomb coefficient mu (0: frictionless)"}.nonnegative(), s.friction);
  v(ParamSpec{"stiffness", "N/mm^3", "penalty k_p per mm of penetration; 0 = automatic (kappa)"}
        .nonnegative(),
    s.stiffness);
  v(ParamSpec{"kappa", "", "automatic k_p: k_p max(A) dt^2 / m_min = kappa (symplectic bound 4)"}
        .positive()
        .at_most(4),
    s.kappa);
  v(ParamSpec{"damping", "", "c_p = damping k_p dt"}.nonnegative(), s.damping);
  v(ParamSpec{"multiplier", "", "augmented Lagrangian: lambda += multiplier k d per update (0: penalty)"}
        .nonnegative()
        .at_most(1),
    s.multiplier);
  v(ParamSpec{"slip_velocity", "mm/ms", "below it friction is viscous (regularised Coulomb)"}.positive(),
    s.slip_velocity);
  v(ParamSpec{"max_depth", "", "contacts reported up to max_depth x the tool radius (tunnelling guard)"}
        .at_least(1),
    s.max_depth);
  v(ParamSpec{"grasp_angle", "rad", "a grasper with opening <= this holds what its jaws touch"}
        .nonnegative()
        .at_most(3.141592653589793, true),
    s.grasp_angle);
  v(ParamSpec{"substep", "", "re-evaluate the normal penalty forces at every substep of the model"},
    s.substep);
  v(ParamSpec{"min_mass", "g", "the smallest node mass a surface force acts on"}.positive().set_by_program(),
    s.min_mass);
  v(ParamSpec{"dt", "ms", "the update the forces are held over"}.positive().set_by_program(), s.dt);
}

/// Throws InvalidInput naming the field.
void validate_contact_settings(const ContactSettings& s);

/// One contact between a tool capsule and a surface triangle.
struct Contact {
  Index triangle = -1;
  int tool = 0;                // tool index
  int part = 0;                // capsule of the tool (grasper: jaw 0 or 1)
  Vec3 point = Vec3::Zero();   // closest point on the deformed triangle (mm)
  Vec3 bary = Vec3::Zero();    // its barycentric weights on the triangle's nodes
  Vec3 normal = Vec3::Zero();  // unit: out of the tissue, towards the tool (the tool is pushed along it)
  double depth = 0;            // penetration (mm), > 0
  double area = 0;             // rest area of the triangle (mm^2)
  Vec3 force = Vec3::Zero();   // force on the tissue (N); the tool gets -force
};

/// Per-tool results of the last update.
struct ToolState {
  Tool tool;
  Pose pose;                        // current pose
  Vec3 force = Vec3::Zero();        // reaction on the tool (N) = -(sum of the forces on the tissue)
  Vec3 torque = Vec3::Zero();       // about pose.position (N mm) = sum (x_c - p) x (-f_c)
  double area = 0;                  // rest area of the triangles in contact (mm^2)
  double penetration = 0;           // deepest surface node inside the tool (mm)
  double triangle_penetration = 0;  // deepest contact point on a triangle (mm): adds the flat
                                    // triangles' chord sagitta, about h^2 / (8 r) for edges h
  Index contacts = 0;               // contacts of this tool
  bool inside = false;              // its axis was inside the organ with no triangle within r: the
                                    // contacts were kept from the nearest surface (persistent contact)
  bool grasping = false;            // grasper holds tissue
  Index attached = 0;               // surface points held by the jaws
  Vec3 grasp_force = Vec3::Zero();  // force of the held points on the jaws (N)
};

/// Forces on surface nodes: dense per node, plus the list of nodes that carry one.
struct SurfaceForces {
  MatX3 force;               // #S x 3 (N), zero outside `nodes`
  std::vector<Index> nodes;  // nodes with a force this update
  Vec3 total = Vec3::Zero();
  Index centre = -1;  // node with the largest force (centre of the local patch), -1 if none
};

class ContactModel {
 public:
  /// faces: #F x 3 (outward orientation is detected from the rest volume); rest: #S x 3, mm.
  ContactModel(const MatX3i& faces, const MatX3& rest, const ContactSettings& settings = {});

  /// Adds a tool at a pose; throws InvalidInput for a bad tool or pose. Returns its index.
  Index add_tool(const Tool& tool, const Pose& pose);
  /// Moves tool k (the motion since the last update is swept). Throws InvalidInput for a NaN pose.
  void set_pose(Index k, const Pose& pose);
  /// Opening angle of grasper k (rad); closing to <= grasp_angle grasps what the jaws touch, opening
  /// beyond it releases. Throws InvalidInput outside [0, pi] or for a tool that is not a grasper.
  void set_opening(Index k, double opening);
  Index num_tools() const { return static_cast<Index>(tools_.size()); }

  /// Throws InvalidInput naming `what` when an end of one of the tool's axes lies inside the closed
  /// surface (generalized winding number >= 1/2): a tool that starts inside the organ is refused, not
  /// pushed out.
  void check_outside(const MatX3& surface, const Tool& tool, const Pose& pose, const std::string& what) const;

  /// Collision of every tool with `surface` (#S x 3, the deformed surface) and the response forces.
  /// Velocities are finite differences over settings().dt. No allocation after the first call.
  void update(const MatX3& surface);
  /// Drops the velocity history (after a reset of the body or a jump of a tool): the next update sees
  /// the surface and the tools at rest.
  void reset_history();
  /// The state that carries over between updates, for a checkpoint: every tool's pose, opening, last
  /// pose and grasp attachments, the augmented-Lagrangian multipliers and the last surface. After
  /// restore_history() on a model built from the same surface with the same tools, the next update()
  /// gives the same bits as the saved model's next update.
  std::string save_history() const;
  /// Throws IoError "<what>: ..." when the bytes are malformed, InvalidInput when they belong to another
  /// surface or tool set (node count, tool kinds and sizes); the model is unchanged then.
  void restore_history(std::string_view bytes, const std::string& what = "contact history");

  /// Contact at the substep rate (docs/tools.md): while the model sub-steps a frame, re-evaluates the
  /// normal penalty force of every contact of the last update() on S, the surface at time t inside the
  /// frame, with the contact set, the normals and the tools' poses held and the depth re-projected along
  /// the held normal (d = depth + n . (p(S) - p(frame start))), its rate by finite differences over the
  /// substeps. Writes the change of the per-node forces since the previous call into the rows
  /// forces().nodes of `delta` (#S x 3; other rows untouched) and returns true, or returns false when
  /// nothing changes: the first call after update() (the frame's forces are the update's), no contact,
  /// or settings().substep off. No allocation.
  bool substep(const MatX3& S, double t, MatX3& delta);
  /// Ends the frame at time t after substep() calls: every contact's force, the tools' reactions and
  /// forces().total become the frame's time averages (the impulse over the frame / its duration).
  void end_frame(double t);

  const SurfaceForces& forces() const { return forces_; }
  const std::vector<Contact>& contacts() const { return contacts_; }
  const ToolState& state(Index k) const { return tools_[static_cast<std::size_t>(k)].state; }
  const ContactSettings& settings() const { return settings_; }
  /// The penalty stiffness in use (N/mm^3) and its stable limit (kappa = 4).
  double stiffness() const { return k_p_; }
  double stiffness_limit() const { return k_limit_; }
  const SurfaceBvh& bvh() const { return bvh_; }

 private:
  struct Attachment {
    Index triangle;
    Vec3 bary;
    Vec3 anchor;  // in the tool frame
  };
  struct ToolSlot {
    ToolState state;
    Pose prev;
    std::vector<Attachment> held;
    bool touching = false;  // it had contacts at the last update
  };
  /// Contacts of capsule c with the triangles whose closest point is within `reach` of its axis; depths
  /// above max_depth r are dropped, or with `inside` (persistent contact) capped to it.
  bool collide(const Capsule& c, const Capsule& c_prev, int tool, int part, const MatX3& S, double reach,
               bool inside);
  /// Generalized winding number of the closed surface S around q (>= 1/2: q is inside).
  double winding(const MatX3& S, const Vec3& q) const;
  /// Distance from q to the nearest triangle of S (all triangles: used only for a tool found inside).
  double nearest_distance(const MatX3& S, const Vec3& q) const;
  void add_force(Index tri, const Vec3& bary, const Vec3& f);
  Vec3 pseudo_normal(const MatX3& S, Index tri, int region) const;

  ContactSettings settings_;
  MatX3i F_;
  VecX area_;                         // rest triangle areas
  std::vector<Index> adj_face_;       // 3 per face: face across edge (v_k, v_k+1), -1 on a border
  std::vector<Index> vf_start_, vf_;  // vertex -> faces (CSR)
  double orient_ = 1.0;               // +1 if faces are counter-clockwise seen from outside
  double k_p_ = 0, k_limit_ = 0;
  SurfaceBvh bvh_;
  std::vector<ToolSlot> tools_;
  std::vector<Contact> contacts_;
  std::vector<Index> candidates_;
  SurfaceForces forces_;
  std::vector<std::uint8_t> touched_;
  VecX node_w_, node_wd_, lambda_;   // per node: sum w A, sum w A d over contacts; multiplier (N)
  MatX3 node_fn_;                    // per node: penalty normal force (direction of the multiplier)
  std::vector<int> node_tool_;       // tool of the node's last contact
  std::vector<Index> lambda_nodes_;  // nodes with lambda > 0 after the last update
  MatX3 prev_;
  bool have_prev_ = false;
  struct SubContact {         // substep evaluation of contacts_[i] (substep(), end_frame())
    Vec3 p0;                  // the contact point from the barycentric weights at the frame start
    double fn0 = 0;           // normal force of the update (N)
    double fn = 0;            // normal force now applied
    double depth = 0, t = 0;  // depth at the last evaluation and its time
    double impulse = 0;       // integral of fn over the frame so far (N ms)
  };
  std::vector<SubContact> sub_;  // parallel to contacts_
  bool sub_open_ = false;        // substep() has been called since update()
  bool sub_changed_ = false;     // a substep changed the forces
  double sub_t0_ = 0, sub_t_ = 0;
};

}  // namespace medspring
