#include "medspring/physics/loads.hpp"

#include <algorithm>
#include <cmath>

#include "medspring/core/check.hpp"
#include "medspring/physics/kernels.hpp"

namespace medspring {

double PointLoad::scale(double t) const {
  return hd::load_scale(t, t_on, t_ramp, t_release, ramp_down);
}

void validate_loads(const std::vector<PointLoad>& loads, Index n) {
  for (std::size_t k = 0; k < loads.size(); ++k) {
    const PointLoad& L = loads[k];
    const std::string p = cat("loads[", k, "]");
    require_index(L.node, n, p, ".node");
    require(L.force.allFinite(), p, ".force: must be finite");
    require_finite(L.t_on, p, ".t_on");
    require_nonnegative(L.t_ramp, p, ".t_ramp");
    require(!std::isnan(L.t_release), p, ".t_release: must not be NaN");
    require(L.t_release >= L.t_on, p, ".t_release: must be >= t_on (", L.t_release, " < ", L.t_on, ")");
  }
}

void accumulate_loads(const std::vector<PointLoad>& loads, double t, MatX3& f_ext) {
  f_ext.setZero();
  for (const PointLoad& L : loads) {
    const double s = L.scale(t);
    if (s != 0.0) f_ext.row(L.node) += s * L.force.transpose();
  }
}

Index nearest_node(const MatX3& X, const Vec3& p) {
  require(X.rows() > 0, "nearest_node: no nodes");
  Index best = 0;
  double bd = (X.row(0).transpose() - p).squaredNorm();
  for (Index a = 1; a < X.rows(); ++a) {
    const double d = (X.row(a).transpose() - p).squaredNorm();
    if (d < bd) {
      bd = d;
      best = a;
    }
  }
  return best;
}

}  // namespace medspring
