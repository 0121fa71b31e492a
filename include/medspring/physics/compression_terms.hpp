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
  std::vector<double> kc;    // (#T) modulus, N/mm^2 (>= 0)
  std::vector<double> kref;  // (#T) the tetrahedron's rest bulk modulus, N/mm^2 (> 0), for the stable step
  std::vector<double> V0;    // (#T) rest volume, mm^3 (set by finalize)
  std::vector<double> iref;  // (#T) 1 / (9 kref V0 / sum_k |x_k - x_c|^2) at rest (set by finalize)

  Index size() const { return static_cast<Index>(a.size()); }
  void add(Index na, Index nb, Index nc, Index nd, double modulus, double rest_bulk_modulus) {
    a.push_back(na);
    b.push_back(nb);
    c.push_back(nc);
    d.push_back(nd);
    kc.push_back(modulus);
    kref.push_back(rest_bulk_modulus);
    V0.push_back(0.0);
    iref.push_back(0.0);
  }
};

/// Sets V0 and iref from the rest positions; throws InvalidInput naming `what` and the term when a corner
/// is out of range or repeated, kc is negative or not finite, kref is not positive, or the rest
/// tetrahedron is inverted or degenerate.
void finalize_compression_terms(CompressionTerms& T, const MatX3& x0, const std::string& what);

/// Adds the forces -dE/dx to f (flat 3N). Returns the terms' stiffening for the stable step: 1 + max over
/// the compressed terms of ||d^2E_t|| / ||K_t(x0)||, with ||d^2E_t|| <= kc (h'' |dV/dx|^2 / V0 + |h'| L_max /
/// 2) and ||K_t(x0)|| >= 9 kref V0 / sum_k |x_k - x_c|^2 (the rest energy of the tetrahedron's uniform
/// dilatation, whose bulk modulus is exact; docs/volumetric.md). The caller adds (s - 1) to the springs'
/// and volume terms' stiffening (Weyl: the term is an addition to the rest stiffness).
double add_compression_forces(const CompressionTerms& T, const double* x, double* f, bool stiffening = true);
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
