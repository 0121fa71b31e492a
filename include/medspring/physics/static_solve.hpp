// Static equilibrium (ALGORITHMS.md §2.4): Newton–Raphson with backtracking line search.
#pragma once

#include "medspring/physics/model.hpp"

namespace medspring {

struct StaticSettings {
  double tolerance = 1e-10;  // max per-node residual norm (N)
  int max_iterations = 200;
  int max_backtracks = 40;
  // Modified Newton: keep the factorised tangent while each step cuts the max residual by at least
  // reuse_rate, refactor otherwise (a large model, e.g. the volumetric kind, spends its time factoring).
  // Same equilibrium to the tolerance, fewer factorisations, more (cheap) iterations.
  bool reuse_tangent = false;
  double reuse_rate = 0.25;
};

struct StaticResult {
  MatX3 x;  // equilibrium positions (#N x 3), mm
  int iterations = 0;
  double residual = 0;  // final max per-node residual (N)
};

/// Solves f_ext + f_int(x) = 0 for the free nodes, starting from x_start (x0 if empty). Throws
/// SolverError if no equilibrium is found (e.g. a soft spring loaded above its peak force).
StaticResult static_equilibrium(const Model& model, const MatX3& f_ext, const StaticSettings& s = {},
                                const MatX3& x_start = MatX3());

}  // namespace medspring
