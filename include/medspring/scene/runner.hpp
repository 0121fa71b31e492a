// Running a built scene: one Simulation advanced frame by frame for the scene's duration, traces of
// every frame, and a callback at every frame to be recorded (the CLI writes .vtp files there).
//
//   SceneResult r = run_scene(built, {.on_frame = [&](const Simulation& sim, Index k) { ... }});
//   r.summary.peak_mm, r.trace.time, r.trace.node_disp[0] ...
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "medspring/scene/build.hpp"
#include "medspring/sim/checkpoint.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring {

/// Per-frame traces (one entry per update, plus the rest state at t = 0 first).
struct SceneTrace {
  std::vector<double> time;                    // ms
  std::vector<double> force;                   // |total applied force|, N
  std::vector<double> max_disp;                // max |u| over the displayed surface, mm
  std::vector<double> local_contact;           // |U| of the local overlay at the contact node, mm (0 without)
  std::vector<double> energy;                  // total energy (kinetic + springs + return springs), mJ
  std::vector<std::vector<double>> node_disp;  // [k][frame] |u| of BuiltScene::trace_nodes[k], mm
  std::vector<std::vector<double>> atom_disp;  // [k][frame] |u| of BuiltScene::trace_atoms[k], mm
  /// [tool][frame] reaction on scene.tools[k] (docs/tools.md): force (N), torque about its pose (N mm),
  /// rest area of the triangles in contact (mm^2), largest penetration (mm), |grasp force| (N).
  struct ToolTrace {
    std::vector<double> fx, fy, fz, tx, ty, tz, area, penetration, grasp;
  };
  std::vector<ToolTrace> tools;
  Index size() const { return static_cast<Index>(time.size()); }
};

/// One recorded surface frame.
struct RecordedFrame {
  Index index = 0;  // 0, 1, 2, ... in recording order
  double time = 0;  // ms
};

struct RunSummary {
  Index updates = 0;
  double wall_seconds = 0.0;
  double median_update_us = 0.0, mean_update_us = 0.0;
  std::uint64_t substeps = 0;    // substeps over the run
  std::uint64_t warnings = 0;    // State::warnings.total()
  double contact_peak_mm = 0.0;  // max |u| of the first load node
  double contact_hold_mm =
      0.0;  // |u| of the first load node in the last frame before its release (or at the end)
  double max_disp_peak_mm = 0.0;  // max over frames of max |u|
  double atom_hold_mm = 0.0;      // |u| of the first traced atom at the first load's release
  double local_hold_mm = 0.0;     // |U| of the local overlay at the first load node at its release
  double release_time = std::numeric_limits<double>::infinity();  // ms, the last release (inf: none)
  double return_ms =
      std::numeric_limits<double>::infinity();  // ms after release until every
                                                // surface node stays within return_tolerance (inf: never)
  double return_tolerance = 1e-3;               // mm
  double final_max_disp_mm = 0.0;               // max |u| at the end
  // SMRM vessels (0 / -1 for other models): the §5.6 validity rho kappa < 1 checked at every update,
  // and the bend of the centerline (alpha_i = turning angle between the segments at atom i). A resumed
  // run covers the updates from the resume on.
  double max_rho_kappa = 0.0;            // max over updates and atoms
  Index rho_kappa_violations = 0;        // (update, atom) pairs with rho kappa >= 1
  Index rho_kappa_updates = 0;           // updates with at least one violation
  double max_turning_change_deg = 0.0;   // max over updates and atoms of |alpha_i - alpha_i^0|
  Index max_turning_atom = -1;           // the atom where it was largest
  double hold_turning_change_deg = 0.0;  // max_i |alpha_i - alpha_i^0| in the hold frame
};

struct SceneResult {
  SceneTrace trace;
  std::vector<RecordedFrame> frames;  // the frames recorded by this call (a resumed run: from the resume on)
  RunSummary summary;
  long first_update = 1;  // 1, or the update after the resume point
  bool stopped = false;   // stopped at RunHooks::stop_at before the scene's duration
};

struct RunHooks {
  /// Called for every recorded frame (the rest state first) with the simulation after that update.
  std::function<void(const Simulation&, const RecordedFrame&)> on_frame;
  /// Called now and then with the fraction done in [0, 1].
  std::function<void(double)> on_progress;
  /// Every `checkpoint_every` updates (0: never), a checkpoint of the run: the simulation plus, in its
  /// `extra` section, the traces and frame count so far. A run resumed from it gives the same traces.
  long checkpoint_every = 0;
  std::function<void(const Checkpoint&)> on_checkpoint;
  /// Continue a run from one of its checkpoints (same scene: InvalidInput otherwise).
  const Checkpoint* resume = nullptr;
  /// Stop after the first update reaching this time (ms), before the scene's duration; a checkpoint
  /// is taken there when on_checkpoint is set.
  double stop_at = std::numeric_limits<double>::infinity();
};

/// One frame of a run's traces (what run_scene samples after every update, without the energy, the tool
/// traces and the vessel checks): time, |applied force|, max |u| of `surface` (the displayed surface),
/// the local overlay's |U| at the contact, |u| of the traced nodes and of the traced atoms (from the DOF
/// positions x). Shared by run_scene and the batch runner (scene/batch.hpp).
void scene_trace_sample(const BuiltScene& built, double time, const Vec3& applied, const MatX3& surface,
                        const MatX3& x, double local_contact, SceneTrace& trace);

/// The summary's metrics from a run's traces: release time, contact peak and hold, atom and local hold,
/// peak and final max displacement, return time. Returns the hold frame (the last frame with the first
/// load on). Shared by run_scene and the batch runner.
Index summarize_trace(const BuiltScene& built, const SceneTrace& trace, RunSummary& summary);

/// Runs the scene for its duration (ceil(duration / dt) updates). Never throws after the first update
/// (numerical trouble is counted in summary.warnings); throws what Simulation throws while setting up
/// (InvalidInput for bad loads) and whatever on_frame throws.
SceneResult run_scene(const BuiltScene& built, const RunHooks& hooks = {});

/// One point of a static force-displacement curve.
struct StaticPoint {
  double force = 0.0;       // N
  double contact_mm = 0.0;  // |u| of the loaded surface node at equilibrium
  double max_mm = 0.0;      // max |u| over the surface
  int iterations = 0;       // Newton iterations
};

/// The static response (§2.4) of the scene's model to its first load, with the magnitude scaled from 0
/// to the full value in `points` equal steps (continuation: each solve starts at the previous
/// equilibrium; residual below 1e-8 N). Local deformation is not included. Throws InvalidInput without a
/// load, SolverError if an equilibrium is not found.
std::vector<StaticPoint> static_response(const BuiltScene& built, int points = 21);

}  // namespace medspring
