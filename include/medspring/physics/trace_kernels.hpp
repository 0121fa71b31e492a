// The per-frame trace values of a scene run, written once for the CPU and the GPU's device-side
// reduction (src/gpu/sample.cu, docs/gpu.md "Study runs on the GPU"): per model the largest displacement
// |x - rest| over its surface nodes and the displacement of each traced point (the load nodes, the
// recorded nodes and atoms of scene_trace_sample). MEDSPRING_HD (`__host__ __device__` under nvcc), no
// Eigen; positions in the GPU engine's layout (model b's n x 3 row-major reals, stored relative to its
// origin: x = x_stored + origin, in double, as gpu::Engine::positions gives them).
#pragma once

#include <math.h>

#include "medspring/core/hd.hpp"

namespace medspring::hd {

/// What is sampled, for a batch of models whose surfaces have the same number of nodes. Model b's arrays
/// start at pointer + b * stride (stride 0: shared by the batch).
struct TraceTable {
  int batch = 0;
  int surface = 0;                       // surface nodes per model
  const int* surface_dof = nullptr;      // the DOF row of each surface node
  const double* surface_rest = nullptr;  // their rest positions (surface x 3)
  long long dof_stride = 0, rest_stride = 0;
  int points = 0;                      // traced points per model (padded: dof -1)
  const int* point_dof = nullptr;      // batch x points
  const double* point_rest = nullptr;  // batch x points x 3
  /// Values per model: [max |u| over the surface, |u| of point 0, 1, ...].
  MEDSPRING_HD int width() const { return 1 + points; }
};

/// Largest of two displacements; a NaN wins (so a NaN anywhere on the surface is the result, in any
/// order of reduction).
MEDSPRING_HD inline double trace_max(double a, double b) {
  return (b > a || b != b) ? b : a;
}

/// |x[dof] + origin - rest|, in double (the host's arithmetic on gpu::Engine::positions' values).
template <class R>
MEDSPRING_HD inline double point_displacement(const R* x, const double* origin, int dof, const double* rest) {
  const R* p = x + 3 * static_cast<long long>(dof);
  const double dx = (static_cast<double>(p[0]) + origin[0]) - rest[0];
  const double dy = (static_cast<double>(p[1]) + origin[1]) - rest[1];
  const double dz = (static_cast<double>(p[2]) + origin[2]) - rest[2];
  return ::sqrt(dx * dx + dy * dy + dz * dz);
}

/// Surface node s of model b (x: model b's positions).
template <class R>
MEDSPRING_HD inline double surface_displacement(const TraceTable& T, int b, const R* x, const double* origin,
                                                int s) {
  return point_displacement(x, origin, T.surface_dof[T.dof_stride * b + s],
                            T.surface_rest + T.rest_stride * b + 3 * static_cast<long long>(s));
}

/// Traced point p of model b (0 for padding).
template <class R>
MEDSPRING_HD inline double traced_displacement(const TraceTable& T, int b, const R* x, const double* origin,
                                               int p) {
  const long long q = static_cast<long long>(b) * T.points + p;
  const int dof = T.point_dof[q];
  return dof < 0 ? 0.0 : point_displacement(x, origin, dof, T.point_rest + 3 * q);
}

/// Model b's values (T.width() of them) into out, one node after the other: what the device computes with
/// a block per model (the max is exact, so the order of reduction does not change it).
template <class R>
MEDSPRING_HD inline void trace_sample(const TraceTable& T, int b, const R* x, const double* origin,
                                      double* out) {
  double m = 0.0;
  for (int s = 0; s < T.surface; ++s) m = trace_max(m, surface_displacement(T, b, x, origin, s));
  out[0] = m;
  for (int p = 0; p < T.points; ++p) out[1 + p] = traced_displacement(T, b, x, origin, p);
}

}  // namespace medspring::hd
