// Exact Euclidean distance transform of binary volumes (ALGORITHMS.md §3.2) and trilinear sampling.
#pragma once

#include <cmath>
#include <cstdint>

#include "medspring/core/check.hpp"
#include "medspring/geometry/volume.hpp"

namespace medspring {

/// Distance from boundary (DFB) of a binary volume, ALGORITHMS.md §3.2.
struct DistanceField {
  /// mm, same grid as the input: for every object voxel, the Euclidean distance (anisotropic spacing
  /// honoured) from its centre to the centre of the nearest background voxel; 0 on background; +inf
  /// on every voxel when the volume holds no background voxel at all.
  ScalarVolume dfb;
  /// Squared EDT in voxel units (di^2 + dj^2 + dk^2, exact integers; 0 on background, INT32_MAX when
  /// there is no background). Filled only on isotropic grids (data empty otherwise): it gives exact
  /// DFB tie comparisons there (dfb = h * sqrt(squared_edt)).
  VolumeT<std::int32_t> squared_edt;
  bool isotropic = false;  // spacing equal on the three axes (relative 1e-12)
};

/// Exact separable EDT (Felzenszwalb & Huttenlocher 2012: lower envelope of parabolas, one pass per
/// axis with weight h_axis^2), O(#voxels). Throws InvalidInput for bad dims/spacing or data size.
DistanceField distance_from_boundary(const MaskVolume& mask);

/// Trilinear interpolation of a scalar volume at a continuous voxel coordinate (i, j, k); the
/// coordinate is clamped to the grid, so points outside take the value of the nearest border point.
double trilinear(const ScalarVolume& volume, const Vec3& ijk);

/// Trilinear interpolation at a world position (mm), through volume.to_index().
inline double sample_trilinear(const ScalarVolume& volume, const Vec3& world) {
  return trilinear(volume, volume.to_index(world));
}

/// Throws InvalidInput("<what>: ...") unless dims are positive, spacing is positive and finite,
/// direction is orthonormal (1e-6) and data holds nx*ny*nz values (at most 2^31 - 1).
template <class T>
void require_valid_volume(const VolumeT<T>& volume, const char* what) {
  for (int a = 0; a < 3; ++a) {
    require(volume.dims[a] > 0, what, ": dims[", a, "] must be > 0 (got ", volume.dims[a], ")");
    require(std::isfinite(volume.spacing[a]) && volume.spacing[a] > 0, what, ": spacing[", a,
            "] must be > 0 (got ", volume.spacing[a], ")");
  }
  require(volume.origin.allFinite(), what, ": origin must be finite");
  require(
      volume.direction.allFinite() &&
          (volume.direction.transpose() * volume.direction - Mat3::Identity()).cwiseAbs().maxCoeff() < 1e-6,
      what, ": direction must be an orthonormal matrix");
  const double n = static_cast<double>(volume.dims[0]) * volume.dims[1] * volume.dims[2];
  require(n <= 2147483647.0, what, ": ", n, " voxels exceed the limit of 2^31 - 1");
  require(volume.data.size() == volume.size(), what, ": data holds ", volume.data.size(),
          " values, dims need ", volume.size());
}

}  // namespace medspring
