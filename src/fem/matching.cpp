#include "medspring/fem/matching.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"

namespace medspring::fem {

namespace {

constexpr int kSub = 16;  // sub-divisions per edge: 256 sub-triangles per face

// Calls f(l0, l1, l2, weight) at the centroids of the kSub^2 sub-triangles (weights sum to 1).
template <class F>
void for_each_subtriangle(F&& f) {
  const double h = 1.0 / kSub, w = 1.0 / (kSub * kSub);
  for (int i = 0; i < kSub; ++i)
    for (int j = 0; i + j < kSub; ++j) {
      f((i + 1.0 / 3.0) * h, (j + 1.0 / 3.0) * h, w);                        // upward sub-triangle
      if (i + j + 1 < kSub) f((i + 2.0 / 3.0) * h, (j + 2.0 / 3.0) * h, w);  // downward one
    }
}

void check_disk(const Vec3& centre, double a, const Vec3& force) {
  require(centre.allFinite(), "disk load: centre must be finite");
  require(std::isfinite(a) && a > 0, "disk load: radius must be > 0 (got ", a, " mm)");
  require(force.allFinite(), "disk load: force must be finite");
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5): barycentrics.
Vec3 closest_bary(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return {1 - v - w, v, w};
}

// Quadratic 6-node triangle shape functions (corners 0-2, mid-edges 01 12 20).
Eigen::Matrix<double, 6, 1> shape6(double l0, double l1, double l2) {
  Eigen::Matrix<double, 6, 1> N;
  N << l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1), 4 * l0 * l1, 4 * l1 * l2, 4 * l2 * l0;
  return N;
}

}  // namespace

std::vector<Index> points_near_extreme(const MatX3& P, const Vec3& direction, double depth,
                                       const std::vector<Index>& candidates) {
  require(direction.allFinite() && direction.norm() > 0, "support rule: direction must be non-zero");
  require(std::isfinite(depth) && depth >= 0, "support rule: depth must be >= 0 (got ", depth, " mm)");
  std::vector<Index> cand = candidates;
  if (cand.empty())
    for (Index i = 0; i < P.rows(); ++i) cand.push_back(i);
  const Vec3 d = direction.normalized();
  double top = -std::numeric_limits<double>::infinity();
  for (Index i : cand) {
    require(i >= 0 && i < P.rows(), "support rule: candidate ", i, " out of range");
    top = std::max(top, P.row(i).dot(d));
  }
  std::vector<Index> out;
  for (Index i : cand)
    if (P.row(i).dot(d) >= top - depth) out.push_back(i);
  return out;
}

MatX3 disk_load_linear(const MatX3& V, const MatX3i& F, const Vec3& centre, double a, const Vec3& force) {
  check_disk(centre, a, force);
  MatX3 f = MatX3::Zero(V.rows(), 3);
  double total = 0;
  for (Index t = 0; t < F.rows(); ++t) {
    const Vec3 p0 = V.row(F(t, 0)), p1 = V.row(F(t, 1)), p2 = V.row(F(t, 2));
    const double area = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    if ((p0 - centre).norm() > a + (p1 - p0).norm() + (p2 - p0).norm()) continue;
    for_each_subtriangle([&](double l1, double l2, double w) {
      const double l0 = 1 - l1 - l2;
      const Vec3 x = l0 * p0 + l1 * p1 + l2 * p2;
      if ((x - centre).norm() >= a) return;
      const double dA = w * area;
      f.row(F(t, 0)) += l0 * dA * force.transpose();
      f.row(F(t, 1)) += l1 * dA * force.transpose();
      f.row(F(t, 2)) += l2 * dA * force.transpose();
      total += dA;
    });
  }
  if (!(total > 0)) throw InvalidInput(cat("disk load: the disk of radius ", a, " mm touches no surface"));
  f /= total;
  return f;
}

