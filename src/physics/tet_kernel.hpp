// The per-tetrahedron kernel of the fused force pass (issue 23, docs/volumetric.md "Speed"): the volume
// term of one tetrahedron and the springs it owns (0, 1 or 2), evaluated from its four corners loaded once
// and scattered once. Shared by add_volume_forces (volume_terms.cpp, no springs) and the force pass of
// models with volume terms (forces.cpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

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

/// Output of the fused compression bound's traces (tet_record with Trace): per node s_i = m_i^-1/2 (0 on a
/// fixed node) and the rows tr B_i the corners' shares are added to.
struct CompTrace {
  const double* s;
  double* rows;
};

/// The fused compression bound's traces: the share of each corner k of a compressed term in the trace of its
/// node's 3x3 block B_i of the block bound (compression_terms.cpp, block_term), tr = a sigma s_k |g_k| + 3 hb
/// s_k (S - s_k) with a = kc h''(J) / V0, hb = |kc h'(J)| L_max / 6, g_k = dV/dx_k, sigma = sum_l s_l |g_l|
/// and S = sum_l s_l; 0 where J >= 1. c: 6 dV/dx of corners b, c, d; l2: the longest edge squared.
[[gnu::always_inline]] inline void compression_trace(const std::int32_t n[4], const double c[3][3],
                                                     double dv6, double V06, double kc6, double l2,
                                                     const CompTrace& out) {
  constexpr double jm = kCompressionJMin, d2m = 1.0 / (jm * jm) - 1.0;
  const double u = dv6 / V06;  // J - 1
  const double J = 1.0 + u;
  const double uc = u < 0.0 ? u : 0.0;
  const double ul = uc > jm - 1.0 ? uc : jm - 1.0;
  const double below = J < jm ? J - jm : 0.0;
  const double d1 = -ul * ul / (1.0 + ul) + d2m * below;                     // h'(J), 0 from J = 1 on
  const double Jl = 1.0 + ul;                                                // J clamped to [J_min, 1]
  const double d2 = u < 0.0 ? (J < jm ? d2m : 1.0 / (Jl * Jl) - 1.0) : 0.0;  // h''(J), 0 from J = 1 on
  const double a = 36.0 * kc6 / V06 * d2;                                    // kc h'' / V0
  const double hb = std::abs(kc6 * d1) * std::sqrt(l2);                      // |kc h'| L_max / 6
  double gn[4];                                                              // |dV/dx_k|
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
/// -kc h'(J) / 6 with J = 1 + dv6 / V06, h' of compression_h written without branches and without its
/// cancellation: h'(J) = 1 - 1/J - (J - 1) = -(J - 1)^2 / J on [J_min, 1), 0 from J = 1 on, and the
/// continuation h'(J_min) + h''(J_min) (J - J_min) below J_min. Only its forces: h (a logarithm) is not
/// needed.
[[gnu::always_inline]] inline double compression_scalar(double dv6, double V06, double kc6) {
  constexpr double jm = kCompressionJMin, d2m = 1.0 / (jm * jm) - 1.0;  // h''(J_min)
  const double u = dv6 / V06;                                           // J - 1
  const double J = 1.0 + u;
  const double uc = u < 0.0 ? u : 0.0;  // J - 1 clamped to [J_min - 1, 0]
  const double ul = uc > jm - 1.0 ? uc : jm - 1.0;
  const double below = J < jm ? J - jm : 0.0;             // the linear continuation's argument
  const double d1 = -ul * ul / (1.0 + ul) + d2m * below;  // h'(J)
  return -kc6 * d1;
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
  for (int k = 0; k < 4; ++k) {
    const double* p = x + 3 * static_cast<std::ptrdiff_t>(r.n[k]);
    P[k][0] = p[0];
    P[k][1] = p[1];
    P[k][2] = p[2];
  }
  double e[3][3];
  for (int k = 0; k < 3; ++k)
    for (int d = 0; d < 3; ++d) e[k][d] = P[k + 1][d] - P[0][d];
  double c[3][3];  // 6 dV/dx of corners b, c, d: e2 x e3, e3 x e1, e1 x e2
  cross3(e[1], e[2], c[0]);
  cross3(e[2], e[0], c[1]);
  cross3(e[0], e[1], c[2]);
  const double dv6 = e[0][0] * c[0][0] + e[0][1] * c[0][1] + e[0][2] * c[0][2] - r.V06;  // 6 (V - V0)
  double s = -r.alpha * dv6;
  if constexpr (Comp) s += compression_scalar(dv6, r.V06, r.kc6);
  double F[4][3];
  for (int d = 0; d < 3; ++d) {
    F[1][d] = s * c[0][d];
    F[2][d] = s * c[1][d];
    F[3][d] = s * c[2][d];
    F[0][d] = -(F[1][d] + F[2][d] + F[3][d]);
  }
  if constexpr (Stiff) {
    double gg = 0, l2 = 0;
    for (int d = 0; d < 3; ++d) {
      const double c0 = c[0][d] + c[1][d] + c[2][d];
      gg += c[0][d] * c[0][d] + c[1][d] * c[1][d] + c[2][d] * c[2][d] + c0 * c0;
    }
    for (int k = 0; k < 3; ++k) {
      const double a = e[k][0] * e[k][0] + e[k][1] * e[k][1] + e[k][2] * e[k][2];
      l2 = a > l2 ? a : l2;
      const int j = (k + 1) % 3;
      double q = 0;
      for (int d = 0; d < 3; ++d) q += (e[j][d] - e[k][d]) * (e[j][d] - e[k][d]);
      l2 = q > l2 ? q : l2;
    }
    const double cur = gg * (1.0 / 36.0) + std::abs(dv6) * std::sqrt(l2) * (1.0 / 12.0);  // |V - V0| L / 2
    if constexpr (Trace) compression_trace(r.n, c, dv6, r.V06, r.kc6, l2, *tr);
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
