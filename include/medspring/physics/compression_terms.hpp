// Compression-stiffening terms of a volumetric spring model (issue 23, docs/volumetric.md "Compression
// stiffening"): one per tetrahedron, an energy of the volume ratio J = V / V0 alone,
//   E_t = kc_t V0_t h(J),   h(J) = J - 1 - ln J - (J - 1)^2 / 2  for J < 1,   h(J) = 0  for J >= 1,
// so h(1) = h'(1) = h''(1) = 0: the small-strain moduli of the springs and volume terms are unchanged, the
// term does nothing in tension, and under compression its curvature h'' = 1/J^2 - 1 grows without bound as
// the tetrahedron flattens -- the Neo-Hookean barrier (-ln J, the J^(-2/3) of the isochoric invariant) that
// linear edge springs plus the quadratic volume term lack. Below J_min = 1/4 h continues as its second-order
// Taylor polynomial at J_min, so an inverted tetrahedron (J <= 0) gets a finite restoring force, never a NaN
// (counted per frame in State::warnings.inverted_elements).
//
// The force of a term is along dV/dx, like the volume term's: f_k = -kc h'(J) dV/dx_k (a fused kernel can
// add kc h'(J) to the volume term's kv (J - 1) scalar).
#pragma once

#include <Eigen/SparseCore>
#include <cstdint>
#include <string>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

/// The continuation point of h: below J_min the energy is quadratic in J (finite for J <= 0).
inline constexpr double kCompressionJMin = 0.25;

/// h(J) and its first two derivatives (see the header comment).
struct CompressionH {
  double h = 0, d1 = 0, d2 = 0;
};
CompressionH compression_h(double J);

/// Compression terms as a struct of arrays; term t spans the tetrahedron (a[t], b[t], c[t], d[t]) with a
/// positive rest volume.
struct CompressionTerms {
  std::vector<Index> a, b, c, d;
  std::vector<double> kc;  // (#T) modulus, N/mm^2 (>= 0)
  std::vector<double> V0;  // (#T) rest volume, mm^3 (set by finalize)

  Index size() const { return static_cast<Index>(a.size()); }
  void add(Index na, Index nb, Index nc, Index nd, double modulus) {
    a.push_back(na);
    b.push_back(nb);
    c.push_back(nc);
    d.push_back(nd);
    kc.push_back(modulus);
    V0.push_back(0.0);
  }
};

/// Sets V0 from the rest positions; throws InvalidInput naming `what` and the term when a corner is out of
/// range or repeated, kc is negative or not finite, or the rest tetrahedron is inverted or degenerate.
void finalize_compression_terms(CompressionTerms& T, const MatX3& x0, const std::string& what);

/// Adds the forces -dE/dx to f (flat 3N). With `mass` (#N), `fixed` (#N) and `rows` (scratch of
/// 6 #N doubles, overwritten: src/physics/compression_rows.hpp), returns a bound of the largest eigenvalue of
/// the terms' mass-scaled Hessian M^-1/2 (sum_t H_t) M^-1/2 at x over the free DOFs ((rad/ms)^2); by Weyl the
/// caller adds it to the others' omega^2 bound. Without them returns 0. The bound (docs/volumetric.md
/// "Compression stiffening"): H_t = a g g^T + b d^2V with a = kc h''/V0 >= 0, b = kc h', g = dV/dx. By
/// Cauchy-Schwarz with weights c_k = s_k |g_k| (s_k = m_k^-1/2, 0 when fixed), (sum_k s_k g_k.v_k)^2 <= sigma
/// sum_k s_k/|g_k| (g_k.v_k)^2 (sigma = sum_k c_k), so the rank-one part is at most the block diagonal of the
/// 3x3 blocks a sigma s_k / |g_k| g_k g_k^T; the blocks of d^2V are skew(edge)/6 (norm <= L_max/6) with zero
/// diagonal, so that part is at most |b| L_max/6 s_k (sum_{l != k} s_l) I per corner. The per-node sum B_i of
/// these 3x3 blocks dominates the matrix, so lambda_max <= max_i lambda_max(B_i) <= max_i tr/3 + sqrt(2/3)
/// |dev B_i|_F. It is never above the former scalar Gershgorin row bound (the trace of the same blocks, with
/// the d^2V blocks bounded by L_max/3), and tighter where the terms at a node pull in different directions.
double add_compression_forces(const CompressionTerms& T, const double* x, double* f,
                              const double* mass = nullptr, const std::uint8_t* fixed = nullptr,
                              double* rows = nullptr, Index nodes = 0);
/// Sum of the energies (mJ).
double compression_energy(const CompressionTerms& T, const MatX3& x);
/// Number of terms whose tetrahedron is inverted or flat (V <= 0) at x.
std::uint64_t count_inverted(const CompressionTerms& T, const MatX3& x);
/// y += K p with the exact Hessian at x (gauss_newton: only kc h'' / V0 dV dV^T, positive semi-definite).
void add_compression_stiffness_product(const CompressionTerms& T, const MatX3& x, const VecX& p, VecX& y,
                                       bool gauss_newton = false);
/// Appends the exact 12 x 12 Hessian blocks of every compressed term at x as triplets (3N x 3N).
void add_compression_stiffness_triplets(const CompressionTerms& T, const MatX3& x,
                                        std::vector<Eigen::Triplet<double>>& out);
/// Adds the Gershgorin row bounds of the terms' Hessian at x (the form of add_volume_gershgorin).
void add_compression_gershgorin(const CompressionTerms& T, const MatX3& x, const VecX& mass,
                                const std::vector<std::uint8_t>& fixed, VecX& diag, VecX& off);

}  // namespace medspring
