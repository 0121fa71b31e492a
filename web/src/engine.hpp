// The Engine of the JavaScript API (embind, web/src/bindings.cpp; docs/web.md). One Engine = one
// Simulation of a model (a bundled phantom or a model package, models/model_package.hpp) plus a haptic
// virtual coupling (sim/haptics.hpp) for the mouse tool, or a rigid tool (sphere probe, grasper:
// sim/tool_sim.hpp, docs/tools.md) that presses, slides and grasps through the contact model.
// web/src/engine.cpp: the model, time, health and settings; web/src/engine_tools.cpp: the tools and the
// trajectory replays.
#pragma once

#include <emscripten/val.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "js_interop.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/sim/haptics.hpp"
#include "medspring/sim/tool_sim.hpp"

namespace medspring::web {

class Engine {
 public:
  /// model: "kidney_phantom" | "tube" | "vessel_phantom", or a Uint8Array holding a model package.
  /// nonlinear: Duffing springs (a package keeps its own setting unless this differs from it).
  Engine(const val& model, bool nonlinear, bool local);

  // ---- what the model is
  int numSurfaceNodes() const { return static_cast<int>(body_->num_surface_nodes()); }
  int numAtoms() const {
    return static_cast<int>(atom_offset_ < 0 ? 0 : sim_->state().x.rows() - atom_offset_);
  }
  std::string kind() const { return body_->kind(); }
  std::string name() const { return package_.name; }
  std::string description() const { return package_.description; }
  int numMasses() const { return static_cast<int>(body_->model().num_nodes()); }
  int numSprings() const { return static_cast<int>(body_->model().num_springs()); }
  /// Rest bounding-box diagonal of the surface, mm.
  double size() const { return size_; }
  double time() const { return sim_->time(); }

  // ---- zero-copy views into wasm memory (valid until the next allocation: re-take them every frame)
  val positions() const { return float_array(pos_); }
  val restPositions() const { return float_array(rest_); }
  val faces() const { return float_array(faces_); }
  /// Current atom positions (#A*3): hybrid skeleton atoms, SMRM centerline atoms; empty for a surface body.
  /// The centerline is the polyline through them in order.
  val atoms() const { return float_array(atoms_); }
  /// The centerline: the polyline through atoms() in order (the same view; for readability).
  val centerline() const { return float_array(atoms_); }
  /// Centerline segments as pairs of atom indices (#segments*2): the springs between atoms (an SMRM
  /// chain: i, i+1; a vessel tree: its branches, meeting at shared junction atoms).
  val centerlineEdges() const { return float_array(edges_); }
  /// Spokes as pairs (surface node, atom), #spokes*2: hybrid spokes (D-9), SMRM node -> its atom.
  val spokes() const { return float_array(spokes_); }
  /// Exact (double) position of one surface node, for tests.
  val node(int i) const;
  /// max_i |x_i - x0_i| over the displayed surface, mm.
  double maxDisplacement() const {
    return (sim_->surface() - body_->rest_surface()).rowwise().norm().maxCoeff();
  }

  // ---- the tool (virtual coupling, docs/haptics.md)
  /// Couples the tool to surface node i at its current position (no force until the tool moves).
  void grab(int i, double k_vc, double b_vc, double f_max);
  void moveTool(double x, double y, double z);
  void release();
  bool grabbed() const { return loop_ != nullptr; }

  // ---- a rigid tool (docs/tools.md): "sphere:R" | "capsule:R:L" | "grasper:R:L:DEG"
  /// Places a rigid tool with its centre (sphere) / tip / hinge at (x, y, z), its local -z along
  /// (dx, dy, dz) (the direction it presses in), replacing a held node or another tool. Throws an Error
  /// for a bad tool, pose or friction, or a tool that starts inside the organ. Each tick the tool moves
  /// towards moveTool()'s target by at most maxStep (mm; 0 = no limit) and the contact reaction is
  /// reaction() (saturated to f_max N).
  void placeTool(const std::string& spec, double x, double y, double z, double dx, double dy, double dz,
                 double friction, double f_max, double max_step);
  /// Opening of the grasper (degrees): closing to <= the grasp angle holds what the jaws touch.
  void setOpening(double degrees);
  bool hasTool() const { return tools_ != nullptr; }
  /// The placed tool: {kind, radius, length, opening (deg), position [xyz], axis [xyz] (local -z),
  /// force [xyz] (N, on the tool), torque, area (mm^2), penetration (mm), contacts, grasping,
  /// attached, graspForce (N)}; null without a tool.
  val toolState() const;
  int contact() const { return loop_ ? static_cast<int>(loop_->contact()) : -1; }
  val tool() const { return vec(tool_); }
  /// Reaction for the device (-F, N) of the last tick; zero when nothing is grabbed.
  val reaction() const { return vec(reaction_); }

