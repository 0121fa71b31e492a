// The 1 kHz haptic loop of ALGORITHMS.md §2.5 on a Simulation: a tool coupled to one surface node by a
// spring-damper (virtual coupling), the force saturated to the device maximum, applied to the model,
// and its opposite returned to the device every tick.
//
//   Simulation sim(body, settings);
//   HapticLoop loop(sim, contact_node);                 // k_vc 0.1 N/mm, b_vc 0.01 N ms/mm, 3 N max
//   for (;;) { Vec3 reaction = loop.tick(device_position()); send_to_device(reaction); }
//
// Offline, run_trajectory() replays a recorded tool path (read_trajectory: CSV time_ms, x, y, z).
#pragma once

#include <filesystem>
#include <istream>
#include <string>
#include <vector>

#include "medspring/sim/simulation.hpp"

namespace medspring {

struct HapticSettings {
  double tick = 1.0;   // ms, fixed physics tick (1 kHz); a multiple of the simulation's step.dt
  double k_vc = 0.1;   // N/mm, coupling stiffness (k_vc / m_node * tick^2 well below 4: stable)
  double b_vc = 0.01;  // N ms/mm, coupling damping on (v_tool - v_c)
  double f_max = 3.0;  // N, device maximum: |F| is saturated to it
  bool record = true;  // keep one HapticSample per tick in samples()
};

/// One tick of the loop.
struct HapticSample {
  double t = 0;                 // ms, simulation time at the start of the tick
  Vec3 tool = Vec3::Zero();     // tool position (mm)
  Vec3 contact = Vec3::Zero();  // contact node position x_c at the start of the tick (mm)
  Vec3 force = Vec3::Zero();    // F applied to the model (N); the device gets -F
  bool saturated = false;       // |F| was clipped to f_max
  double compute_us = 0;        // wall time of the tick (coupling + physics + local patch), µs
};

class HapticLoop {
 public:
  /// Couples a tool to surface node `contact` of `sim` (which must outlive the loop). The tick must be
  /// a whole multiple of sim.settings().step.dt. Throws InvalidInput naming the setting at fault.
  HapticLoop(Simulation& sim, Index contact, const HapticSettings& settings = {});

  /// One tick: F = k_vc (x_tool - x_c) + b_vc (v_tool - v_c), saturated to f_max, applied to the
  /// contact node for the whole tick (Simulation::set_tool_force), then the simulation advances by
  /// `tick`. x_c is the contact node on the global (mapped) surface, without the local overlay (the
  /// overlay is a display effect, and coupling to it would make the loop an explicit iteration on a
  /// stiff algebraic relation); velocities are finite differences over one tick (zero on the first).
  /// Returns the reaction for the device, -F (N).
  Vec3 tick(const Vec3& x_tool);
  /// Lets go of the tissue (no tool force until the next tick()).
  void release();

  const std::vector<HapticSample>& samples() const { return samples_; }
  const HapticSample& last() const { return last_; }
  Index contact() const { return contact_; }
  const HapticSettings& settings() const { return settings_; }
  int updates_per_tick() const { return updates_per_tick_; }

 private:
  Simulation& sim_;
  Index contact_;
  HapticSettings settings_;
  int updates_per_tick_ = 1;
  bool first_ = true;
  Vec3 tool_prev_ = Vec3::Zero(), contact_prev_ = Vec3::Zero();
  HapticSample last_;
  std::vector<HapticSample> samples_;
};

/// A recorded tool path: strictly increasing times (ms) and positions (mm).
struct TrajectoryPoint {
  double t = 0;
  Vec3 x = Vec3::Zero();
};
using Trajectory = std::vector<TrajectoryPoint>;

/// Reads a CSV of `time_ms, x, y, z` rows (mm). An optional first header row whose first field is not
/// a number, blank lines and lines starting with '#' are skipped. Throws InvalidInput naming
/// "<name>:<line>" for a row without exactly 4 numeric finite fields or a time not after the previous
/// one, and for a file without rows.
Trajectory read_trajectory(std::istream& in, const std::string& name = "trajectory");
/// The same from a file; IoError if it cannot be opened.
Trajectory read_trajectory_file(const std::filesystem::path& file);

/// The tool position at time t (ms): linear interpolation, held constant outside the recorded range.
Vec3 trajectory_position(const Trajectory& path, double t);

/// Per-tick compute time statistics, µs.
struct TickStats {
  double median_us = 0, p99_us = 0, max_us = 0, mean_us = 0;
  long ticks = 0;
};
TickStats tick_stats(const std::vector<HapticSample>& samples);

/// Replays `path` through `loop` from the simulation's current time until `duration` ms (default: the
/// last recorded time), one tick per `settings.tick`. Returns the statistics of the ticks run.
TickStats run_trajectory(HapticLoop& loop, const Trajectory& path, double duration = -1);

}  // namespace medspring
