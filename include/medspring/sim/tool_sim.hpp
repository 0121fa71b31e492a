// Rigid tools acting on a Simulation (docs/tools.md): every update, the tools' poses follow their
// paths, the contact model collides them with the deformed (global) surface, and its forces join the
// loads of the update. Reaction force and torque on each tool are available after every update.
//
//   Simulation sim(body, settings);
//   ToolSimulation tools(sim);                              // contact settings from the model
//   Index probe = tools.add_tool(Tool::sphere(5), pose);     // throws if it starts inside the organ
//   tools.set_path(probe, read_tool_path_file("press.csv"));
//   while (sim.time() < 500) tools.update();
//   tools.contact().state(probe).force;                      // N, on the tool
//
// A haptic device drives a tool through ToolHapticLoop: the tool (a kinematic proxy) sits at the
// device position each 1 ms tick and the device receives the contact reaction, saturated to f_max.
#pragma once

#include <filesystem>
#include <istream>
#include <string>
#include <vector>

#include "medspring/sim/haptics.hpp"
#include "medspring/sim/simulation.hpp"
#include "medspring/tools/contact.hpp"

namespace medspring {

/// A pose keyframe of a tool path. opening < 0: keep the grasper's opening.
struct ToolKeyframe {
  double t = 0;  // ms
  Pose pose;
  double opening = -1;  // rad
};
using ToolPath = std::vector<ToolKeyframe>;

/// Reads a CSV of rows `time_ms, x, y, z` or `time_ms, x, y, z, qw, qx, qy, qz` or the same plus
/// `opening_deg` (grasper). A first header row, blank lines and '#' lines are skipped. Throws
/// InvalidInput naming "<name>:<line>" for a row with another field count, a non-finite field, a
/// zero quaternion, an opening outside [0, 180] degrees or a time not after the previous row's.
ToolPath read_tool_path(std::istream& in, const std::string& name = "tool path");
/// The same from a file; IoError if it cannot be opened.
ToolPath read_tool_path_file(const std::filesystem::path& file);
/// Validates keyframes given in code (finite, increasing times, unit-able quaternions); throws
/// InvalidInput naming `what`[k].
void validate_tool_path(const ToolPath& path, const std::string& what);
/// The pose at time t: positions and openings interpolated linearly, rotations by slerp; held outside
/// the keyframes' range.
ToolKeyframe tool_path_at(const ToolPath& path, double t);

/// Contact settings for a simulation: dt of its frame, min_mass the smallest DOF mass.
ContactSettings contact_settings_for(const Simulation& sim, ContactSettings base = {});

class ToolSimulation {
 public:
  /// `sim` must outlive this object. base: contact settings (dt and min_mass are taken from sim).
  explicit ToolSimulation(Simulation& sim, const ContactSettings& base = {});
  ~ToolSimulation();
  ToolSimulation(const ToolSimulation&) = delete;
  ToolSimulation& operator=(const ToolSimulation&) = delete;

  /// Adds a tool; throws InvalidInput for a bad tool or pose or one that starts inside the organ.
  Index add_tool(const Tool& tool, const Pose& pose);
  /// Drives tool k along a path (from the simulation's time on); an empty path stops it.
  void set_path(Index k, ToolPath path);
  void set_pose(Index k, const Pose& pose) { contact_.set_pose(k, pose); }
  void set_opening(Index k, double opening) { contact_.set_opening(k, opening); }

  /// One update: poses from the paths at sim.time(), collision and response on the global surface,
  /// then Simulation::update() with the contact forces, their normal penalty part re-evaluated at every
  /// substep of the model (ContactModel::substep; the reactions are the frame's averages). Never throws
  /// after the first call.
  StepStatus update();
  StepStatus advance(long frames);
  /// Simulation::reset() and the contact's velocity history (tools keep their poses).
  void reset();

  /// The contact's history for a checkpoint (ContactModel::save_history): restored into a
  /// ToolSimulation with the same tools on the same model whose Simulation got the checkpoint, the
  /// next update() repeats the saved run's bit for bit.
  std::string save_history() const { return contact_.save_history(); }
  void restore_history(std::string_view bytes, const std::string& what = "contact history") {
    contact_.restore_history(bytes, what);
  }
  const ContactModel& contact() const { return contact_; }
  Simulation& simulation() { return sim_; }
  const Simulation& simulation() const { return sim_; }

 private:
  static void substep_contact(void* self, State& state, double t);

  Simulation& sim_;
  ContactModel contact_;
  std::vector<ToolPath> paths_;
  SubstepForce substep_{};
  MatX3 substep_surface_, substep_delta_;  // the surface at a substep, the change of the contact forces
};

/// The 1 kHz haptic loop with a tool: the device position places the tool (orientation kept) and
/// the device gets the reaction on the tool, saturated to settings.f_max.
class ToolHapticLoop {
 public:
  ToolHapticLoop(ToolSimulation& tools, Index tool, const HapticSettings& settings = {});
  /// One tick: tool at x_device, updates_per_tick updates; returns the force for the device (N).
  Vec3 tick(const Vec3& x_device);
  const std::vector<HapticSample>& samples() const { return samples_; }
  const HapticSample& last() const { return last_; }
  int updates_per_tick() const { return updates_per_tick_; }
  const HapticSettings& settings() const { return settings_; }

 private:
  ToolSimulation& tools_;
  Index tool_;
  HapticSettings settings_;
  int updates_per_tick_ = 1;
  HapticSample last_;
  std::vector<HapticSample> samples_;
};

/// Replays a position trajectory through a tool haptic loop (as run_trajectory does for HapticLoop).
TickStats run_tool_trajectory(ToolHapticLoop& loop, const Trajectory& path, double duration = -1);

}  // namespace medspring
