// Basic numeric types of MedSpring. Units throughout: mm, g, ms, N (see docs/units.md).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

namespace medspring {

using Index = int;  // node, spring and element indices (models up to ~2^31 elements)

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using VecX = Eigen::VectorXd;
using VecXi = Eigen::VectorXi;

/// #N by 3 list of points, row-major: xyz interleaved, so a flat 3N vector and a NumPy (N,3) view
/// share its memory without copy.
using MatX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// #F by 3 list of triangle vertex indices.
using MatX3i = Eigen::Matrix<Index, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// #E by 2 list of edge (spring) end indices.
using MatX2i = Eigen::Matrix<Index, Eigen::Dynamic, 2, Eigen::RowMajor>;

/// A flat 3N view of a #N by 3 point list.
inline Eigen::Map<VecX> flat(MatX3& P) {
  return {P.data(), P.size()};
}
inline Eigen::Map<const VecX> flat(const MatX3& P) {
  return {P.data(), P.size()};
}

}  // namespace medspring
