// Volume terms of a volumetric spring model (issue 23, docs/volumetric.md): one per tetrahedron,
//   E_t = kv_t / (2 V0_t) (V_t - V0_t)^2,   V_t = (x_b - x_a) . ((x_c - x_a) x (x_d - x_a)) / 6,
// the energy of a bulk-like modulus kv (N/mm^2) acting on the volume strain (V - V0) / V0. It restores the
// Poisson effect that edge springs lack (a spring lattice is locked near nu = 1/4). The energy is a
// polynomial of the positions, so an inverted tetrahedron (V < 0) gets a finite restoring force, never a
// NaN; inverted elements are counted per frame in State::warnings.inverted_elements.
#pragma once

#include <Eigen/SparseCore>
#include <cstdint>
#include <string>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

struct CompressionTerms;  // compression_terms.hpp
struct VolumeTermsF32;    // the single-precision pass's rest data (src/physics/volume_f32.hpp, internal)

/// Volume terms as a struct of arrays; term t spans the tetrahedron (a[t], b[t], c[t], d[t]) with a
/// positive rest volume.
struct VolumeTerms {
  std::vector<Index> a, b, c, d;  // (#T) corners, positive orientation at rest
  std::vector<double> kv;         // (#T) modulus, N/mm^2 (= MPa), >= 0
  std::vector<double> V0;         // (#T) rest volume, mm^3 (set by finalize from the rest positions)
  std::vector<double> G0;         // (#T) rest sum over corners of |dV/dx|^2, mm^4 (set by finalize)

  /// Rest data of one term for the fused force pass, packed (one record per term, 64 bytes): the corners,
  /// up to two springs of the model that lie on its edges ("owned": evaluated with the term, from the same
  /// four loaded corners, and scattered once), and the precomputed constants.
  struct Packed {
    std::int32_t n[4];   // corners a, b, c, d
    std::int32_t s[2];   // owned springs (-1: none)
    std::uint8_t pq[2];  // local corners (p, q) of owned spring k: 4 p + q, spring i = n[p], j = n[q]
    double alpha;        // kv / (36 V0): f_k = -alpha (6V - 6V0) (e_k+1 x e_k+2), 1/mm
    double V06;          // 6 V0, mm^3
    double iG0;          // 1 / rest sum of |dV/dx|^2 (stiffening bound; 0 when that sum is 0)
    double kv;           // modulus (the order of the records is not the order of the terms)
    double kc6;          // the fused compression term's kc / 6 (0: none; fuse_compression_terms)
  };
  // Derived by finalize_volume_terms (records) and plan_owned_springs (owned springs): the records
  // grouped by the number of springs they own (0, 1, 2), so that the fused pass runs three loops without
  // a branch per record; loose springs are those of the model that no term owns.
  std::vector<Packed> packed;
  Index owned_end[3] = {0, 0, 0};    // ends of the groups owning 0, 1, 2 springs in `packed`
  std::vector<Index> loose_springs;  // springs evaluated by the plain spring pass
  Index planned_springs = -1;        // number of springs of the plan (-1: none; every spring is loose)
  // Derived by set_volume_rest_rows (Model's finalize), for the local stiffening of the stable step: per
  // record (in `packed` order) and corner k, the term's share of its corner's rest Gershgorin row of
  // M^-1/2 K M^-1/2, r_k = kv/V0 |dV0/dx_k| sum_{l free} |dV0/dx_l| / sqrt(m_k m_l), (rad/ms)^2; 0 for a
  // fixed corner. Empty (the global rule is used) until set, and cleared by finalize / plan.
  std::vector<double> rest_rows;  // (4 #T)
  // Derived by fuse_compression_terms (Model's finalize): the moduli kc of the model's compression terms
  // on the same tetrahedra (term order), evaluated in this pass (records' kc6); empty: not fused. Cleared
  // by finalize.
  std::vector<double> kc;  // (#T)

  Index size() const { return static_cast<Index>(a.size()); }
  void add(Index na, Index nb, Index nc, Index nd, double modulus) {
    a.push_back(na);
    b.push_back(nb);
    c.push_back(nc);
    d.push_back(nd);
    kv.push_back(modulus);
    V0.push_back(0.0);
    G0.push_back(0.0);
  }
};

/// Signed volume (mm^3) of the tetrahedron (p0, p1, p2, p3); positive when (p1-p0, p2-p0, p3-p0) is
/// right-handed.
double signed_tet_volume(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3);

/// Sets V0 and G0 from the rest positions x0; throws InvalidInput naming `what` and the term when a
/// corner is out of range, repeated, kv is negative or not finite, or the rest tetrahedron is inverted
/// or degenerate (volume <= 1e-12 of its longest edge cubed).
void finalize_volume_terms(VolumeTerms& T, const MatX3& x0, const std::string& what);

