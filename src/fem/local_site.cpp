#include "medspring/fem/local_site.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/local/distributed.hpp"

namespace medspring::fem {

MatX3 disk_local_overlay(const Body& body, const ContactLoad& load, double k_loc, int rings) {
  require_positive(k_loc, "local overlay (disk load): k_loc");
  const MatX3& S = body.rest_surface();
  const MatX3 f = disk_load_linear(S, body.faces(), load.centre, load.radius, load.force);
  std::vector<Index> loaded;
  Index contact = -1;
  for (Index i = 0; i < f.rows(); ++i)
    if (f.row(i).squaredNorm() > 0) {
      loaded.push_back(i);
      if (contact < 0 || f.row(i).squaredNorm() > f.row(contact).squaredNorm()) contact = i;
    }
  require(!loaded.empty(), "local overlay (disk load): the disk at (", load.centre(0), ", ", load.centre(1),
          ", ", load.centre(2), ") mm, radius ", load.radius, " mm, loads no surface node");
  const LocalPatch patch =
      loaded_nodes_patch(vertex_adjacency(body.num_surface_nodes(), unique_edges(body.faces())), loaded,
                         contact, k_loc, body.fixed_surface_nodes(), rings);
  MatX3 Fp(patch.size(), 3);
  for (Index a = 0; a < patch.size(); ++a) Fp.row(a) = f.row(patch.nodes[a]);
  MatX3 U;
  solve_local_distributed(patch, Fp, U);
  MatX3 out = MatX3::Zero(S.rows(), 3);
  for (Index a = 0; a < patch.size(); ++a) out.row(patch.nodes[a]) = U.row(a);
  return out;
}

OverlayCoefficients fit_overlay_coefficients(const std::vector<MatX3>& u, const std::vector<MatX3>& v,
                                             const std::vector<CalibrationCase>& training, bool fit_scale) {
  require(!training.empty() && u.size() == training.size() && v.size() == training.size(),
          "calibrate (overlay): ", u.size(), " responses and ", v.size(), " overlays for ", training.size(),
          " training loads");
  // the cost is quadratic in (alpha, a): sums of the weighted products of u, v and the FEM, both terms
  double uu = 0, uv = 0, vv = 0, uU = 0, vU = 0, UU = 0;
  for (std::size_t i = 0; i < training.size(); ++i) {
    const auto& t = training[i];
    const Eigen::Index n = t.u_fem.rows();
    require(u[i].rows() >= n && v[i].rows() == u[i].rows(), "calibrate (overlay): load ", i,
            ": response has ", u[i].rows(), " rows, overlay ", v[i].rows(), ", the FEM ", n);
    const double s = std::max(t.u_fem.rowwise().norm().maxCoeff(), 1e-12);
    const double wn = 1.0 / (s * s * static_cast<double>(n)), wc = t.site_weight / (s * s);
    const auto ut = u[i].topRows(n), vt = v[i].topRows(n);
    const Vec3 su = site_readout(t, u[i]), sv = site_readout(t, v[i]), sU = fem_site_readout(t);
    uu += wn * ut.squaredNorm() + wc * su.squaredNorm();
    vv += wn * vt.squaredNorm() + wc * sv.squaredNorm();
    uv += wn * (ut.array() * vt.array()).sum() + wc * su.dot(sv);
    uU += wn * (ut.array() * t.u_fem.array()).sum() + wc * su.dot(sU);
    vU += wn * (vt.array() * t.u_fem.array()).sum() + wc * sv.dot(sU);
    UU += wn * t.u_fem.squaredNorm() + wc * sU.squaredNorm();
  }
  OverlayCoefficients c;
  if (!fit_scale) {
    c.a = vv > 0 ? std::max(0.0, (vU - uv) / vv) : 0.0;
  } else {
    const double det = uu * vv - uv * uv;
    if (det > 1e-14 * uu * vv) {
      c.alpha = (uU * vv - vU * uv) / det;
      c.a = (vU * uu - uU * uv) / det;
    }
    if (!(det > 1e-14 * uu * vv) || c.a < 0) {  // the constraint a >= 0 active: the scale alone
      c.a = 0;
      c.alpha = uu > 0 ? uU / uu : 1.0;
    }
  }
  const double al = c.alpha, a = c.a;
  c.cost = std::max(0.0, al * al * uu + a * a * vv + UU + 2 * al * a * uv - 2 * al * uU - 2 * a * vU);
  return c;
}

OverlayFit calibrate_volumetric_overlay(const BatchResponse& small_strain, const Response* full,
                                        const std::function<MatX3(const ContactLoad&)>& overlay,
                                        const std::vector<CalibrationCase>& training, int evaluations) {
  require(!training.empty() && evaluations >= 3,
          "calibrate (overlay): need >= 1 training load and >= 3 evaluations");
  std::vector<ContactLoad> loads;
  std::vector<MatX3> v;
  for (const auto& t : training) {
    loads.push_back(t.load);
    v.push_back(overlay(t.load));
  }
  double best_cost = std::numeric_limits<double>::infinity(), best_logr = 0;
  OverlayCoefficients best;
  auto cost = [&](double logr) {
    VecX m(2);
    m << 1.0, std::exp(logr);
    std::vector<MatX3> us;
    try {
      us = small_strain(m, loads);
    } catch (const SolverError&) {
      return std::numeric_limits<double>::infinity();
    }
    const OverlayCoefficients c = fit_overlay_coefficients(us, v, training, true);
    if (!(c.alpha > 0)) return std::numeric_limits<double>::infinity();
    if (c.cost < best_cost) best_cost = c.cost, best_logr = logr, best = c;
    return c.cost;
  };
  // golden section over log r, as calibrate_scale_and_ratio
  const double g = (std::sqrt(5.0) - 1) / 2;
  double lo = std::log(1e-2), hi = std::log(1e2);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = cost(x1), f2 = cost(x2);
  for (int it = 0; it < evaluations - 2; ++it)
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = cost(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = cost(x2);
    }
  if (!std::isfinite(best_cost))
    throw SolverError("calibrate (overlay): no ratio in [1e-2, 1e2] has a response");
  OverlayFit out;
  out.m = VecX(4);
  out.m << 1 / best.alpha, std::exp(best_logr) / best.alpha, 1.0, best.a;
  out.m_small_strain = out.m.head(2);
  out.a_small_strain = best.a;
  out.small_strain_cost = out.cost = best_cost;
  if (!full) return out;
  const double a0 = best.a;
  const Response with_overlay = [&](const VecX& m3, const ContactLoad& l) {
    return MatX3((*full)(m3, l) + a0 * overlay(l));
  };
  const VolumetricFit vf = calibrate_volumetric_nonlinear(with_overlay, out.m.head(2), training);
  std::vector<MatX3> u;
  for (const auto& l : loads) u.push_back((*full)(vf.m, l));
  const OverlayCoefficients c = fit_overlay_coefficients(u, v, training, false);
  out.m << vf.m(0), vf.m(1), vf.m(2), c.a;
  out.cost = c.cost;
  out.evaluations = vf.refine.evaluations + 1;
  return out;
}

}  // namespace medspring::fem
