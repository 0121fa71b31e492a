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
};
Integrator parse_integrator(const std::string& text);
std::string to_string(Integrator integrator);

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
};

/// Validates settings (finite positive dt, safety in (0, 1], ...). Throws InvalidInput naming the field.
/// With substep = false and the symplectic integrator, also rejects dt above the model's stable step at rest.
void validate_step_settings(const Model& model, const StepSettings& s);

/// Threads the step really uses: settings.threads, reduced so that every thread gets at least
/// kMinSpringsPerThread springs (1 for smaller models), 1 for the implicit integrator, bending terms or a
/// build without threads (WebAssembly). Deterministic: the same model and settings give the same count.
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

/// Advances the state by one frame of duration settings.dt. External force: `loads` evaluated at the
/// start of every substep if given, else state.f_ext held constant. No heap allocation.
StepStatus step(const Model& model, State& state, const StepSettings& settings,
                const std::vector<PointLoad>* loads = nullptr);

}  // namespace medspring
