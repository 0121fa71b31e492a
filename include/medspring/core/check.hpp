// Cheap input checks that stay on in release builds. Each throws InvalidInput with a message
// naming what is wrong, e.g. "kidney: springs[12].k: must be >= 0 (got -1)".
#pragma once

#include <cmath>
#include <sstream>
#include <string>
#include <string_view>

#include "medspring/core/error.hpp"
#include "medspring/core/types.hpp"

namespace medspring {

/// Concatenates the arguments with operator<< into one string.
template <class... Args>
std::string cat(const Args&... args) {
  std::ostringstream os;
  os.precision(10);
  (os << ... << args);
  return os.str();
}

/// Throws InvalidInput(cat(args...)) unless cond holds.
template <class... Args>
void require(bool cond, const Args&... args) {
  if (!cond) throw InvalidInput(cat(args...));
}

// The `what` arguments below are concatenated with cat() only when the check fails, so a check in
// a loop over a million elements costs a comparison, not a string.
template <class... What>
void require_finite(double x, const What&... what) {
  if (!std::isfinite(x)) throw InvalidInput(cat(what..., ": must be finite (got ", x, ")"));
}
template <class... What>
void require_positive(double x, const What&... what) {
  if (!(std::isfinite(x) && x > 0)) throw InvalidInput(cat(what..., ": must be > 0 (got ", x, ")"));
}
template <class... What>
void require_nonnegative(double x, const What&... what) {
  if (!(std::isfinite(x) && x >= 0)) throw InvalidInput(cat(what..., ": must be >= 0 (got ", x, ")"));
}
template <class... What>
void require_index(Index i, Index n, const What&... what) {
  if (i < 0 || i >= n) throw InvalidInput(cat(what..., ": index ", i, " out of range [0, ", n, ")"));
}

/// First row of P holding a NaN/Inf, or -1.
inline Index first_nonfinite_row(const MatX3& P) {
  for (Index r = 0; r < P.rows(); ++r)
    if (!P.row(r).allFinite()) return r;
  return -1;
}
template <class... What>
void require_finite_points(const MatX3& P, const What&... what) {
  const Index r = first_nonfinite_row(P);
  if (r >= 0)
    throw InvalidInput(cat(what..., "[", r, "]: coordinates must be finite (got ", P(r, 0), ", ", P(r, 1),
                           ", ", P(r, 2), ")"));
}

}  // namespace medspring
