// Forces, energy and tangent stiffness of a Model (ALGORITHMS.md §1.3–1.8).
#pragma once

#include <Eigen/SparseCore>

#include "medspring/physics/model.hpp"

namespace medspring {

/// f = f_ext - k_r (x - x0) + sum of spring and bending forces, without damping (the g of §2.1),
/// for every node (fixed ones included). Returns max_s kappa_s / k_s (>= 1), the stiffening of §2.2.
/// Springs shorter than 1e-9 mm are skipped (direction undefined, §1.3).
double internal_forces(const Model& model, const MatX3& x, const MatX3& f_ext, MatX3& f);

/// Total energy (§1.8): kinetic + return springs + springs + bending, mJ (= N mm).
double total_energy(const Model& model, const MatX3& x, const MatX3& v);
/// Potential energy only (return springs + springs + bending), mJ.
double potential_energy(const Model& model, const MatX3& x);

struct StiffnessOptions {
  bool clamp_transverse = false;  // use max(phi/L, 0) for the transverse term (SPD; Choi & Ko 2002)
  bool include_return = true;     // add k_r I per node
};

/// Tangent stiffness K = d^2 V / dx^2 (3N x 3N, all nodes; internal-force Jacobian = -K), §1.3.
Eigen::SparseMatrix<double> tangent_stiffness(const Model& model, const MatX3& x,
                                              const StiffnessOptions& opt = {});

/// Largest per-node norm of the static residual f_ext + f_int over free nodes (N).
double max_residual(const Model& model, const MatX3& x, const MatX3& f_ext);

}  // namespace medspring
