// The effective elastic moduli of a spring-and-volume-term network (issue 23, docs/volumetric.md,
// "Effective moduli of the mesh"): homogeneous strains imposed on the boundary nodes (kinematic uniform
// boundary conditions), the interior relaxed statically at rest (small strain), and the stored energy read
// as an elasticity tensor. Needs no FEM: it measures what the per-tetrahedron closed forms give on a real,
// irregular mesh, where the interior relaxes non-affinely.
#pragma once

#include <Eigen/SparseCore>
#include <array>
#include <string>

#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/model.hpp"

namespace medspring {

struct MeshModuli {
  // Isotropic part of the effective tensor (N/mm^2): mu = mean energy of the five unit deviatoric strains
  // per volume, K = bulk modulus from the unit hydrostatic strain.
  double mu = 0, K = 0;
  double mu_min = 0, mu_max = 0;  // spread over the five deviatoric modes (anisotropy of the mesh)
  // The same with every node moved affinely (no relaxation): the per-tetrahedron rule's own value.
  double mu_affine = 0, K_affine = 0;
  // Uniform traction sigma n on the boundary faces instead (static uniform boundary conditions, the lower
  // bound of the two; 0 when no faces were given): the boundary layer is free to relax too.
  double mu_traction = 0, K_traction = 0;
  double volume = 0;  // mm^3 (sum of the rest tetrahedron volumes of the model's volume terms, or given)
  double lambda() const { return K - 2.0 * mu / 3.0; }
  double nu() const { return (3.0 * K - 2.0 * mu) / (2.0 * (3.0 * K + mu)); }
  double E() const { return 9.0 * K * mu / (3.0 * K + mu); }  // N/mm^2
};

/// Effective moduli of `model` at rest: the first `boundary_nodes` nodes follow u = eps x (eps: the six
/// unit strains of the Mandel basis), the others are relaxed (K_ii u_i = -K_ib u_b; return springs and
/// pins ignored), and the energies u^T K u / (2 V) give the tensor. `volume` (mm^3) is the body's volume
/// (0: the sum of the rest volumes of the model's volume terms). With `faces` (outward triangles over the
/// boundary nodes) it also loads the free body by the uniform tractions of the six unit stresses (nodal
/// forces sigma n A / 3) and reads the compliance (mu_traction, K_traction). Throws InvalidInput when there
/// is no interior node, no boundary node or no volume, SolverError when the interior is not held (singular).
MeshModuli mesh_moduli(const Model& model, Index boundary_nodes, double volume = 0,
                       const MatX3i* faces = nullptr);
/// The same for a stiffness matrix K (3N x 3N, at rest) over the nodes X, e.g. p1_stiffness. With no interior
/// node (boundary_nodes = N) the strains are affine.
MeshModuli mesh_moduli(const Eigen::SparseMatrix<double>& K, const MatX3& X, Index boundary_nodes,
                       double volume, const MatX3i* faces = nullptr, const std::string& name = "mesh");

/// The linear-elastic stiffness (3N x 3N, N/mm) of the linear tetrahedra T over X with Lame parameters
/// (mu, lambda) in N/mm^2: the P1 finite element on the same mesh as a volumetric spring model, the yardstick
/// that separates the mesh's own discretisation error from the spring rule's (docs/accuracy.md).
Eigen::SparseMatrix<double> p1_stiffness(const MatX3& X, const MatX4i& T, double mu, double lambda);

/// Multipliers (springs, volume terms) that bring the measured effective moduli of the mesh to (mu, lambda):
/// the volumetric rule of docs/volumetric.md (springs k = 5/2 mu V / L^2 per tetrahedron, volume modulus
/// lambda - mu) is exact for affine deformation only; on an irregular mesh the interior relaxes and the
/// network comes out a few % softer. The target is the mean of the uniform-strain (upper) and
/// uniform-traction (lower) estimates of mesh_moduli; three fixed-point rounds (springs from mu, volume terms
/// from the bulk modulus); with nu < 1/4 (no volume term) only the springs are corrected.
struct ModuliCorrection {
  double spring = 1, volume = 1;       // multipliers of the rule's springs and volume terms
  double mu_before = 0, K_before = 0;  // measured effective moduli / target before the correction
  double mu_after = 0, K_after = 0;    // and after
};
ModuliCorrection moduli_correction(const VolumetricMesh& mesh, double mu, double lambda);

}  // namespace medspring
