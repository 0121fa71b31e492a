// Time integration (ALGORITHMS.md §2): symplectic Euler with implicit damping (default) and linearly
// implicit Euler with a matrix-free Jacobi-preconditioned CG solve.
#pragma once

#include <string>
#include <vector>

#include "medspring/physics/loads.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/physics/state.hpp"

namespace medspring {

enum class Integrator {
  SymplecticEuler,  // default, §2.1
  ImplicitEuler,    // §2.3 (Baraff & Witkin), unconditionally stable, dissipative
  // Quasi-static and linear (issue 23, physics/linear_response.hpp): x = x0 + K0^-1 f_ext at every frame,
  // the tangent at rest factored once and each loaded node's response cached; no inertia, no stiffening
  LinearStatic,
};
Integrator parse_integrator(const std::string& text);
std::string to_string(Integrator integrator);
inline Integrator parse_enum(const std::string& text, Integrator*) {
  return parse_integrator(text);
}

/// The symplectic step's stable-step rule (docs/volumetric-stable-step.md).
/// Bound: the growth bound of the last force pass (the default; cheap, a bound at every frame). Refresh: for
/// models with volume or compression terms, the bound is replaced where smaller by a 15-product Lanczos
/// estimate on the current tangent, retaken every 20-200 frames one product per frame on a snapshot (fewer
/// sub-steps under load; ~0.8 ms more CPU on the frames that take a product, and its band and age limits are
/// heuristic: for offline runs).
enum class StableStep { Bound, Refresh };
/// "bound" | "refresh"; InvalidInput naming stable_step otherwise.
StableStep parse_stable_step(const std::string& text);
std::string to_string(StableStep rule);
inline StableStep parse_enum(const std::string& text, StableStep*) {
  return parse_stable_step(text);
}

struct StepSettings {
  double dt = 0.5;  // frame duration (ms)
  Integrator integrator = Integrator::SymplecticEuler;
  bool substep = true;          // split a frame above dt_safe into equal substeps (§2.2); false: refuse it
  double safety = 0.8;          // dt_safe = safety * 2 / omega
  int max_substeps = 4096;      // cap on substeps per frame (counted in Warnings when hit)
  bool guard = true;            // roll back and halve the step on NaN/Inf or |v| > v_max (§2.5)
  double v_max = 100.0;         // mm/ms
  int max_rollbacks = 6;        // halvings tried before the frame is reported failed
  double cg_tolerance = 1e-8;   // implicit: relative residual
  int cg_max_iterations = 200;  // implicit
  int newton_iterations = 1;    // implicit: 1 = linearly implicit; > 1 = full Newton with line search
  int threads = 1;  // symplectic: threads of the step, 1..256 (kMaxThreads); see effective_threads
  StableStep stable_step = StableStep::Bound;  // symplectic, volume/compression terms: see StableStep
};

/// The declaration of StepSettings (core/params.hpp): the scene's "integrator" block, the Python
/// properties and keywords of StepSettings, the table in docs/parameters.md.
template <ParamOf<StepSettings> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"integrator", "",
              "symplectic_euler (§2.1), implicit_euler (§2.3) or linear_static (quasi-static linear response "
              "x0 + K0^-1 f, precomputed: docs/linear-response.md)"}
        .json_key("method"),
    s.integrator);
  v(ParamSpec{"dt", "ms", "frame duration"}.positive(), s.dt);
  v(ParamSpec{"substep", "", "split a frame above dt_safe into equal substeps (§2.2); false: refuse it"},
    s.substep);
  v(ParamSpec{"safety", "", "dt_safe = safety * 2 / omega"}.positive().at_most(1), s.safety);
  v(ParamSpec{"max_substeps", "", "cap on substeps per frame (counted in warnings when hit)"}.at_least(1),
    s.max_substeps);
  v(ParamSpec{"guard", "", "roll back and halve the step on NaN/Inf or |v| > v_max (§2.5)"}, s.guard);
  v(ParamSpec{"v_max", "mm/ms", "speed above which the guard rolls back"}.positive(), s.v_max);
  v(ParamSpec{"max_rollbacks", "", "halvings tried before the frame is reported failed"}.nonnegative(),
    s.max_rollbacks);
  v(ParamSpec{"cg_tolerance", "", "implicit: relative residual of the CG solve"}.positive(), s.cg_tolerance);
  v(ParamSpec{"cg_max_iterations", "", "implicit: CG iterations per solve"}.at_least(1), s.cg_max_iterations);
  v(ParamSpec{"newton_iterations", "", "implicit: 1 = linearly implicit; > 1 = Newton with line search"}
        .at_least(1),
    s.newton_iterations);
  v(ParamSpec{"threads", "", "symplectic: threads of the step (see effective_threads)"}.at_least(1).at_most(
        256),
    s.threads);
  v(ParamSpec{"stable_step", "",
              "symplectic, volumetric: bound (growth bound, default) or refresh (tangent estimate every "
              "20-200 frames, one product per frame: fewer sub-steps; heuristic, offline runs)"},
    s.stable_step);
}

