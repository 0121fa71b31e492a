// Centerlines: polylines with a radius per point.
#pragma once

#include <string>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

/// One centerline polyline in mm with the lumen (inscribed) radius at every point.
struct Centerline {
  MatX3 points;  // #P x 3, mm
  VecX radii;    // #P, mm (> 0)
  std::string name;

  Index size() const { return static_cast<Index>(points.rows()); }
  /// Cumulative arc length at every point (first = 0), mm.
  VecX arc_length() const;
  double length() const;
};

/// Removes consecutive points closer than tol (mm), keeping the first of each run; the radius of a
/// removed point is dropped.
Centerline deduplicate(const Centerline& line, double tol);

/// Resamples to `count` points at equal arc-length spacing (including both ends), interpolating
/// positions and radii linearly. Throws InvalidInput for count < 2 or a zero-length line.
Centerline resample(const Centerline& line, Index count);

}  // namespace medspring
