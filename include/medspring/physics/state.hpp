// The mutable simulation state (ALGORITHMS.md §2): positions, velocities, time, scratch, warnings.
#pragma once

#include <cstdint>
#include <memory>

#include "medspring/core/types.hpp"
#include "medspring/physics/model.hpp"

namespace medspring {

/// Counters of numerical trouble detected inside steps (never thrown; the caller decides).
struct Warnings {
  std::uint64_t nonfinite = 0;         // a substep produced NaN/Inf: rolled back
  std::uint64_t velocity_limit = 0;    // max |v| exceeded StepSettings::v_max: rolled back
  std::uint64_t rollbacks = 0;         // frames retried with a halved step
  std::uint64_t unstable_refused = 0;  // frames refused: dt above the stable bound with sub-stepping off
  std::uint64_t substeps_capped = 0;   // the bound asked for more than max_substeps
  std::uint64_t cg_not_converged = 0;  // implicit solves that hit the iteration limit
  std::uint64_t failed = 0;            // frames that could not be advanced at all (state restored)
  /// Volume terms (issue 23): tetrahedra inverted at a frame's end, summed over frames.
  std::uint64_t inverted_elements = 0;
  std::uint64_t total() const {
    return nonfinite + velocity_limit + unstable_refused + substeps_capped + cg_not_converged + failed +
           inverted_elements;
  }
};

class LinearResponse;  // physics/linear_response.hpp
struct ThreadedStep;   // worker pool + static partition of the threaded step (integrators.cpp)

/// A State's worker pool for StepSettings::threads > 1. A copied State starts without one (it is made
/// again by prepare_step or at the copy's first threaded step), so copies never share threads.
struct ThreadedStepHandle {
  std::shared_ptr<ThreadedStep> p;
  ThreadedStepHandle() = default;
  ThreadedStepHandle(const ThreadedStepHandle&) noexcept {}
  ThreadedStepHandle& operator=(const ThreadedStepHandle&) noexcept { return *this; }
  ThreadedStepHandle(ThreadedStepHandle&&) noexcept = default;
  ThreadedStepHandle& operator=(ThreadedStepHandle&&) noexcept = default;
  ~ThreadedStepHandle() = default;
};

/// Everything that changes while simulating. Copying a State is a checkpoint.
struct State {
  MatX3 x;                     // positions (#N x 3), mm
  MatX3 v;                     // velocities (#N x 3), mm/ms
  MatX3 f_ext;                 // external force held over the next frame (#N x 3), N
  double t = 0.0;              // time, ms
  std::uint64_t frames = 0;    // frames advanced
  std::uint64_t substeps = 0;  // substeps taken in total
  double stiffening = 1.0;     // max_s kappa_s / k_s at the last force evaluation (>= 1), §2.2
  Warnings warnings;

  // Scratch (sized once by make_state; never reallocated inside a step).
  MatX3 f;                                       // force accumulator (#N x 3)
  MatX3 x_save, v_save;                          // implicit: substep-start copy for the rollback guard
  MatX3 x_trial;                                 // implicit Newton: trial positions
  VecX step_coef;                                // symplectic: 1 / (m + h d) per node for the cached h
  VecX spring_force;                             // gather pass: force of every spring slot, x | y | z blocks
  VecX stiff_rows;                               // volume terms: local stiffening rows (#N), increments (#T)
  std::vector<float> volume_f32;                 // single-precision volume pass (Model::volume_f32): 8 #N
  double step_coef_h = -1.0;                     // the h step_coef was computed for
  VecX cg_r, cg_z, cg_p, cg_q, dv, rhs, jacobi;  // implicit Euler (3N)
  VecX spring_a, spring_b;                       // implicit: per-spring stiffness coefficients (#S)
  MatX3 spring_n;                                // implicit: per-spring unit directions (#S x 3)
  ThreadedStepHandle threaded;                   // symplectic, StepSettings::threads > 1
  // Integrator::LinearStatic: the factored response at rest (a function of the model: copies share it; its
  // cache is thread-safe) and its direct solve's scratch (#free DOFs)
  std::shared_ptr<LinearResponse> linear;
  VecX linear_b, linear_u;
};

/// A state at rest (x = x0, v = 0, t = 0) with all scratch allocated.
State make_state(const Model& model);

}  // namespace medspring