/// Validates settings (finite positive dt, safety in (0, 1], ...). Throws InvalidInput naming the field.
/// With substep = false and the symplectic integrator, also rejects dt above the model's stable step at rest.
void validate_step_settings(const Model& model, const StepSettings& s);

/// Threads the step really uses: settings.threads, reduced so that every thread gets at least
/// kMinSpringsPerThread springs (1 for smaller models), 1 for the implicit integrator, bending terms or a
/// build without threads (WebAssembly). A volumetric model with the float volume pass (volume_precision
/// float, the default) runs the sub-steps without the stable step's bound on settings.threads threads,
/// reduced so that every thread gets at least 2,000 tetrahedra (docs/threads.md, "Volumetric models").
/// Deterministic: the same model and settings give the same count.
int effective_threads(const Model& model, const StepSettings& settings);

/// Readies a state for steps with these settings: allocates the implicit integrator's scratch when it
/// is used and missing, and starts the worker pool and partitions the model for a threaded step (when
/// effective_threads > 1). step() does this itself on first use; calling it beforehand keeps thread
/// creation and allocation out of the first update.
void prepare_step(const Model& model, State& state, const StepSettings& settings);

/// A state at rest with only the scratch that steps with `settings` need (make_state(model) allocates
/// the implicit integrator's too: about 360 bytes per node more), prepared by prepare_step.
State make_state(const Model& model, const StepSettings& settings);

enum class StepCode { Ok, RolledBack, Refused, Failed };

struct StepStatus {
  StepCode code = StepCode::Ok;
  int substeps = 0;       // substeps taken in this frame
  int cg_iterations = 0;  // implicit: total CG iterations in this frame
  bool ok() const { return code == StepCode::Ok || code == StepCode::RolledBack; }
};

/// A force re-evaluated at the start of every substep of a frame (contact at the substep rate,
/// sim/tool_sim.hpp): fn(ctx, state, t) is called before each substep's force evaluation, the first
/// one included, with the substep's start time t (again, with the same t, after a rollback) and may
/// change state.f_ext. It must not allocate or throw.
struct SubstepForce {
  void (*fn)(void* ctx, State& state, double t) = nullptr;
  void* ctx = nullptr;
};

/// Advances the state by one frame of duration settings.dt. LinearStatic: x = x0 + K0^-1 f_ext with the force
/// at the frame's start (loads, then per_substep, called once), v = the frame's mean velocity, one "substep";
/// the first frame factors K0 unless prepare_step did, and a node's first load solves its response
/// (allocates) unless LinearResponse::precompute did. External force: `loads` evaluated at the start of every
/// substep if given, else state.f_ext held constant; then `per_substep` if given. No heap allocation.
StepStatus step(const Model& model, State& state, const StepSettings& settings,
                const std::vector<PointLoad>* loads = nullptr, const SubstepForce* per_substep = nullptr);

}  // namespace medspring
