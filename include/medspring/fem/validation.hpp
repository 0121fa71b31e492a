// Validation of the FEM pipeline against closed-form solutions (docs/accuracy.md). Each case meshes,
// solves with CalculiX and compares one quantity with its analytic value, at a refinement level
// (1 = coarse, used by the test suite; 2, 3 finer, used by `medspring accuracy`).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "medspring/fem/calculix.hpp"

namespace medspring::fem {

struct ValidationResult {
  ValidationResult() = default;
  ValidationResult(std::string n, int l) : name(std::move(n)), level(l) {}
  std::string name;  // "uniaxial", "cantilever", "boussinesq"
  int level = 0;     // refinement level
  Index nodes = 0, elements = 0;
  std::string quantity;  // what was compared, with its unit
  double fem = 0.0, analytic = 0.0;
  double rel_error = 0.0;  // |fem - analytic| / |analytic|
  double solve_seconds = 0.0;
};

/// Uniaxial stretch of a 10 mm Neo-Hookean cube (E = 10 kPa, nu = 0.45) under a dead nominal traction
/// of 2 kPa, symmetry planes as supports; compares the stretch with the exact compressible Neo-Hookean
/// solution (uniaxial_stretch()).
ValidationResult validate_uniaxial(int level, const FemSettings& s = {});

/// Small-deflection cantilever 40 x 4 x 4 mm (E = 1 MPa, nu = 0.3), clamped at x = 0, a shear load on
/// the tip face giving a deflection of ~1 % of the length; compares the mean tip deflection with
/// Timoshenko beam theory F L^3 / (3 E I) + F L / (kappa G A), kappa = 5/6.
ValidationResult validate_cantilever(int level, const FemSettings& s = {});

/// Uniform pressure on a disk of radius a = 1 mm on a thick block (quarter model, 10 a x 10 a x 10 a,
/// E = 1 MPa, nu = 0.4, total force 0.01 N), the exact Boussinesq point-load field imposed on the far
/// faces; compares the displacement under the disk centre with 2 (1 - nu^2) p a / E and (second result)
/// the surface displacement at r = 3 a with the exact disk-load solution (elliptic integrals).
std::vector<ValidationResult> validate_boussinesq(int level, const FemSettings& s = {});

/// Exact stretch lambda of the compressible Neo-Hookean material under a dead uniaxial nominal stress
/// P (MPa), lateral faces free.
double uniaxial_stretch(const Material& m, double P);

/// Displacement (mm) at x of a point load F (N) at the origin pressing into the half-space z < 0
/// (Boussinesq), for the linear material m (MPa). The far-field condition of validate_boussinesq and of
/// the sphere indentation (indentation.hpp).
Vec3 boussinesq_displacement(const Material& m, double F, const Vec3& x);

/// The nodes of m whose coordinate `axis` equals `value` (within 1e-9 mm).
std::vector<Index> nodes_on_plane(const TetMesh& m, int axis, double value);

}  // namespace medspring::fem