  // ---- time
  /// One 1 ms tick (two 0.5 ms updates); returns its compute time (µs).
  double tick();
  /// n ticks, the surface mirrored once at the end; returns their total compute time (µs). A state
  /// that diverges is reset to rest (message()).
  double ticks(int n);
  /// Median, p99 and mean compute time (µs) of the last (up to) 1000 ticks, and the tick count.
  val tickStats() const;

  // ---- health
  bool finite() const { return sim_->state().x.allFinite() && sim_->state().v.allFinite(); }
  /// The last automatic-reset message ("" when none) and the number of automatic resets.
  std::string message() const { return message_; }
  void clearMessage() { message_.clear(); }
  int autoResets() const { return auto_resets_; }
  /// Test hook: puts a NaN into the state, as a diverging integration would.
  void injectNaN();

  // ---- settings
  void reset();
  void setLocal(bool on);
  bool local() const { return sim_->settings().local.enabled; }
  /// {k, eta, kr, beta, nonlinear} (models/model_package.hpp TissueParams).
  val params() const;
  /// Sets any of {k, eta, kr, beta, nonlinear} and rebuilds the body; the state (positions,
  /// velocities, time) and a grabbed node are kept when the DOF count is unchanged (a rigid tool is
  /// removed). Invalid values
  /// throw an Error naming the parameter, and nothing changes.
  void setParams(const val& p);

  /// Replays a trajectory CSV through the haptic loop exactly as `medspring haptics` does; returns
  /// per tick [t, contact xyz, reaction xyz] as one flat JS array.
  val runTrajectory(const std::string& csv, int contact);
  /// The same replay, timed: {median, p99, max, mean, ticks} of the per-tick compute time (µs) and
  /// times, a Float64Array of every tick's.
  val benchTrajectory(const std::string& csv, int contact);
  /// Replays a tool path CSV (time_ms, x, y, z) with a rigid tool exactly as `medspring haptics
  /// --tool SPEC --friction MU` does; returns per tick [t, tool xyz, reaction on the tool xyz] flat.
  val runToolTrajectory(const std::string& csv, const std::string& spec, double friction);

 private:
  static val vec(const Vec3& v) {
    val a = val::array();
    for (int c = 0; c < 3; ++c) a.call<void>("push", v(c));
    return a;
  }
  void drop_tool() {
    tool_loop_.reset();
    tools_.reset();  // detaches its surface forces from the simulation
  }
  void check_node(int i) const;

  /// One tick; a state that is no longer finite, could not be advanced, or flew apart is reset.
  double advance();
  void auto_reset(const std::string& why);
  void build_spokes();
  void mirror();

  ModelPackage package_;
  BodyPtr body_;
  std::unique_ptr<Simulation> sim_;
  std::unique_ptr<HapticLoop> loop_;
  std::unique_ptr<ToolSimulation> tools_;  // a rigid tool (placeTool), or none
  std::unique_ptr<ToolHapticLoop> tool_loop_;
  double max_step_ = 0;
  HapticSettings haptic_;
  Vec3 tool_ = Vec3::Zero(), reaction_ = Vec3::Zero();
  std::vector<float> pos_, rest_, atoms_;
  std::vector<std::uint32_t> faces_, spokes_, edges_;
  Index atom_offset_ = -1;  // first atom DOF (hybrid: #S, smrm: 0), -1 without atoms
  double size_ = 0;
  std::vector<double> times_ = std::vector<double>(1000, 0.0);
  std::size_t times_used_ = 0;
  long tick_count_ = 0;
  std::uint64_t failed_seen_ = 0;
  std::string message_;
  int auto_resets_ = 0;
};

}  // namespace medspring::web
