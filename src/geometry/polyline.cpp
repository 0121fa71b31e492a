#include "medspring/geometry/polyline.hpp"

#include <algorithm>

#include "medspring/core/check.hpp"

namespace medspring {

VecX Centerline::arc_length() const {
  VecX s(points.rows());
  if (points.rows() == 0) return s;
  s[0] = 0;
  for (Index i = 1; i < points.rows(); ++i) s[i] = s[i - 1] + (points.row(i) - points.row(i - 1)).norm();
  return s;
}

double Centerline::length() const {
  const VecX s = arc_length();
  return s.size() ? s[s.size() - 1] : 0.0;
}

Centerline deduplicate(const Centerline& line, double tol) {
  require(line.radii.size() == line.points.rows(), "centerline '", line.name, "': ", line.points.rows(),
          " points but ", line.radii.size(), " radii");
  std::vector<Index> keep;
  for (Index i = 0; i < line.size(); ++i)
    if (keep.empty() || (line.points.row(i) - line.points.row(keep.back())).norm() > tol) keep.push_back(i);
  Centerline out;
  out.name = line.name;
  out.points.resize(static_cast<Index>(keep.size()), 3);
  out.radii.resize(static_cast<Index>(keep.size()));
  for (std::size_t k = 0; k < keep.size(); ++k) {
    out.points.row(static_cast<Index>(k)) = line.points.row(keep[k]);
    out.radii[static_cast<Index>(k)] = line.radii[keep[k]];
  }
  return out;
}

Centerline resample(const Centerline& line, Index count) {
  require(count >= 2, "resample: count must be >= 2 (got ", count, ")");
  require(line.size() >= 2, "centerline '", line.name, "': needs at least 2 points (got ", line.size(), ")");
  require(line.radii.size() == line.points.rows(), "centerline '", line.name, "': ", line.points.rows(),
          " points but ", line.radii.size(), " radii");
  const VecX s = line.arc_length();
  const double L = s[s.size() - 1];
  require(L > 0, "centerline '", line.name, "': has zero length");
  Centerline out;
  out.name = line.name;
  out.points.resize(count, 3);
  out.radii.resize(count);
  Index seg = 0;
  for (Index k = 0; k < count; ++k) {
    const double target = L * static_cast<double>(k) / static_cast<double>(count - 1);
    while (seg + 2 < line.size() && s[seg + 1] < target) ++seg;
    const double len = s[seg + 1] - s[seg];
    const double lam = len > 0 ? std::clamp((target - s[seg]) / len, 0.0, 1.0) : 0.0;
    out.points.row(k) = (1 - lam) * line.points.row(seg) + lam * line.points.row(seg + 1);
    out.radii[k] = (1 - lam) * line.radii[seg] + lam * line.radii[seg + 1];
  }
  return out;
}

}  // namespace medspring
