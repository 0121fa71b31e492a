// A correction term for thin tetrahedra of the volumetric spring model (issue 23, docs/volumetric-mesh.md,
// "A correction term for thin tetrahedra"). Six central springs per tetrahedron sense only n^T eps n, so a
// flat tetrahedron loses its through-thickness shear as (h/L)^2. Per flagged tetrahedron this term adds
//   E_c = 1/2 V0 e(U - I)^T C_c e(U - I),   U = sqrt(F^T F),  F = Ds Dm^-1,
// where e(.) is the Mandel vector of a symmetric tensor and C_c = P+(C_P1 - C_rule) is the positive part of
// the difference between the linear P1 element's and the rule's (springs + volume term) rest stiffness.
// The forces are the exact gradient (rotation from the polar decomposition, no rotation estimate), so they
// conserve linear and angular momentum and a rigid rotation gives none. Part of Model (Model::thin), built
// by VolumetricBody when VolumetricSettings::thin_tet is on (off by default).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

/// How the difference C_P1 - C_rule is kept positive semi-definite.
enum class ThinTetProjection {
  Clip,  // C_c = P+(C_P1 - C_rule): negative eigenvalues set to 0; the springs keep their in-plane excess
  ScaleSprings,  // the tetrahedron's springs are scaled by the largest s <= 1 with C_P1 - C_vol - s C_spr
                 // PSD, and C_c = C_P1 - C_vol - s C_spr: rule + term = P1 exactly at rest (spring_factor =
                 // s)
};

/// Which tetrahedra get a term and with which rule they are compared.
struct ThinTetSettings {
  double E = 0.01;          // Young's modulus, N/mm^2
  double nu = 0.45;         // Poisson ratio, [0, 0.5)
  double q_max = 0.3;       // a term on the tetrahedra with q = h_min / L_max < q_max (q = 1 to take all)
  double spring_scale = 1;  // the rule's springs: each edge k_e L_e^2 = spring_scale * (5/2) mu V
  double volume_scale = 1;  // the rule's volume term: kv = volume_scale * max(lambda - mu, 0)
  ThinTetProjection projection = ThinTetProjection::Clip;
};

/// The terms as a struct of arrays; term t spans corners n[t] of the tetrahedron tet[t] of the input.
struct ThinTetCorrections {
  std::vector<std::array<Index, 4>> n;  // corners
  std::vector<Index> tet;               // index of the tetrahedron in the input list
  std::vector<Mat3> DmInv;              // inverse rest edge matrix [x1-x0, x2-x0, x3-x0]^-1
  std::vector<double> V0;               // rest volume, mm^3
  std::vector<Mat6> C;                  // C_c (Mandel, N/mm^2), symmetric positive semi-definite
  std::vector<double> clipped;          // the largest clipped (negative) eigenvalue's magnitude / (2 mu)
  std::vector<double> spring_factor;    // factor on this tetrahedron's share of its six springs (1 with Clip)
  std::vector<double> c_max;            // largest eigenvalue of C_c (N/mm^2), for the stable step's bound

  Index size() const { return static_cast<Index>(n.size()); }
};

/// Mandel vector (e11, e22, e33, sqrt2 e23, sqrt2 e13, sqrt2 e12) of a symmetric tensor.
Vec6 mandel(const Mat3& s);
/// q = h_min / L_max of a tetrahedron: its smallest height (3 V / largest face area) over its longest edge.
double tet_quality(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3);
/// The rest stiffness (Mandel) of the linear P1 element, lambda dd^T + 2 mu I.
Mat6 p1_mandel_stiffness(double E, double nu);
/// The rest stiffness (Mandel) of the rule's springs and volume term on one tetrahedron; the springs'
/// share times spring_factor.
Mat6 rule_mandel_stiffness(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3,
                           const ThinTetSettings& s, double spring_factor = 1.0);

