// The per-tetrahedron kernel of the fused force pass (issue 23, docs/volumetric-speed.md): the volume
// term of one tetrahedron and the springs it owns (0, 1 or 2), evaluated from its four corners loaded once
// and scattered once. Shared by add_volume_forces (volume_terms.cpp, no springs) and the force pass of
// models with volume terms (forces.cpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "medspring/physics/compression_terms.hpp"
#include "medspring/physics/kernels.hpp"
#include "medspring/physics/volume_terms.hpp"

namespace medspring::detail {

/// Raw spring parameters, indexed by spring.
struct SpringParams {
  const double* L0;
  const double* K;
  const double* KP;
  const double* IK;
};

inline void cross3(const double* u, const double* v, double* w) {
  w[0] = u[1] * v[2] - u[2] * v[1];
  w[1] = u[2] * v[0] - u[0] * v[2];
  w[2] = u[0] * v[1] - u[1] * v[0];
}

/// The four corners of record r: P[k] = the three coordinates of node r.n[k] in x (3 doubles a node).
/// Loads only (tet_record, fused_compression_blocks).
[[gnu::always_inline]] inline void load_corners(const VolumeTerms::Packed& r, const double* x,
                                                double (&P)[4][3]) {
  for (int k = 0; k < 4; ++k) {
    const double* p = x + 3 * static_cast<std::ptrdiff_t>(r.n[k]);
    P[k][0] = p[0];
    P[k][1] = p[1];
    P[k][2] = p[2];
  }
}

/// The squared length of the longest of a tetrahedron's six edges, from the three edge vectors from
/// corner 0 (e[k] = P[k+1] minus P[0]; the other three edges are e[j] minus e[k]).
[[gnu::always_inline]] inline double max_edge2(const double (&e)[3][3]) {
  double l2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double a = e[k][0] * e[k][0] + e[k][1] * e[k][1] + e[k][2] * e[k][2];
    l2 = a > l2 ? a : l2;
    const int j = (k + 1) % 3;
    double q = 0;
    for (int d = 0; d < 3; ++d) q += (e[j][d] - e[k][d]) * (e[j][d] - e[k][d]);
    l2 = q > l2 ? q : l2;
  }
  return l2;
}

/// min and max that stay branch-free: GCC turned the selects of the compression scalar into a branch on
/// J < 1 (about 60 % of the kidney's tetrahedra are compressed: mispredicted) with the division in one arm.
[[gnu::always_inline]] inline double min_nb(double a, double b) {
#if defined(__SSE2__)
  return _mm_cvtsd_f64(_mm_min_sd(_mm_set_sd(a), _mm_set_sd(b)));
#else
  return a < b ? a : b;
#endif
}
[[gnu::always_inline]] inline double max_nb(double a, double b) {
#if defined(__SSE2__)
  return _mm_cvtsd_f64(_mm_max_sd(_mm_set_sd(a), _mm_set_sd(b)));
#else
  return a > b ? a : b;
#endif
}

/// h'(J) of the fused compression term (compression_h) at J = 1 + dv6 / V06, without branches, with one
/// division and without the cancellation of 1 - 1/J - (J - 1): with d = dv6 clamped to [(J_min - 1) V06, 0]
/// (J clamped to [J_min, 1]) and W = V06 + d (= V06 J there), h' = -(J - 1)^2 / J = -d^2 / (V06 W) on
/// [J_min, 1), 0 from J = 1 on, and below J_min the continuation h'(J_min) + h''(J_min) (J - J_min), the
/// last factor min(dv6 - (J_min - 1) V06, 0) / V06. `r` = 1 / (V06 W) is kept for h'' (compression_trace).
struct CompDh {
  double d1, r, W;
};
[[gnu::always_inline]] inline CompDh compression_dh6(double dv6, double V06) {
  constexpr double jm = kCompressionJMin, d2m = 1.0 / (jm * jm) - 1.0;  // h''(J_min)
  const double lo = (jm - 1.0) * V06;
  const double d = max_nb(min_nb(dv6, 0.0), lo);
  const double bl = min_nb(dv6 - lo, 0.0);  // V06 (J - J_min) below J_min, else 0
  const double W = V06 + d;
  const double r = 1.0 / (V06 * W);
  return {r * (d2m * bl * W - d * d), r, W};
}

