// Voxel phantoms of ALGORITHMS.md §3.8 and §8.0 for tests and benchmarks.
#pragma once

#include <array>

#include "medspring/core/types.hpp"
#include "medspring/geometry/volume.hpp"
#include "medspring/skeleton/voxelize.hpp"

namespace medspring {

/// Quarter-torus tube of §3.8: centerline = arc of radius R in the xy-plane about the origin from
/// (R, 0, 0) to (0, R, 0); voxel centres within r of the arc's circle are object (<= r). The grid has
/// spacing h with voxel centres at x, y = 0, h, 2h, ... (so the volume border x = 0 and y = 0 cuts the
/// tube at both ends, perpendicular to the arc) and z symmetric about 0, with >= 2 background voxels
/// beyond the tube elsewhere.
struct QuarterTorusShape {
  double R = 40.0;  // mm, centerline radius
  double r = 5.0;   // mm, tube radius
  double h = 0.5;   // mm, voxel spacing
};
MaskVolume quarter_torus_volume(const QuarterTorusShape& shape = {});

/// Solid ellipsoid of §3.8 centred at the origin: voxel centres with (x/a)^2 + (y/b)^2 + (z/c)^2 <= 1
/// (evaluated as x^2 b^2 c^2 + ... <= a^2 b^2 c^2, exact on integer grids), grid symmetric about the
/// origin with voxel centres at multiples of h and 2 background voxels beyond the tips.
struct EllipsoidShape {
  Vec3 semi_axes{40.0, 20.0, 15.0};  // mm, (a, b, c)
  double h = 1.0;                    // mm, voxel spacing
};
MaskVolume ellipsoid_volume(const EllipsoidShape& shape = {});

/// The kidney phantom mesh (geometry/phantoms.hpp) voxelised by voxelize() (§3.6 defaults: h_v =
/// smallest extent / 48 = 0.75 mm).
MaskVolume kidney_phantom_volume(const VoxelizeSettings& settings = {});

/// Voxel centres within `radius` (mm) of a polyline `path` (#P x 3, world mm) on the grid given by
/// dims, spacing and origin (identity direction): a tube of any shape, e.g. cut by the volume border.
MaskVolume tube_volume(const MatX3& path, double radius, const std::array<Index, 3>& dims,
                       const Vec3& spacing, const Vec3& origin);

}  // namespace medspring
