// Procedural surfaces around a centerline, shared by the medial and models tests (ALGORITHMS.md §8.0).
#pragma once

#include <cmath>
#include <numbers>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/medial/frames.hpp"
#include "medspring/medial/reconstruction.hpp"

namespace medspring::testing {

/// Rest surface nodes P0_ij = C0_i + F0_i o_j of a structured tube (node i M + j), computed directly.
inline MatX3 structured_rest_nodes(const FrameReference& ref, const MatX3& offsets) {
  const Index n = ref.size(), M = static_cast<Index>(offsets.rows());
  MatX3 P(n * M, 3);
  for (Index i = 0; i < n; ++i)
    for (Index j = 0; j < M; ++j)
      P.row(i * M + j) = ref.C0.row(i) + (ref.F0.frame(i) * offsets.row(j).transpose()).transpose();
  return P;
}

/// A closed tube mesh around the rest centerline of `ref` with a different resolution than the atoms:
/// `per_segment` rings per atom segment (interpolated frames, §5.9), `spokes` nodes per ring with local
/// offsets (a cos th, b sin th, c sin 3 th), and one cap node at each end atom. Outward-oriented.
inline SurfaceMesh closed_tube_around(const FrameReference& ref, Index per_segment, Index spokes, double a,
                                      double b, double c = 0.0) {
  const Index n = ref.size();
  const Index rings = (n - 1) * per_segment + 1;
  SurfaceMesh m;
  m.V.resize(rings * spokes + 2, 3);
  for (Index r = 0; r < rings; ++r) {
    const Index i = std::min(r / per_segment, n - 2);
    const double lam = static_cast<double>(r - i * per_segment) / static_cast<double>(per_segment);
    const Mat3 F = interpolated_frame(ref.F0, i, lam);
    const Vec3 C = (1.0 - lam) * ref.C0.row(i).transpose() + lam * ref.C0.row(i + 1).transpose();
    for (Index j = 0; j < spokes; ++j) {
      const double th = 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(spokes);
      const Vec3 o(a * std::cos(th), b * std::sin(th), c * std::sin(3.0 * th));
      m.V.row(r * spokes + j) = (C + F * o).transpose();
    }
  }
  const Index c0 = rings * spokes, c1 = c0 + 1;
  m.V.row(c0) = ref.C0.row(0);
  m.V.row(c1) = ref.C0.row(n - 1);
  const MatX3i tube = tube_grid_faces(rings, spokes);
  m.F.resize(tube.rows() + 2 * spokes, 3);
  m.F.topRows(tube.rows()) = tube;
  for (Index j = 0; j < spokes; ++j) {
    const Index j1 = (j + 1) % spokes;
    m.F.row(tube.rows() + j) << c0, j1, j;
    m.F.row(tube.rows() + spokes + j) << c1, (rings - 1) * spokes + j, (rings - 1) * spokes + j1;
  }
  return m;
}

/// Rotation by `angle` (rad) about a unit axis.
inline Mat3 rotation(const Vec3& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

/// Applies x -> R x + b to every row.
inline MatX3 rigid(const MatX3& P, const Mat3& R, const Vec3& b) {
  MatX3 Q(P.rows(), 3);
  for (Index k = 0; k < P.rows(); ++k) Q.row(k) = (R * P.row(k).transpose() + b).transpose();
  return Q;
}

inline double max_row_distance(const MatX3& A, const MatX3& B) {
  return (A - B).rowwise().norm().maxCoeff();
}

}  // namespace medspring::testing
