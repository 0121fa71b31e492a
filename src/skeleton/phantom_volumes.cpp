#include "medspring/skeleton/phantom_volumes.hpp"

#include <algorithm>
#include <cmath>

#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"

namespace medspring {

MaskVolume quarter_torus_volume(const QuarterTorusShape& s) {
  require_positive(s.R, "quarter_torus_volume: R");
  require_positive(s.r, "quarter_torus_volume: r");
  require_positive(s.h, "quarter_torus_volume: h");
  require(s.r < s.R, "quarter_torus_volume: r must be < R (got r = ", s.r, ", R = ", s.R, ")");
  MaskVolume v;
  const Index nxy = static_cast<Index>(std::ceil((s.R + s.r) / s.h)) + 3;
  const Index half_z = static_cast<Index>(std::ceil(s.r / s.h)) + 2;
  v.dims = {nxy, nxy, 2 * half_z + 1};
  v.spacing = Vec3::Constant(s.h);
  v.origin = Vec3(0.0, 0.0, -s.h * static_cast<double>(half_z));
  v.data.assign(v.size(), 0);
  for (Index k = 0; k < v.dims[2]; ++k)
    for (Index j = 0; j < v.dims[1]; ++j)
      for (Index i = 0; i < v.dims[0]; ++i) {
        const Vec3 p = v.to_world(Vec3(i, j, k));
        const double d = std::hypot(p.x(), p.y()) - s.R;
        if (d * d + p.z() * p.z() <= s.r * s.r) v.at(i, j, k) = 1;
      }
  return v;
}

MaskVolume ellipsoid_volume(const EllipsoidShape& s) {
  for (int a = 0; a < 3; ++a) require_positive(s.semi_axes[a], "ellipsoid_volume: semi-axis");
  require_positive(s.h, "ellipsoid_volume: h");
  MaskVolume v;
  std::array<Index, 3> half{};
  for (int a = 0; a < 3; ++a) {
    half[a] = static_cast<Index>(std::floor(s.semi_axes[a] / s.h)) + 2;
    v.dims[a] = 2 * half[a] + 1;
    v.origin[a] = -s.h * static_cast<double>(half[a]);
  }
  v.spacing = Vec3::Constant(s.h);
  v.data.assign(v.size(), 0);
  const double a2 = s.semi_axes[0] * s.semi_axes[0], b2 = s.semi_axes[1] * s.semi_axes[1],
               c2 = s.semi_axes[2] * s.semi_axes[2];
  for (Index k = 0; k < v.dims[2]; ++k)
    for (Index j = 0; j < v.dims[1]; ++j)
      for (Index i = 0; i < v.dims[0]; ++i) {
        const double x = s.h * static_cast<double>(i - half[0]), y = s.h * static_cast<double>(j - half[1]),
                     z = s.h * static_cast<double>(k - half[2]);
        if (x * x * b2 * c2 + y * y * a2 * c2 + z * z * a2 * b2 <= a2 * b2 * c2) v.at(i, j, k) = 1;
      }
  return v;
}

MaskVolume kidney_phantom_volume(const VoxelizeSettings& settings) {
  return voxelize(kidney_phantom(), settings);
}

MaskVolume tube_volume(const MatX3& path, double radius, const std::array<Index, 3>& dims,
                       const Vec3& spacing, const Vec3& origin) {
  require(path.rows() >= 1, "tube_volume: path needs at least one point");
  require_finite_points(path, "tube_volume: path");
  require_positive(radius, "tube_volume: radius");
  MaskVolume v;
  v.dims = dims;
  v.spacing = spacing;
  v.origin = origin;
  for (int a = 0; a < 3; ++a) {
    require(dims[a] > 0, "tube_volume: dims[", a, "] must be > 0 (got ", dims[a], ")");
    require_positive(spacing[a], "tube_volume: spacing");
  }
  v.data.assign(v.size(), 0);
  const double r2 = radius * radius;
  for (Index s = 0; s < std::max<Index>(1, static_cast<Index>(path.rows()) - 1); ++s) {
    const Vec3 A = path.row(s).transpose();
    const Vec3 B = path.row(std::min<Index>(s + 1, static_cast<Index>(path.rows()) - 1)).transpose();
    const Vec3 lo = A.cwiseMin(B).array() - radius, hi = A.cwiseMax(B).array() + radius;
    std::array<Index, 3> i0{}, i1{};
    for (int a = 0; a < 3; ++a) {
      i0[a] = std::max<Index>(0, static_cast<Index>(std::ceil((lo[a] - origin[a]) / spacing[a])));
      i1[a] = std::min<Index>(dims[a] - 1, static_cast<Index>(std::floor((hi[a] - origin[a]) / spacing[a])));
    }
    const Vec3 AB = B - A;
    const double ab2 = AB.squaredNorm();
    for (Index k = i0[2]; k <= i1[2]; ++k)
      for (Index j = i0[1]; j <= i1[1]; ++j)
        for (Index i = i0[0]; i <= i1[0]; ++i) {
          const Vec3 p = v.to_world(Vec3(i, j, k));
          const double t = ab2 > 0 ? std::clamp((p - A).dot(AB) / ab2, 0.0, 1.0) : 0.0;
          if ((A + t * AB - p).squaredNorm() <= r2) v.at(i, j, k) = 1;
        }
  }
  return v;
}

}  // namespace medspring
