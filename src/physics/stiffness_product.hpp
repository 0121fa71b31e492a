// The tangent stiffness times a vector, K p, matrix-free: written once for the implicit integrator's CG
// (integrators.cpp, y = K p) and the stable-step estimate's Lanczos (stability.cpp, y = S K S p with
// S = M^-1/2). Private to the physics layer.
//
//   stiffness_product<false>(m, x, nullptr, p, y, nullptr, true, [&](Index s, const Vec3& d) { return K_s d;
//   });
//
// K = diag(k_r) + sum over springs of K_s (the caller's per-spring 3x3 action on d = p_i - p_j, so each
// caller keeps its own coefficients: stored unit directions, or directions recomputed from x) + the bending
// terms k_b w w^T (w = (1, -2, 1)) + the volume terms at x (Gauss-Newton part only when `gauss_newton`).
#pragma once

#include "medspring/physics/compression_terms.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/physics/volume_terms.hpp"

namespace medspring::detail {

/// y = S K S p, S = diag(scale[node]) when Scaled (else the identity). `w` is scratch for S p when Scaled
/// (resized only when bending or volume terms need it; unused, may be null, otherwise). spring(s, d)
/// returns K_s d for spring s.
template <bool Scaled, class SpringAction>
void stiffness_product(const Model& m, const MatX3& x, const double* scale, const VecX& p, VecX& y, VecX* w,
                       bool gauss_newton, SpringAction&& spring) {
  const Index n = m.num_nodes();
  const double* P = p.data();
  double* Y = y.data();
  for (Index a = 0; a < n; ++a)
    for (int c = 0; c < 3; ++c) Y[3 * a + c] = m.kr[a] * (Scaled ? scale[a] * P[3 * a + c] : P[3 * a + c]);
  const Springs& S = m.springs;
  const Index* SI = S.i.data();
  const Index* SJ = S.j.data();
  for (Index q = 0; q < S.size(); ++q) {
    const Index i = 3 * SI[q], j = 3 * SJ[q];
    Vec3 d;
    if constexpr (Scaled) {
      const double si = scale[SI[q]], sj = scale[SJ[q]];
      d = Vec3(si * P[i] - sj * P[j], si * P[i + 1] - sj * P[j + 1], si * P[i + 2] - sj * P[j + 2]);
    } else {
      d = Vec3(P[i] - P[j], P[i + 1] - P[j + 1], P[i + 2] - P[j + 2]);
    }
    const Vec3 k = spring(q, d);
    Y[i] += k.x();
    Y[i + 1] += k.y();
    Y[i + 2] += k.z();
    Y[j] -= k.x();
    Y[j + 1] -= k.y();
    Y[j + 2] -= k.z();
  }
  const BendingTerms& B = m.bending;
  if (B.size() > 0 || m.volume.size() > 0 || m.compression.size() > 0 || m.thin.size() > 0) {
    const VecX* sp = &p;  // S p
    if constexpr (Scaled) {
      w->resize(3 * n);
      for (Index a = 0; a < n; ++a) w->segment<3>(3 * a) = scale[a] * p.segment<3>(3 * a);
      sp = w;
    }
    for (Index t = 0; t < B.size(); ++t) {
      const Vec3 g = B.kb[t] * (sp->segment<3>(3 * B.a[t]) - 2.0 * sp->segment<3>(3 * B.b[t]) +
                                sp->segment<3>(3 * B.c[t]));
      y.segment<3>(3 * B.a[t]) += g;
      y.segment<3>(3 * B.b[t]) -= 2.0 * g;
      y.segment<3>(3 * B.c[t]) += g;
    }
    if (m.volume.size() > 0) add_volume_stiffness_product(m.volume, x, *sp, y, gauss_newton);
    if (m.compression.size() > 0) add_compression_stiffness_product(m.compression, x, *sp, y, gauss_newton);
    if (m.thin.size() > 0) add_thin_tet_stiffness_product(m.thin, x, *sp, y);  // co-rotated, PSD
  }
  if constexpr (Scaled)
    for (Index a = 0; a < n; ++a)
      for (int c = 0; c < 3; ++c) Y[3 * a + c] *= scale[a];
}

}  // namespace medspring::detail
