// Nodal volume terms (issue 23, docs/volumetric-mesh.md "Locking and the nodal volume term"): the average
// nodal pressure of Bonet & Burton (1998), "A simple average nodal pressure tetrahedral element for
// incompressible and nearly incompressible dynamic explicit applications", Commun. Numer. Meth. Engng 14.
//
// Per node a, over the tetrahedra e that share it: W_a = sum_e V_e (current), W0_a = sum_e V0_e (rest),
// J_a = W_a / W0_a, the node's volume V_a = W0_a / 4 (the nodal volumes sum to the body's), and
//   E = sum_a 1/2 k_a V_a (J_a - 1)^2 = sum_a k_a (W_a - W0_a)^2 / (8 W0_a),
// k_a the volume-weighted mean of the moduli of its tetrahedra. The forces go through each tetrahedron's
// pressure, the sum of its corners' p_a = k_a (W_a - W0_a) / (4 W0_a) (= 1/4 sum of P_a = k_a (J_a - 1), the
// mean of its corners' pressures): f = -sum_e (sum_{a in e} p_a) dV_e/dx. Under a uniform strain it stores
// 1/2 V k (tr eps)^2 to first order, like the per-tetrahedron term E_t = k (V - V0)^2 / (2 V0), but it
// constrains one volume per node instead of one per tetrahedron (about a fifth as many), which is what
// removes the volumetric locking of linear tetrahedra at nu -> 1/2.
#pragma once

#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

using MatX4i = Eigen::Matrix<Index, Eigen::Dynamic, 4, Eigen::RowMajor>;  // as in models/volumetric_body.hpp

struct NodalVolumeTerms {
  MatX4i T;                // (#T x 4) tetrahedra, positive orientation at rest
  std::vector<double> V0;  // (#T) rest volumes, mm^3
  VecX k;                  // (#N) nodal modulus k_a, N/mm^2 (0 where a node has no tetrahedron)
  VecX W0;                 // (#N) sum of the rest volumes of the node's tetrahedra, mm^3

  Index size() const { return static_cast<Index>(T.rows()); }
};

/// Builds the terms on the tetrahedra T over the rest positions x0, tetrahedron e with modulus kv[e]
/// (N/mm^2, >= 0); the nodal moduli are the volume-weighted means. Throws InvalidInput naming `what` when a
/// corner is out of range or a rest tetrahedron is inverted or degenerate.
NodalVolumeTerms make_nodal_volume_terms(const MatX3& x0, const MatX4i& T, const std::vector<double>& kv,
                                         const std::string& what);

/// The energy (mJ) at x.
double nodal_volume_energy(const NodalVolumeTerms& N, const MatX3& x);

/// Adds the forces -dE/dx at x to f (#N x 3). `W` is scratch of #N doubles (overwritten).
void add_nodal_volume_forces(const NodalVolumeTerms& N, const MatX3& x, MatX3& f, VecX& W);

/// Appends the Gauss-Newton Hessian sum_a k_a / (4 W0_a) G_a G_a^T (G_a = dW_a/dx, over the tetrahedra
/// at a) at x as triplets (3N x 3N); at rest (x = x0) it is the exact Hessian, the rest stiffness. Each
/// node couples every pair of nodes of its tetrahedra, so the matrix is denser than the per-tetrahedron
/// term's.
void add_nodal_volume_stiffness_triplets(const NodalVolumeTerms& N, const MatX3& x,
                                         std::vector<Eigen::Triplet<double>>& out);

}  // namespace medspring
