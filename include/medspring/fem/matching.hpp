// Matched boundary conditions between the FEM reference and a spring model (docs/accuracy.md):
// a support region picked by one rule on both surfaces, a load spread over a contact disk with the same
// total force and the same distribution (uniform traction over the disk), and the FEM displacement
// sampled at the spring model's surface nodes.
#pragma once

#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/fem/tet_mesh.hpp"

namespace medspring::fem {

/// Support rule: the points of P (candidates, or all when empty) within `depth` (mm) of the extreme
/// point along `direction` (measured along the direction: a slab behind the plane of the extreme point).
std::vector<Index> points_near_extreme(const MatX3& P, const Vec3& direction, double depth,
                                       const std::vector<Index>& candidates = {});

/// Consistent nodal forces of a uniform traction over the disk |x - centre| < a on a surface of linear
/// triangles (V, F): f_i = sum over faces of the integral of N_i t dA, computed on 256 sub-triangles
/// per face (16 x 16), then scaled so that the forces sum to `force` exactly. Returns #V x 3 (N). Throws
/// InvalidInput when the disk touches no face.
MatX3 disk_load_linear(const MatX3& V, const MatX3i& F, const Vec3& centre, double a, const Vec3& force);

/// The same on the 6-node boundary triangles of a quadratic tet mesh (quadratic shape functions):
/// returns the nonzero nodal forces.
std::vector<std::pair<Index, Vec3>> disk_load_quadratic(const TetMesh& mesh, const MatX6i& boundary,
                                                        const Vec3& centre, double a, const Vec3& force);

/// Consistent nodal forces of a uniform traction over the given 6-node faces (a subset of the boundary),
/// summing to `total` (N): for a quadratic triangle the corners carry none, each mid-edge node a third.
std::vector<std::pair<Index, Vec3>> uniform_traction(const TetMesh& mesh, const MatX6i& faces,
                                                     const Vec3& total);

/// The rows of `boundary` whose corners all lie within tol (mm) of the plane x(axis) = value.
MatX6i faces_on_plane(const TetMesh& mesh, const MatX6i& boundary, int axis, double value, double tol = 1e-9);

/// Where each point lies on the FEM boundary: the nearest boundary face (flat corner triangle) and the
/// barycentric coordinates of the nearest point on it.
struct BoundarySample {
  std::vector<Index> face;
  MatX3 bary;     // (#P x 3)
  VecX distance;  // mm, from the point to its nearest boundary point
};
BoundarySample locate_on_boundary(const TetMesh& mesh, const MatX6i& boundary, const MatX3& points);

/// Nodal field u (#N x 3) interpolated at the samples with the quadratic face shape functions.
MatX3 interpolate(const MatX6i& boundary, const BoundarySample& s, const MatX3& u);

}  // namespace medspring::fem