/// Builds the terms for the tetrahedra `tets` (#T x 4, positive orientation) of the rest positions x0 whose
/// quality is below s.q_max. Throws InvalidInput naming `what` and the element when E <= 0, nu outside
/// [0, 0.5), a corner is out of range or a rest tetrahedron is inverted or degenerate.
ThinTetCorrections build_thin_tet_corrections(const MatX3& x0, const std::vector<std::array<Index, 4>>& tets,
                                              const ThinTetSettings& s, const std::string& what);

/// Sum of the terms' energies (mJ) at x.
double thin_tet_energy(const ThinTetCorrections& C, const MatX3& x);
/// Adds the forces -dE_c/dx to f (#nodes x 3).
void add_thin_tet_forces(const ThinTetCorrections& C, const MatX3& x, MatX3& f);
/// The rest Hessian V0 B^T C_c B of term t (12 x 12, corner-major: rows 3k..3k+2 are corner k).
Mat12 thin_tet_rest_stiffness(const ThinTetCorrections& C, Index t);
/// The rest stiffness V B^T C B (12 x 12, corner-major) of the tetrahedron `tet` of x0 for a Mandel stiffness
/// C (positive orientation).
Mat12 tet_mandel_rest_stiffness(const MatX3& x0, const std::array<Index, 4>& tet, const Mat6& C);
/// What the terms change in the rest stiffness of a model of the rule on x0 (3N x 3N): their rest Hessians
/// and, with ScaleSprings, (spring_factor - 1) times each flagged tetrahedron's share of its springs. Added
/// to the plain rule's tangent stiffness at rest it gives the corrected model's (the one VolumetricBody
/// builds with thin_tet on) linear response. `s` must be the settings the terms were built with.
Eigen::SparseMatrix<double> thin_tet_rest_stiffness_change(const ThinTetCorrections& C, const MatX3& x0,
                                                           const ThinTetSettings& s);

/// Adds the forces and, with `stiffening`, returns the largest growth factor over the terms of the term's
/// stiffness off rest (1 at rest; docs/volumetric-mesh.md, "Stable step"):
///   s_t = 2 rho + 3 |T|_F / (sigma_min c_max),  rho = max_{i<j} (s_i^2 + s_j^2) / (s_i + s_j)^2,
/// sigma the singular values of F, T the Biot stress C_c e(U - I): d^2 Psi/dF^2 <= s_t c_max |dF|^2, where
/// the rest stiffness is c_max |sym dF|^2 at most. Without `stiffening` returns 1.
double add_thin_tet_forces(const ThinTetCorrections& C, const MatX3& x, MatX3& f, bool stiffening);
/// y += K_c p, K_c = sum_t R_t K_t(x0) R_t^T (the terms' rest stiffness co-rotated by the polar rotation of
/// each F: symmetric positive semi-definite, exact at rest; the Gauss-Newton part of the implicit step's
/// and the stable-step estimate's product). p, y: 3 #N (node-major).
void add_thin_tet_stiffness_product(const ThinTetCorrections& C, const MatX3& x, const VecX& p, VecX& y);
/// The same co-rotated stiffness as triplets (rows 3 a + i) for tangent_stiffness.
void add_thin_tet_stiffness_triplets(const ThinTetCorrections& C, const MatX3& x,
                                     std::vector<Eigen::Triplet<double>>& T);
/// Checks sizes, corner ranges, finite positive V0 and finite C of terms set by hand (finalize); throws
/// InvalidInput naming `what` and the term.
void validate_thin_tet_corrections(const ThinTetCorrections& C, Index nodes, const std::string& what);

/// Adds, per node, the Gershgorin row bound of the terms' rest Hessians in the form of add_volume_gershgorin:
/// diag[a] += Frobenius norm of its own 3x3 block, off[a] += sum over the free other corners b of the
/// Frobenius norms of the blocks (a, b) / sqrt(m_a m_b).
void add_thin_tet_gershgorin(const ThinTetCorrections& C, const VecX& mass,
                             const std::vector<std::uint8_t>& fixed, VecX& diag, VecX& off);

}  // namespace medspring
