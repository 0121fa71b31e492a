// The FEM reference solve (docs/accuracy.md): large-deformation static equilibrium of a compressible
// Neo-Hookean body in CalculiX (Debian package calculix-ccx, run as a subprocess).
//
//   fem::FemProblem p{fem::box_mesh(xs, ys, zs), fem::Material::from_kpa(10, 0.45)};
//   p.fixed = {...};                       // supports: all three displacements zero
//   p.loads = {{node, Vec3(0, 0, -0.5)}};  // nodal forces, N
//   fem::FemResult r = fem::solve(p);      // r.u: nodal displacements, mm
//
// Units: length mm, force N, so stress and moduli in N/mm^2 = MPa (10 kPa = 0.01 MPa).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "medspring/fem/tet_mesh.hpp"

namespace medspring::fem {

/// Compressible Neo-Hookean material (CalculiX *HYPERELASTIC, NEO HOOKE):
/// W = C10 (I1bar - 3) + (J - 1)^2 / D1, with C10 = mu / 2 and D1 = 2 / K for the small-strain
/// Young's modulus E and Poisson ratio nu.
struct Material {
  double E = 0.0;   // Young's modulus, MPa (N/mm^2)
  double nu = 0.0;  // Poisson ratio, in (-1, 0.5)
  static Material from_kpa(double E_kPa, double nu) { return {E_kPa * 1e-3, nu}; }
  double mu() const { return E / (2.0 * (1.0 + nu)); }
  double bulk() const { return E / (3.0 * (1.0 - 2.0 * nu)); }
  double c10() const { return mu() / 2.0; }
  double d1() const { return 2.0 / bulk(); }
};

/// Throws InvalidInput unless E > 0 and -1 < nu < 0.5 (both finite); `what` names the material.
void validate_material(const Material& m, const std::string& what = "material");

/// A force (N) on one node.
struct NodalForce {
  Index node = 0;
  Vec3 force = Vec3::Zero();
};

/// One displacement component held at a value (mm): dof 0, 1, 2 = x, y, z.
struct DofConstraint {
  Index node = 0;
  int dof = 0;
  double value = 0.0;
};

struct FemProblem {
  FemProblem() = default;
  FemProblem(TetMesh m, const Material& mat) : mesh(std::move(m)), material(mat) {}
  TetMesh mesh;
  Material material;
  std::vector<Index> fixed;                // nodes with all three displacements zero (supports)
  std::vector<DofConstraint> constraints;  // single components held (symmetry planes, imposed values)
  std::vector<NodalForce> loads;           // dead loads, N
};

struct FemSettings {
  int increments = 5;      // initial increment = 1 / increments of the load (CalculiX may cut back)
  bool use_cache = true;   // look up / store results in cache_dir
  std::string cache_dir;   // default: $MEDSPRING_FEM_CACHE, else $XDG_CACHE_HOME or ~/.cache + /medspring/fem
  std::string executable;  // default: $MEDSPRING_CCX, then `ccx` on PATH
  bool reaction_forces = false;  // also ask CalculiX for the nodal reaction forces (FemResult::rf)
};

struct FemResult {
  MatX3 u;                     // nodal displacements (#N x 3), mm
  MatX3 rf;                    // nodal reaction forces (#N x 3), N, at supports and imposed values
                               // (zero elsewhere); empty unless FemSettings::reaction_forces
  double solve_seconds = 0.0;  // wall time of the CalculiX run (the cached one's when from_cache)
  bool from_cache = false;
  std::uint64_t key = 0;  // cache key: FNV-1a 64 of the input deck
};

/// Validates a problem: a mesh with positive elements, the material, node and dof indices in range,
/// finite values, and constraints that leave no rigid motion free (InvalidInput naming what is wrong).
void validate_problem(const FemProblem& p);

/// The CalculiX input deck (.inp) of a problem (nodes and elements numbered from 1).
std::string write_inp(const FemProblem& p, const FemSettings& s = {});

/// Solves the problem (or returns the cached result of an identical input deck). Throws IoError when
/// ccx is missing (naming calculix-ccx) and SolverError with the last lines of CalculiX's output when
/// the run fails or does not converge to the full load. Nothing is written outside a private temporary
/// folder except the cache entry, which is written under a temporary name and renamed.
FemResult solve(const FemProblem& p, const FemSettings& s = {});

}  // namespace medspring::fem
