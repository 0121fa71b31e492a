// A rigid sphere indenting the FEM reference (docs/tools.md, docs/accuracy.md): the force–indentation
// curve of a frictionless rigid sphere pressed into a CalculiX body, for comparison with the Hertz law
// and with MedSpring's tools (issue 18).
//
//   fem::SphereIndentation s;
//   s.radius = 10; s.touch_centre = {0, 0, 10}; s.direction = {0, 0, -1}; s.depths = {0.1, 0.2, 0.4};
//   std::vector<fem::IndentationPoint> curve = fem::sphere_indentation(problem, s);   // force (N) per depth
//
// Contact is node-to-sphere with an active set: every boundary node inside the sphere gets its
// displacement along the indentation direction imposed so that it lies on the sphere (its lateral
// motion stays free: frictionless); after each CalculiX solve, nodes whose reaction pulls them towards
// the sphere are released and free nodes that ended inside it are added, until the set no longer
// changes. The force on the sphere is the sum of the contact nodes' reaction forces (CalculiX RF).
// Units: mm, N, MPa.
#pragma once

#include <functional>
#include <vector>

#include "medspring/fem/calculix.hpp"
#include "medspring/fem/validation.hpp"

namespace medspring::fem {

struct SphereIndentation {
  double radius = 5.0;               // R, mm
  Vec3 touch_centre = Vec3::Zero();  // sphere centre at depth 0 (first touch), mm
  Vec3 direction = Vec3(0, 0, -1);   // unit: the sphere moves along it, into the tissue
  std::vector<double> depths;        // indentation depths (mm), > 0, increasing
  double symmetry_factor = 1.0;      // force multiplier (4 for a quarter model on two symmetry planes)
  int max_iterations = 12;           // active-set iterations per depth
  double tolerance = 1e-3;           // mm: inside the sphere by more than this = penetrating
  // Called before every solve with the problem about to be solved and the current force estimate
  // (N, the previous iteration's; 0 at first): e.g. far-field boundary values of a half-space model.
  // With it, an iteration also converges only when the force changed by < 0.1 %.
  std::function<void(FemProblem& p, double force)> update_boundary;
};

struct IndentationPoint {
  double depth = 0;              // mm
  double force = 0;              // N: the pressing force on the sphere along `direction` (> 0 in contact)
  Vec3 reaction = Vec3::Zero();  // N: total force of the tissue on the sphere (x symmetry_factor)
  double contact_radius = 0;     // mm: largest distance of a contact node from the sphere's axis
  Index contact_nodes = 0;
  int iterations = 0;        // CalculiX solves for this depth
  bool converged = false;    // the active set settled within max_iterations
  double solve_seconds = 0;  // CalculiX wall time summed over the iterations
  MatX3 u;                   // displacement of the last solve (#N x 3, mm, original frame)
};

/// Force–indentation of a rigid frictionless sphere on `base` (mesh, material and supports; base's
/// own single-component constraints are kept and must be in a frame where `direction` is -z, i.e.
/// they are only allowed when direction = (0, 0, -1)). Boundary nodes that are fixed are never contact
/// nodes. Throws InvalidInput for bad settings (radius <= 0, direction zero, depths not positive and
/// increasing), SolverError when CalculiX fails.
std::vector<IndentationPoint> sphere_indentation(const FemProblem& base, const SphereIndentation& s,
                                                 const FemSettings& settings = {});

/// Hertz: force of a rigid sphere of radius R pressed by depth d into an elastic half-space,
/// F = 4/3 E/(1 - nu^2) sqrt(R) d^(3/2) (N, for E in MPa and lengths in mm).
double hertz_force(const Material& m, double R, double depth);

/// The sphere centre at first touch when it moves along `direction` on the axis through `axis_point`
/// towards the triangle surface (V, F): the highest position at which the sphere touches a triangle
/// (exact on a face's interior; edges and corners sampled on a barycentric grid of 24 x 24). Throws
/// InvalidInput if the axis misses.
Vec3 first_touch_centre(const MatX3& V, const MatX3i& F, double R, const Vec3& axis_point,
                        const Vec3& direction);

/// Principal curvatures (1/mm, positive for a convex surface seen from outside along -direction) of the
/// surface at `point`: a quadric z = (a x^2 + 2 b xy + c y^2) / 2 fitted by least squares to the vertices
/// within `radius` in the tangent frame whose normal is -direction.
std::pair<double, double> principal_curvatures(const MatX3& V, const Vec3& point, const Vec3& direction,
                                               double radius);

/// Validation of the indentation: a rigid sphere (R = 10 mm) on a thick block (quarter model, 20 mm, E =
/// 10 kPa, nu = 0.45), the far faces held at the Boussinesq point-load field of the FEM's own force
/// (iterated with the active set, so the block acts as a half-space); one result per depth (0.1, 0.2,
/// 0.4 mm at level >= 2; 0.2 mm at level 1) comparing the force with hertz_force.
std::vector<ValidationResult> validate_hertz(int level, const FemSettings& s = {});

}  // namespace medspring::fem
