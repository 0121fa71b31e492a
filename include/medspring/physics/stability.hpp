// Stable time-step estimates for the explicit integrator (ALGORITHMS.md §2.2).
#pragma once

#include <cmath>
#include <cstdint>

#include "medspring/physics/model.hpp"

namespace medspring {

/// Gershgorin bound on omega_max (rad/ms) of M^-1 K_t at positions x (cheap, conservative).
double gershgorin_omega(const Model& model, const MatX3& x);

/// Estimate of omega_max (rad/ms) at positions x from below: `iterations` Lanczos steps (matrix-free
/// products) of the symmetrised M^-1/2 K_t M^-1/2 from a fixed pseudo-random start, the largest Ritz
/// value (>= the power iteration's Rayleigh quotient after as many products), times `safety` (default
/// 1.05). Deterministic. (The name is historical: it was a power iteration of 30 steps.)
double power_iteration_omega(const Model& model, const MatX3& x, int iterations = 15, double safety = 1.05);

/// Scratch of tangent_omega2 and of the amortised estimate (sized on first use; no allocation afterwards for
/// the same model): the Lanczos vectors, the springs' tangent coefficients, and, for the amortised estimate,
/// the snapshot of the positions it is taken at and the tridiagonal built so far.
struct TangentScratch {
  static constexpr int kMaxProducts = 64;
  VecX q, qprev, y, w, sc, ce, cb;
  MatX3 x;                       // tangent_lanczos_start: the positions of the estimate (#N x 3), mm
  double alpha[kMaxProducts]{};  // the Lanczos tridiagonal's diagonal ...
  double beta[kMaxProducts]{};   // ... and off-diagonal
  int k = 0;                     // products taken
  int iterations = 0;            // products asked for
  double beta_prev = 0.0;
  bool done = true;            // no estimate under way
  std::uint64_t products = 0;  // products taken in all (the amortised refresh's work per frame)
};

/// The same estimate as power_iteration_omega(model, x, iterations, 1.0), squared ((rad/ms)^2), from the
/// same start vector, without allocating once `scratch` is sized: the largest eigenvalue of the Lanczos
/// tridiagonal by bisection (Sturm counts) instead of Eigen's solver, so equal to rounding. iterations <=
/// 64. The stable step's tangent refresh (integrators.cpp) calls it at the current state.
/// Sizes `scratch` for tangent_omega2 on `model` (allocates unless already sized).
void size_tangent_scratch(const Model& model, TangentScratch& scratch);
double tangent_omega2(const Model& model, const MatX3& x, int iterations, TangentScratch& scratch);

/// tangent_omega2 in pieces, so that its products can be spread over frames (the stable step's amortised
/// refresh, docs/volumetric-stable-step.md): start copies x into scratch.x (the snapshot) and takes the
/// springs' coefficients and the start vector (no product); advance takes up to `products` more products at
/// the snapshot and returns true once the estimate is complete; omega2 is then its value. start + advance
/// (iterations) + omega2 is tangent_omega2 bit for bit, however the products are split. No allocation once
/// `scratch` is sized.
void tangent_lanczos_start(const Model& model, const MatX3& x, int iterations, TangentScratch& scratch);
bool tangent_lanczos_advance(const Model& model, int products, TangentScratch& scratch);
double tangent_lanczos_omega2(const TangentScratch& scratch);

/// The run-time stable step: safety * 2 / (omega_rest * sqrt(stiffening)) (ms).
inline double dt_safe(const Model& model, double stiffening, double safety = 0.8) {
  return safety * 2.0 / (model.omega_rest * std::sqrt(stiffening < 1.0 ? 1.0 : stiffening));
}

/// Sub-steps the symplectic step takes for a frame of dt under that step (uncapped; 1 when the frame is
/// stable as it is), as integrators.cpp's step decides them.
inline double stable_substeps(const Model& model, double stiffening, double dt, double safety) {
  const double hs = dt_safe(model, stiffening, safety);
  return dt > hs * (1.0 + 1e-12) ? std::ceil(dt / hs) : 1.0;
}

}  // namespace medspring