std::vector<std::pair<Index, Vec3>> disk_load_quadratic(const TetMesh& mesh, const MatX6i& B,
                                                        const Vec3& centre, double a, const Vec3& force) {
  check_disk(centre, a, force);
  std::vector<double> w(static_cast<std::size_t>(mesh.num_nodes()), 0.0);
  double total = 0;
  for (Index t = 0; t < B.rows(); ++t) {
    const Vec3 p0 = mesh.X.row(B(t, 0)), p1 = mesh.X.row(B(t, 1)), p2 = mesh.X.row(B(t, 2));
    const double area = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    if ((p0 - centre).norm() > a + (p1 - p0).norm() + (p2 - p0).norm()) continue;
    for_each_subtriangle([&](double l1, double l2, double wt) {
      const double l0 = 1 - l1 - l2;
      const Vec3 x = l0 * p0 + l1 * p1 + l2 * p2;
      if ((x - centre).norm() >= a) return;
      const auto N = shape6(l0, l1, l2);
      for (int k = 0; k < 6; ++k) w[static_cast<std::size_t>(B(t, k))] += N(k) * wt * area;
      total += wt * area;
    });
  }
  if (!(total > 0)) throw InvalidInput(cat("disk load: the disk of radius ", a, " mm touches no surface"));
  std::vector<std::pair<Index, Vec3>> out;
  for (std::size_t i = 0; i < w.size(); ++i)
    if (w[i] != 0.0) out.emplace_back(static_cast<Index>(i), (w[i] / total) * force);
  return out;
}

std::vector<std::pair<Index, Vec3>> uniform_traction(const TetMesh& mesh, const MatX6i& faces,
                                                     const Vec3& total) {
  require(total.allFinite(), "uniform traction: force must be finite");
  std::vector<double> w(static_cast<std::size_t>(mesh.num_nodes()), 0.0);
  double area = 0;
  for (Index t = 0; t < faces.rows(); ++t) {
    const Vec3 p0 = mesh.X.row(faces(t, 0)), p1 = mesh.X.row(faces(t, 1)), p2 = mesh.X.row(faces(t, 2));
    const double A = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    for (int k = 3; k < 6; ++k) w[static_cast<std::size_t>(faces(t, k))] += A / 3.0;
    area += A;
  }
  require(area > 0, "uniform traction: no face area");
  std::vector<std::pair<Index, Vec3>> out;
  for (std::size_t i = 0; i < w.size(); ++i)
    if (w[i] != 0.0) out.emplace_back(static_cast<Index>(i), (w[i] / area) * total);
  return out;
}

MatX6i faces_on_plane(const TetMesh& mesh, const MatX6i& boundary, int axis, double value, double tol) {
  require(axis >= 0 && axis <= 2, "faces_on_plane: axis must be 0, 1 or 2");
  std::vector<Index> rows;
  for (Index t = 0; t < boundary.rows(); ++t) {
    bool on = true;
    for (int k = 0; k < 3; ++k) on = on && std::abs(mesh.X(boundary(t, k), axis) - value) <= tol;
    if (on) rows.push_back(t);
  }
  MatX6i out(static_cast<Index>(rows.size()), 6);
  for (std::size_t i = 0; i < rows.size(); ++i) out.row(static_cast<Index>(i)) = boundary.row(rows[i]);
  return out;
}

BoundarySample locate_on_boundary(const TetMesh& mesh, const MatX6i& B, const MatX3& points) {
  require(B.rows() > 0, "boundary sample: no boundary faces");
  BoundarySample s;
  const Index n = static_cast<Index>(points.rows());
  s.face.assign(static_cast<std::size_t>(n), 0);
  s.bary.resize(n, 3);
  s.distance.resize(n);
  for (Index i = 0; i < n; ++i) {
    const Vec3 p = points.row(i);
    double best = std::numeric_limits<double>::infinity();
    for (Index t = 0; t < B.rows(); ++t) {
      const Vec3 a = mesh.X.row(B(t, 0)), b = mesh.X.row(B(t, 1)), c = mesh.X.row(B(t, 2));
      // cheap reject: distance to the corner a minus the two edge lengths
      const double lb = (p - a).norm() - (b - a).norm() - (c - a).norm();
      if (lb > best) continue;
      const Vec3 l = closest_bary(p, a, b, c);
      const double d = (p - (l(0) * a + l(1) * b + l(2) * c)).norm();
      if (d < best) {
        best = d;
        s.face[static_cast<std::size_t>(i)] = t;
        s.bary.row(i) = l.transpose();
      }
    }
    s.distance(i) = best;
  }
  return s;
}

MatX3 interpolate(const MatX6i& B, const BoundarySample& s, const MatX3& u) {
  const Index n = static_cast<Index>(s.bary.rows());
  MatX3 out(n, 3);
  for (Index i = 0; i < n; ++i) {
    const Index t = s.face[static_cast<std::size_t>(i)];
    const auto N = shape6(s.bary(i, 0), s.bary(i, 1), s.bary(i, 2));
    out.row(i).setZero();
    for (int k = 0; k < 6; ++k) out.row(i) += N(k) * u.row(B(t, k));
  }
  return out;
}

}  // namespace medspring::fem