/// Lets the terms own springs (i[s], j[s]) of the model that lie on their edges, at most two per term, so
/// that the fused pass (add_volume_and_owned_spring_forces) evaluates them; the others become loose.
/// Call after finalize_volume_terms with the model's final spring arrays (Model's finalize does).
void plan_owned_springs(VolumeTerms& T, const std::vector<Index>& i, const std::vector<Index>& j,
                        Index nodes);

/// Fuses compression terms C (compression_terms.hpp) into the volume pass when they span the same
/// tetrahedra as T, term by term with the same corners in the same order (as VolumetricBody builds them),
/// T is finalized and has no spring plan yet: sets T.kc and the records' kc6, so that
/// add_volume_and_compression_forces (and the fused spring pass without the stiffening) add C's forces
/// -kc h'(J) dV/dx along the same dV/dx, with J = V / V0 of the volume term (one gradient and one scatter
/// per tetrahedron). Returns whether it fused (else T.kc is empty and C's forces stay with
/// add_compression_forces, as they do in the force pass with the stable step's bound).
bool fuse_compression_terms(VolumeTerms& T, const CompressionTerms& C);

/// Sets T.rest_rows from the rest positions, masses and pins (after finalize_volume_terms).
void set_volume_rest_rows(VolumeTerms& T, const MatX3& x0, const VecX& mass,
                          const std::vector<std::uint8_t>& fixed);

/// The volume forces with the local stiffening (issue 23, docs/volumetric-speed.md "Stable step"): adds
/// -dE/dx to f like add_volume_forces and returns the terms' largest stiffening s_max (>= 1) as it does; in
/// addition sets row_max = max over nodes i of sum over the terms t at i with s_t > 1 of (s_t - 1) r_t,i, the
/// Gershgorin bound of the stiffening's increment to M^-1/2 K M^-1/2 ((rad/ms)^2). `rows` is scratch of
/// `nodes` + #T doubles (overwritten). Needs T.rest_rows. The two halves are add_volume_forces_inc and
/// volume_row_max.
double add_volume_forces_local(const VolumeTerms& T, const double* x, double* f, double* rows, Index nodes,
                               double& row_max);
/// add_volume_forces with the stiffening, and each term's stiffening increment (s_t - 1)+ into inc (#T, in
/// `packed` order).
double add_volume_forces_inc(const VolumeTerms& T, const double* x, double* f, double* inc);
/// max over nodes i of sum over the terms t at i of inc_t r_t,i (the rest rows); `rows`: scratch of `nodes`
/// doubles. Needs T.rest_rows.
double volume_row_max(const VolumeTerms& T, const double* inc, double* rows, Index nodes);

/// Adds the volume forces -dE/dx to f (flat 3N arrays). With `stiffening`, returns the stiffening of the
/// terms (>= 1): the largest ratio of a term's current curvature bound to its rest one, for the stable
/// step (§2.2); without, returns 1 (skips the six edge lengths per term).
double add_volume_forces(const VolumeTerms& T, const double* x, double* f, bool stiffening = true);
/// add_volume_forces without the stiffening, and the forces of the fused compression terms (T.kc, from
/// fuse_compression_terms; none when empty) in the same pass: one dV/dx and one scatter per tetrahedron.
/// The force passes of the sub-steps without the stable step's bound use it (forces.cpp); the pass with the
/// bound keeps add_volume_forces and add_compression_forces (which evaluates the bound with the forces).
void add_volume_and_compression_forces(const VolumeTerms& T, const double* x, double* f);
/// Sum of the volume energies (mJ).
double volume_energy(const VolumeTerms& T, const MatX3& x);
/// Number of terms whose tetrahedron is inverted or flat (V <= 0) at x.
std::uint64_t count_inverted(const VolumeTerms& T, const MatX3& x);
/// y += K_vol p, the exact Hessian of the volume energy at x applied to p (flat 3N); gauss_newton drops
/// the (V - V0) d^2V part (symmetric positive semi-definite, for CG solves).
void add_volume_stiffness_product(const VolumeTerms& T, const MatX3& x, const VecX& p, VecX& y,
                                  bool gauss_newton = false);
/// Appends the exact 12 x 12 Hessian blocks of every term at x as triplets (3N x 3N).
void add_volume_stiffness_triplets(const VolumeTerms& T, const MatX3& x,
                                   std::vector<Eigen::Triplet<double>>& out);
/// Adds, per node, the Gershgorin row bound of the terms' Hessian at x: diag[a] += sum over its terms of
/// the norm of its own block, off[a] += sum of the norms of its blocks with the free other corners / sqrt
/// of the masses (the §2.2 form used for springs).
void add_volume_gershgorin(const VolumeTerms& T, const MatX3& x, const VecX& mass,
                           const std::vector<std::uint8_t>& fixed, VecX& diag, VecX& off);

}  // namespace medspring
