// Distances between two triangle surfaces: symmetric Hausdorff and mean surface distance, from
// dense samples on each surface and exact point-to-triangle distances to the other (CGAL AABB tree).
#pragma once

#include "medspring/geometry/surface_mesh.hpp"

namespace medspring {

struct SurfaceDistanceSettings {
  /// Sample spacing on each surface, mm (vertices plus a barycentric grid on every triangle).
  /// 0 = 1/250 of the larger bounding-box diagonal. The sampled Hausdorff distance is a lower
  /// bound of the true one, short of it by at most about the spacing.
  double sample_spacing = 0.0;
};

struct SurfaceDistance {
  double a_to_b_max = 0.0, b_to_a_max = 0.0;    // one-sided Hausdorff distances, mm
  double a_to_b_mean = 0.0, b_to_a_mean = 0.0;  // area-weighted mean distances, mm
  double hausdorff = 0.0;                       // max of the two one-sided maxima, mm
  double mean = 0.0;                            // average of the two one-sided means, mm
  Index samples = 0;                            // sample points used on both surfaces together
};

/// Distances between surfaces a and b (any triangle meshes, open or closed). Throws InvalidInput
/// when either mesh is empty or has invalid indices.
SurfaceDistance surface_distance(const SurfaceMesh& a, const SurfaceMesh& b,
                                 const SurfaceDistanceSettings& settings = {});

/// Exact distance (mm) from each point (#P x 3) to the nearest point of `surface`'s triangles.
VecX distances_to_surface(const MatX3& points, const SurfaceMesh& surface);

/// The nearest point of `surface`'s triangles to each point (#P x 3), mm.
MatX3 closest_points_on_surface(const MatX3& points, const SurfaceMesh& surface);

/// The sample points surface_distance uses on `s` (every triangle's barycentric grid of `spacing` mm,
/// corners included), with each sample's share of its triangle's area in *weights (if given). Throws
/// InvalidInput for an empty or invalid mesh or a spacing <= 0.
MatX3 surface_samples(const SurfaceMesh& s, double spacing, VecX* weights = nullptr);

/// surface_distance(a, b, settings).hausdorff: the symmetric Hausdorff distance, mm.
double hausdorff_distance(const SurfaceMesh& a, const SurfaceMesh& b,
                          const SurfaceDistanceSettings& settings = {});

}  // namespace medspring