/// Output of the fused compression bound's traces (tet_record with Trace): per node s_i = m_i^-1/2 (0 on a
/// fixed node) and the rows tr B_i the corners' shares are added to.
struct CompTrace {
  const double* s;
  double* rows;
};

/// The fused compression bound's traces: the share of each corner k of a compressed term in the trace of its
/// node's 3x3 block B_i of the block bound (compression_terms.cpp, block_term), tr = a sigma s_k |g_k| + 3 hb
/// s_k (S - s_k) with a = kc h''(J) / V0, hb = |kc h'(J)| L_max / 6, g_k = dV/dx_k, sigma = sum_l s_l |g_l|
/// and S = sum_l s_l; 0 where J >= 1 (h' = h'' = 0 there). c: 6 dV/dx of corners b, c, d; l2: the longest
/// edge squared; h: compression_dh6. h'' = 1 / J^2 - 1 on [J_min, 1) and h''(J_min) below, i.e. 1 / J_c^2 - 1
/// with J clamped to [J_min, 1], 1 / J_c = V06 / W = V06^2 r.
[[gnu::always_inline]] inline void compression_trace(const std::int32_t n[4], const double c[3][3],
                                                     const CompDh& h, double V06, double kc6, double l2,
                                                     const CompTrace& out) {
  const double iJ = V06 * V06 * h.r;
  const double d2 = max_nb(iJ * iJ - 1.0, 0.0);            // h''(J) >= 0, 0 from J = 1 on (not -1 ulp)
  const double a = 36.0 * kc6 * (h.W * h.r) * d2;          // kc h'' / V0 (1 / V06 = W r)
  const double hb = std::abs(kc6 * h.d1) * std::sqrt(l2);  // |kc h'| L_max / 6
  double gn[4];                                            // |dV/dx_k|
  for (int k = 0; k < 3; ++k)
    gn[k + 1] = std::sqrt(c[k][0] * c[k][0] + c[k][1] * c[k][1] + c[k][2] * c[k][2]);
  {
    const double c0[3] = {c[0][0] + c[1][0] + c[2][0], c[0][1] + c[1][1] + c[2][1],
                          c[0][2] + c[1][2] + c[2][2]};
    gn[0] = std::sqrt(c0[0] * c0[0] + c0[1] * c0[1] + c0[2] * c0[2]);
  }
  double sk[4], S = 0.0, sigma = 0.0;
  for (int k = 0; k < 4; ++k) {
    gn[k] *= 1.0 / 6.0;
    sk[k] = out.s[n[k]];
    S += sk[k];
    sigma += sk[k] * gn[k];
  }
  const double as = a * sigma, h3 = 3.0 * hb;
  for (int k = 0; k < 4; ++k) out.rows[n[k]] += sk[k] * (as * gn[k] + h3 * (S - sk[k]));
}

/// The fused compression term's share of the force scalar s of tet_record (f_k = s (6 dV/dx_k)):
/// -kc h'(J) / 6 with J = 1 + dv6 / V06 (compression_dh6). Only its forces: h (a logarithm) is not needed.
[[gnu::always_inline]] inline double compression_scalar(const CompDh& h, double kc6) {
  return -kc6 * h.d1;
}

