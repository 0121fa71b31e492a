// External point forces with ramp / hold / release profiles (ALGORITHMS.md §1.6).
#pragma once

#include <limits>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

/// A point force on one node: F(t) = scale(t) * force.
struct PointLoad {
  Index node = 0;             // node index in the model's DOFs (or surface, for mapped models)
  Vec3 force = Vec3::Zero();  // full force vector (N)
  double t_on = 0.0;          // ms: the ramp starts here
  double t_ramp = 20.0;       // ms: linear ramp duration (0 = step)
  double t_release = std::numeric_limits<double>::infinity();  // ms: release time
  bool ramp_down = false;  // release over t_ramp instead of instantly (paper: instantly)

  /// Profile factor in [0, 1] at time t.
  double scale(double t) const;
  Vec3 at(double t) const { return scale(t) * force; }
};

/// Validates loads against a model of n nodes; throws InvalidInput naming "loads[k].field".
void validate_loads(const std::vector<PointLoad>& loads, Index n);

/// f_ext = sum of the loads at time t (f_ext is zeroed first; its size must be n x 3).
void accumulate_loads(const std::vector<PointLoad>& loads, double t, MatX3& f_ext);

/// Index of the point of X nearest to p (ties: lowest index).
Index nearest_node(const MatX3& X, const Vec3& p);

}  // namespace medspring
