// Labelled 3D image volumes (segmentations) in physical coordinates.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

/// A scalar volume with voxel spacing, origin and orientation. Voxel (i,j,k) has linear index
/// i + nx*(j + ny*k) and its centre at origin + direction * (spacing .* (i,j,k)), in mm.
template <class T>
struct VolumeT {
  std::array<Index, 3> dims{0, 0, 0};  // nx, ny, nz
  Vec3 spacing = Vec3::Ones();         // mm
  Vec3 origin = Vec3::Zero();          // mm, centre of voxel (0,0,0)
  Mat3 direction = Mat3::Identity();   // columns: world directions of the i, j, k axes
  std::vector<T> data;                 // nx*ny*nz values

  std::size_t size() const { return static_cast<std::size_t>(dims[0]) * dims[1] * dims[2]; }
  std::size_t index(Index i, Index j, Index k) const {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(dims[0]) *
               (static_cast<std::size_t>(j) + static_cast<std::size_t>(dims[1]) * k);
  }
  T& at(Index i, Index j, Index k) { return data[index(i, j, k)]; }
  const T& at(Index i, Index j, Index k) const { return data[index(i, j, k)]; }
  bool inside(Index i, Index j, Index k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < dims[0] && j < dims[1] && k < dims[2];
  }
  /// World position (mm) of a continuous voxel coordinate.
  Vec3 to_world(const Vec3& ijk) const { return origin + direction * spacing.cwiseProduct(ijk); }
  /// Continuous voxel coordinate of a world position (mm).
  Vec3 to_index(const Vec3& p) const { return (direction.transpose() * (p - origin)).cwiseQuotient(spacing); }
};

using LabelVolume = VolumeT<std::int32_t>;  // label image (0 = background)
using MaskVolume = VolumeT<std::uint8_t>;   // binary mask (1 = object)
using ScalarVolume = VolumeT<double>;       // distance maps etc.

/// Binary mask of voxels equal to `label` (or > 0 if label < 0).
MaskVolume select_label(const LabelVolume& labels, std::int32_t label);

}  // namespace medspring