/// Adds the forces of record r (its volume term and its first Own owned springs) to f (flat 3N). With
/// Stiff: sv = max(sv, the term's curvature bound |dV/dx|^2 + |V - V0| L_max / 2 over its rest value;
/// ||d^2V|| <= L_max / 2: each corner row of d^2V has three 3x3 blocks [x_m - x_n]x / 6)
/// and ss = max(ss, kappa/k of its springs), as the separate passes compute them. With Local (and Stiff):
/// also *inc = (s_t - 1)+, the term's stiffening increment (the local stiffening of the stable step,
/// scattered to the nodes afterwards by volume_row_max: a scatter here would chain the next terms' row
/// updates to this term's square root through memory).
/// With Comp: also the fused compression term's force (r.kc6, fuse_compression_terms), -kc h'(J) dV/dx, along
/// the same dV/dx: its scalar joins the volume term's (no second gradient, no second scatter). Its curvature
/// bound is not part of sv (add_compression_forces computes it).
/// With Trace (and Stiff, Comp): also the compression term's shares in the traces of its bound's blocks
/// (compression_trace), added to tr->rows.
template <int Own, bool Soft, bool Stiff, bool Local = false, bool Comp = false, bool Trace = false>
[[gnu::always_inline]] inline void tet_record(const VolumeTerms::Packed& r, const SpringParams& S,
                                              const double* x, double* f, double& ss, double& sv,
                                              double* inc = nullptr, const CompTrace* tr = nullptr) {
  double P[4][3];
  load_corners(r, x, P);
  double e[3][3];
  for (int k = 0; k < 3; ++k)
    for (int d = 0; d < 3; ++d) e[k][d] = P[k + 1][d] - P[0][d];
  double c[3][3];  // 6 dV/dx of corners b, c, d: e2 x e3, e3 x e1, e1 x e2
  cross3(e[1], e[2], c[0]);
  cross3(e[2], e[0], c[1]);
  cross3(e[0], e[1], c[2]);
  const double dv6 = e[0][0] * c[0][0] + e[0][1] * c[0][1] + e[0][2] * c[0][2] - r.V06;  // 6 (V - V0)
  double s = -r.alpha * dv6;
  CompDh ch{};
  if constexpr (Comp) {
    ch = compression_dh6(dv6, r.V06);
    s += compression_scalar(ch, r.kc6);
  }
  double F[4][3];
  for (int d = 0; d < 3; ++d) {
    F[1][d] = s * c[0][d];
    F[2][d] = s * c[1][d];
    F[3][d] = s * c[2][d];
    F[0][d] = -(F[1][d] + F[2][d] + F[3][d]);
  }
  if constexpr (Stiff) {
    double gg = 0;
    for (int d = 0; d < 3; ++d) {
      const double c0 = c[0][d] + c[1][d] + c[2][d];
      gg += c[0][d] * c[0][d] + c[1][d] * c[1][d] + c[2][d] * c[2][d] + c0 * c0;
    }
    const double l2 = max_edge2(e);
    const double cur = gg * (1.0 / 36.0) + std::abs(dv6) * std::sqrt(l2) * (1.0 / 12.0);  // |V - V0| L / 2
    if constexpr (Trace) compression_trace(r.n, c, ch, r.V06, r.kc6, l2, *tr);
    if constexpr (Local) {  // branch-free: about half the terms stiffen, a branch would be unpredictable
      const double st = cur * r.iG0 - 1.0;
      *inc = st > 0.0 ? st : 0.0;
    }
    // a branch, not a max: rarely taken, so no iteration waits on the previous one's square root
    if (cur * r.iG0 > sv) [[unlikely]]
      sv = cur * r.iG0;
  }
  // Owned springs, without indexing the corner arrays by a run-time corner (that would keep them in
  // memory): weights w_k = [k == p] - [k == q] select the spring's ends, so that e = x_q - x_p exactly
  // (the other terms add zeros) and the corners get +f at p and -f at q.
#pragma GCC unroll 2
  for (int o = 0; o < Own; ++o) {
    const int p = r.pq[o] >> 2, q = r.pq[o] & 3;
    const std::ptrdiff_t sp = r.s[o];
    double w[4];
    for (int k = 0; k < 4; ++k) w[k] = static_cast<double>(k == p) - static_cast<double>(k == q);
    double ev[3];
    for (int d = 0; d < 3; ++d) ev[d] = -w[0] * P[0][d] - w[1] * P[1][d] - w[2] * P[2][d] - w[3] * P[3][d];
    double fo[3];
    if (!hd::spring_force<Soft, Stiff>(ev[0], ev[1], ev[2], S.L0[sp], S.K[sp], S.KP[sp], S.IK[sp], ss, fo[0],
                                       fo[1], fo[2]))
      continue;
    for (int k = 0; k < 4; ++k)
      for (int d = 0; d < 3; ++d) F[k][d] += w[k] * fo[d];
  }
  for (int k = 0; k < 4; ++k) {
    double* o = f + 3 * static_cast<std::ptrdiff_t>(r.n[k]);
    o[0] += F[k][0];
    o[1] += F[k][1];
    o[2] += F[k][2];
  }
}

}  // namespace medspring::detail
