// The polyline stage of the centerline (centerline_stages.hpp): arc length, sub-curves, uniform
// resampling and Gaussian smoothing in local physical coordinates (mm).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "centerline_stages.hpp"

namespace medspring::skeleton_detail {

std::vector<double> cumulative_length(const Curve& P) {
  std::vector<double> S(P.size(), 0.0);
  for (std::size_t i = 1; i < P.size(); ++i) S[i] = S[i - 1] + (P[i] - P[i - 1]).norm();
  return S;
}

/// Point at arc length s (clamped); `seg` is a monotone search hint.
Vec3 point_at(const Curve& P, const std::vector<double>& S, double s, std::size_t& seg) {
  const std::size_t n = P.size();
  if (s <= S.front()) return P.front();
  if (s >= S.back()) return P.back();
  while (seg + 2 < n && S[seg + 1] < s) ++seg;
  while (seg > 0 && S[seg] > s) --seg;
  const double len = S[seg + 1] - S[seg];
  const double t = len > 0 ? std::clamp((s - S[seg]) / len, 0.0, 1.0) : 0.0;
  return (1.0 - t) * P[seg] + t * P[seg + 1];
}

/// The part of P between arc lengths a < b.
Curve sub_curve(const Curve& P, const std::vector<double>& S, double a, double b) {
  Curve out;
  std::size_t seg = 0;
  out.push_back(point_at(P, S, a, seg));
  const double tol = 1e-12 * std::max(1.0, S.back());
  for (std::size_t i = 0; i < P.size(); ++i)
    if (S[i] > a + tol && S[i] < b - tol) out.push_back(P[i]);
  out.push_back(point_at(P, S, b, seg));
  return out;
}

/// §3.5.1: uniform arc-length resampling with step L / ceil(L / delta) <= delta.
Curve resample_uniform(const Curve& P, double delta, double& step) {
  const std::vector<double> S = cumulative_length(P);
  const double L = S.back();
  const Index m = std::max<Index>(1, static_cast<Index>(std::ceil(L / delta - 1e-9)));
  step = L / static_cast<double>(m);
  Curve out(static_cast<std::size_t>(m) + 1);
  std::size_t seg = 0;
  for (Index i = 0; i < m; ++i) out[i] = point_at(P, S, step * static_cast<double>(i), seg);
  out[m] = P.back();
  return out;
}

/// §3.5.2: Gaussian smoothing along arc length (uniform samples, spacing `step`), endpoints fixed,
/// sigma_eff(s) = min(sigma, s_end/3) so the 3-sigma window stays symmetric and inside the curve.
Curve smooth_gaussian(const Curve& P, double step, double sigma) {
  const Index m = static_cast<Index>(P.size()) - 1;
  Curve out(P.size());
  for (Index i = 0; i <= m; ++i) {
    const Index to_end = std::min(i, m - i);
    const double sig = std::min(sigma, static_cast<double>(to_end) * step / 3.0);
    Index K = sig > 0 ? static_cast<Index>(std::floor(3.0 * sig / step + 1e-9)) : 0;
    K = std::min(K, to_end);
    if (K == 0) {
      out[i] = P[i];
      continue;
    }
    Vec3 acc = Vec3::Zero();
    double wsum = 0.0;
    for (Index j = -K; j <= K; ++j) {
      const double x = static_cast<double>(j) * step;
      const double w = std::exp(-x * x / (2.0 * sig * sig));
      acc += w * P[i + j];
      wsum += w;
    }
    out[i] = acc / wsum;
  }
  return out;
}

}  // namespace medspring::skeleton_detail
