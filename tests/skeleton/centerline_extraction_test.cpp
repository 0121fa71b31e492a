#include "medspring/skeleton/centerline_extraction.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>

#include "medspring/core/error.hpp"
#include "medspring/skeleton/distance_transform.hpp"
#include "medspring/skeleton/phantom_volumes.hpp"

namespace medspring {
namespace {

constexpr double kPi = std::numbers::pi;

std::array<Index, 3> ijk_of(const MaskVolume& m, Index lin) {
  return {lin % m.dims[0], (lin / m.dims[0]) % m.dims[1], lin / (m.dims[0] * m.dims[1])};
}

/// Largest |step| (Chebyshev) and L1 step between consecutive path voxels.
std::pair<Index, Index> max_steps(const MaskVolume& m, const std::vector<Index>& path) {
  Index cheb = 0, l1 = 0;
  for (std::size_t q = 1; q < path.size(); ++q) {
    const auto a = ijk_of(m, path[q - 1]), b = ijk_of(m, path[q]);
    Index c = 0, s = 0;
    for (int d = 0; d < 3; ++d) {
      c = std::max(c, std::abs(a[d] - b[d]));
      s += std::abs(a[d] - b[d]);
    }
    cheb = std::max(cheb, c);
    l1 = std::max(l1, s);
  }
  return {cheb, l1};
}

/// Arc length of every atom along `curve`, found independently (nearest point on the polyline).
std::vector<double> atom_arc_positions(const SkeletonResult& r) {
  const MatX3& C = r.curve;
  std::vector<double> S(C.rows(), 0.0);
  for (Index i = 1; i < C.rows(); ++i) S[i] = S[i - 1] + (C.row(i) - C.row(i - 1)).norm();
  std::vector<double> out;
  for (Index a = 0; a < r.atoms.rows(); ++a) {
    const Vec3 p = r.atoms.row(a).transpose();
    double best = 1e300, s_best = 0.0;
    for (Index i = 0; i + 1 < C.rows(); ++i) {
      const Vec3 A = C.row(i).transpose(), B = C.row(i + 1).transpose();
      const double len2 = (B - A).squaredNorm();
      const double t = len2 > 0 ? std::clamp((p - A).dot(B - A) / len2, 0.0, 1.0) : 0.0;
      const double d = (A + t * (B - A) - p).norm();
      if (d < best) {
        best = d;
        s_best = S[i] + t * std::sqrt(len2);
      }
    }
    EXPECT_LT(best, 1e-9) << "atom " << a << " is not on the curve";
    out.push_back(s_best);
  }
  return out;
}

void expect_even_spacing(const SkeletonResult& r) {
  const std::vector<double> s = atom_arc_positions(r);
  const double mean = (s.back() - s.front()) / static_cast<double>(s.size() - 1);
  for (std::size_t i = 1; i < s.size(); ++i)
    EXPECT_NEAR(s[i] - s[i - 1], mean, 1e-9 * mean) << "atom spacing " << i;
}

double torus_deviation(const Vec3& p, double R) {
  return std::hypot(std::hypot(p.x(), p.y()) - R, p.z());
}
double torus_arc_from_ends(const Vec3& p, double R) {
  const double ang = std::atan2(p.y(), p.x());
  return R * std::min(ang, kPi / 2 - ang);
}

void expect_bit_identical(const SkeletonResult& a, const SkeletonResult& b) {
  ASSERT_EQ(a.atoms.rows(), b.atoms.rows());
  EXPECT_TRUE((a.atoms.array() == b.atoms.array()).all());
  EXPECT_TRUE((a.radii.array() == b.radii.array()).all());
  EXPECT_EQ(a.path_voxels, b.path_voxels);
  ASSERT_EQ(a.curve.rows(), b.curve.rows());
  EXPECT_TRUE((a.curve.array() == b.curve.array()).all());
  ASSERT_EQ(a.smoothed.rows(), b.smoothed.rows());
  EXPECT_TRUE((a.smoothed.array() == b.smoothed.array()).all());
  EXPECT_EQ(a.notes, b.notes);
}

std::string what_of(const MaskVolume& m, const SkeletonSettings& s = {}) {
  try {
    extract_centerline(m, s);
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "(no exception)";
}

// ---- ALGORITHMS.md §8.5 check 22 ----
TEST(CenterlineExtraction, QuarterTorusCenterlineWithinHalfVoxelOfArcAndRadiusWithinHalfMm) {
  const QuarterTorusShape shape;  // R 40, r 5, h 0.5
  const MaskVolume m = quarter_torus_volume(shape);
  const SkeletonResult r = extract_centerline(m);
  ASSERT_EQ(r.atoms.rows(), 40);
  ASSERT_EQ(r.open_end_sizes.size(), 2u);
  EXPECT_EQ(r.ends[0].kind, EndKind::Open);
  EXPECT_EQ(r.ends[1].kind, EndKind::Open);
  EXPECT_EQ(r.ends[0].trimmed, 0.0);  // D-8: open ends are not trimmed
  EXPECT_EQ(r.ends[1].trimmed, 0.0);
  // D-6: the two cut faces, centroid (R, 0, 0) and (0, R, 0), in either order
  const double x0 = r.ends[0].position.x(), x1 = r.ends[1].position.x();
  EXPECT_NEAR(std::max(x0, x1), shape.R, 1e-12);
  EXPECT_NEAR(std::min(x0, x1), 0.0, 1e-12);

  double max_dev = 0.0, max_interior = 0.0;
  for (Index i = 0; i < r.curve.rows(); ++i) {
    const Vec3 p = r.curve.row(i).transpose();
    const double d = torus_deviation(p, shape.R);
    max_dev = std::max(max_dev, d);
    if (torus_arc_from_ends(p, shape.R) >= 2 * shape.r) max_interior = std::max(max_interior, d);
  }
  for (Index i = 0; i < r.atoms.rows(); ++i)
    max_dev = std::max(max_dev, torus_deviation(r.atoms.row(i).transpose(), shape.R));
  EXPECT_LE(max_dev, 0.5);  // one voxel (prototype: 0.25 everywhere, 0.08 interior)

  double rmin = 1e9, rmax = 0.0;
  for (Index i = 0; i < r.atoms.rows(); ++i) {
    if (torus_arc_from_ends(r.atoms.row(i).transpose(), shape.R) < 2 * shape.r) continue;
    rmin = std::min(rmin, r.radii[i]);
    rmax = std::max(rmax, r.radii[i]);
    EXPECT_NEAR(r.radii[i], shape.r, 0.5) << "atom " << i;
  }
  std::printf(
      "[ figures  ] quarter torus: max deviation %.4f mm, interior %.4f mm, interior radius %.3f..%.3f mm\n",
      max_dev, max_interior, rmin, rmax);
  expect_even_spacing(r);
}

// ---- §8.5 check 23 ----
TEST(CenterlineExtraction, EllipsoidEndpointsNearTipsAndPathOnMedialSheet) {
  const EllipsoidShape shape;  // (40, 20, 15), h 1
  const MaskVolume m = ellipsoid_volume(shape);
  const SkeletonResult r = extract_centerline(m);
  EXPECT_TRUE(r.open_end_sizes.empty());
  EXPECT_EQ(r.ends[0].kind, EndKind::Closed);
  EXPECT_EQ(r.ends[1].kind, EndKind::Closed);
  // double-sweep endpoints before trimming: one near each tip
  const double a = shape.semi_axes.x();
  EXPECT_GE(std::abs(r.ends[0].position.x()), 0.9 * a);
  EXPECT_GE(std::abs(r.ends[1].position.x()), 0.9 * a);
  EXPECT_LT(r.ends[0].position.x() * r.ends[1].position.x(), 0.0);
  EXPECT_GT(r.ends[0].trimmed, 0.0);  // D-8: closed tips are trimmed
  EXPECT_GT(r.ends[1].trimmed, 0.0);

  // inner 70 % of the extracted centerline (atoms are evenly spaced by arc length)
  double max_y = 0.0, max_z = 0.0;
  const Index n = static_cast<Index>(r.atoms.rows());
  for (Index i = 0; i < n; ++i) {
    const double f = static_cast<double>(i) / static_cast<double>(n - 1);
    if (f < 0.15 || f > 0.85) continue;
    max_y = std::max(max_y, std::abs(r.atoms(i, 1)));
    max_z = std::max(max_z, std::abs(r.atoms(i, 2)));
  }
  EXPECT_LE(max_z, 1.0);
  EXPECT_LE(max_y, 3.0);
  // the same on the dense smoothed path, inner 70 % of its arc length
  const MatX3& Q = r.smoothed;
  std::vector<double> S(Q.rows(), 0.0);
  for (Index i = 1; i < Q.rows(); ++i) S[i] = S[i - 1] + (Q.row(i) - Q.row(i - 1)).norm();
  double sy = 0.0, sz = 0.0;
  for (Index i = 0; i < Q.rows(); ++i) {
    if (S[i] < 0.15 * S.back() || S[i] > 0.85 * S.back()) continue;
    sy = std::max(sy, std::abs(Q(i, 1)));
    sz = std::max(sz, std::abs(Q(i, 2)));
  }
  EXPECT_LE(sz, 1.0);
  EXPECT_LE(sy, 3.0);
  std::printf(
      "[ figures  ] ellipsoid: endpoints x = %.1f, %.1f; inner 70%%: atoms |y| <= %.3f |z| <= %.3f, "
      "smoothed path |y| <= %.3f |z| <= %.3f\n",
      r.ends[0].position.x(), r.ends[1].position.x(), max_y, max_z, sy, sz);
  expect_even_spacing(r);
}

// ---- §8.5 check 26 ----
TEST(CenterlineExtraction, TwoRunsAreBitIdentical) {
  const MaskVolume torus = quarter_torus_volume();
  expect_bit_identical(extract_centerline(torus), extract_centerline(torus));
  const MaskVolume kidney = kidney_phantom_volume();
  const SkeletonSettings s{.atom_count = 42};
  expect_bit_identical(extract_centerline(kidney, s), extract_centerline(kidney, s));
  const SkeletonSettings pd{.path_method = PathMethod::PenalizedDijkstra};
  const MaskVolume ellipsoid = ellipsoid_volume();
  expect_bit_identical(extract_centerline(ellipsoid, pd), extract_centerline(ellipsoid, pd));
}

/// A closed, wiggly tube of varying radius (isotropic h = 1), used for the D-7 tree property.
MaskVolume wiggly_tube() {
  MaskVolume m;
  m.dims = {54, 26, 22};
  m.data.assign(m.size(), 0);
  for (Index k = 0; k < m.dims[2]; ++k)
    for (Index j = 0; j < m.dims[1]; ++j)
      for (Index i = 0; i < m.dims[0]; ++i)
        for (double t = 5.0; t <= 44.0; t += 0.25) {
          const Vec3 c(t + 2.0, 13.0 + 3.0 * std::sin(t / 5.0), 11.0 + 2.0 * std::cos(t / 7.0));
          const double rad = 3.2 + 1.6 * std::sin(t / 3.0);
          if ((Vec3(i, j, k) - c).norm() <= rad) {
            m.at(i, j, k) = 1;
            break;
          }
        }
  return m;
}

TEST(CenterlineExtraction, TreePathMaximisesTheSmallestDfbBetweenAnyTwoOfItsVoxels) {
  // D-7: the path of a maximum spanning tree is a bottleneck (maximin) path between any two of its
  // voxels. Reference: the largest level t such that both voxels are connected through voxels with
  // squared EDT >= t (union-find over decreasing levels).
  const MaskVolume m = wiggly_tube();
  const SkeletonResult r = extract_centerline(m);
  ASSERT_TRUE(r.open_end_sizes.empty());
  const DistanceField df = distance_from_boundary(m);  // closed object: same DFB as the padded one
  const std::vector<std::int32_t>& L = df.squared_edt.data;
  const std::vector<Index>& path = r.path_voxels;
  ASSERT_GT(path.size(), 30u);

  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t a = 0; a < path.size(); a += 7)
    for (std::size_t b = a + 3; b < path.size(); b += 11) pairs.emplace_back(a, b);
  pairs.emplace_back(0, path.size() - 1);

  std::vector<Index> order;
  for (Index v = 0; v < static_cast<Index>(m.size()); ++v)
    if (m.data[v]) order.push_back(v);
  std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) { return L[a] > L[b]; });
  std::vector<Index> parent(m.size(), -1);
  std::vector<std::uint8_t> added(m.size(), 0);
  auto find = [&](Index v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  std::vector<std::int32_t> widest(pairs.size(), -1);
  for (std::size_t q = 0; q < order.size();) {
    const std::int32_t level = L[order[q]];
    for (; q < order.size() && L[order[q]] == level; ++q) {
      const Index v = order[q];
      parent[v] = v;
      added[v] = 1;
      const auto c = ijk_of(m, v);
      for (int dk = -1; dk <= 1; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            if (!m.inside(c[0] + di, c[1] + dj, c[2] + dk)) continue;
            const Index w = static_cast<Index>(m.index(c[0] + di, c[1] + dj, c[2] + dk));
            if (added[w]) parent[find(w)] = find(v);
          }
    }
    for (std::size_t p = 0; p < pairs.size(); ++p)
      if (widest[p] < 0 && added[path[pairs[p].first]] && added[path[pairs[p].second]] &&
          find(path[pairs[p].first]) == find(path[pairs[p].second]))
        widest[p] = level;
  }
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    std::int32_t path_min = L[path[pairs[p].first]];
    for (std::size_t q = pairs[p].first; q <= pairs[p].second; ++q) path_min = std::min(path_min, L[path[q]]);
    EXPECT_EQ(path_min, widest[p]) << "path voxels " << pairs[p].first << ".." << pairs[p].second;
  }
  EXPECT_EQ(max_steps(m, path).first, 1);  // 26-connected
}

TEST(CenterlineExtraction, SingleVoxelThickLineHasRadiiClampedToHalfSpacing) {
  // an L-shaped line of single voxels in the xy-plane; spacing (0.8, 0.8, 1.3): DFB = 0.8 = h_min on
  // every voxel, so r = max(DFB - h_min/2, h_min/2) = 0.4 everywhere (clamped where the smoothed curve
  // cuts the corner and the interpolated DFB drops)
  MaskVolume m;
  m.dims = {30, 24, 5};
  m.spacing = Vec3(0.8, 0.8, 1.3);
  m.data.assign(m.size(), 0);
  for (Index i = 3; i <= 26; ++i) m.at(i, 2, 2) = 1;
  for (Index j = 2; j <= 20; ++j) m.at(26, j, 2) = 1;
  const SkeletonResult r = extract_centerline(m, {.atom_count = 12});
  EXPECT_EQ(r.path_voxels.size(), 24u + 18u);
  EXPECT_EQ(r.max_dfb, 0.8);
  for (Index i = 0; i < r.atoms.rows(); ++i) {
    EXPECT_NEAR(r.radii[i], 0.4, 1e-15) << "atom " << i;
    EXPECT_NEAR(r.atoms(i, 2), 2.6, 1e-12);
  }
  expect_even_spacing(r);
}

TEST(CenterlineExtraction, BlobTooShortToTrimKeepsItsEndsByTheFourDeltaRule) {
  // a 2 x 2 x 1 voxel plate: the double sweep joins opposite corners, the tree path takes two face
  // steps (2 mm, D-7 prefers the shorter edge); cutting both closed ends where s_end < r (r = 0.5 mm)
  // would leave less than 4 delta = 2 mm, so D-8 trimming is skipped (§3.7)
  MaskVolume m;
  m.dims = {7, 7, 7};
  m.data.assign(m.size(), 0);
  for (Index j = 2; j <= 3; ++j)
    for (Index i = 2; i <= 3; ++i) m.at(i, j, 3) = 1;
  const SkeletonResult r = extract_centerline(m, {.atom_count = 5});
  EXPECT_NEAR((r.ends[0].position - r.ends[1].position).norm(), std::sqrt(2.0), 1e-12);
  EXPECT_EQ(r.path_voxels.size(), 3u);
  EXPECT_EQ(r.ends[0].trimmed, 0.0);
  EXPECT_EQ(r.ends[1].trimmed, 0.0);
  bool noted = false;
  for (const auto& n : r.notes) noted = noted || n.find("trimming skipped") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(CenterlineExtraction, TwoComponentsUseTheLargestAndSaySo) {
  MaskVolume m;
  m.dims = {44, 22, 22};
  m.data.assign(m.size(), 0);
  Index big = 0;
  for (Index k = 0; k < 22; ++k)
    for (Index j = 0; j < 22; ++j)
      for (Index i = 0; i < 44; ++i) {
        if ((Vec3(i, j, k) - Vec3(33, 11, 11)).norm() <= 8.0) {
          m.at(i, j, k) = 1;
          ++big;
        }
        if ((Vec3(i, j, k) - Vec3(9, 11, 11)).norm() <= 4.0) m.at(i, j, k) = 1;
      }
  const SkeletonResult r = extract_centerline(m);
  EXPECT_EQ(r.components, 2);
  EXPECT_EQ(r.component_voxels, big);
  EXPECT_GT(r.object_voxels, big);
  ASSERT_FALSE(r.notes.empty());
  EXPECT_NE(r.notes[0].find("used the largest of 2 components"), std::string::npos) << r.notes[0];
  for (Index i = 0; i < r.atoms.rows(); ++i)
    EXPECT_LE((r.atoms.row(i).transpose() - Vec3(33, 11, 11)).norm(), 8.0) << "atom " << i;
}

TEST(CenterlineExtraction, RejectsEmptyMaskFewAtomsBadSpacingAndSingleVoxel) {
  MaskVolume m;
  m.dims = {5, 5, 5};
  m.data.assign(m.size(), 0);
  EXPECT_EQ(what_of(m), "mask: no object voxels");
  m.at(2, 2, 2) = 1;
  EXPECT_NE(what_of(m).find("coincide"), std::string::npos) << what_of(m);
  m.at(3, 2, 2) = 1;
  EXPECT_NE(what_of(m, {.atom_count = 1}).find("atom_count must be >= 2"), std::string::npos);
  m.spacing = Vec3(1.0, -0.5, 1.0);
  EXPECT_NE(what_of(m).find("mask: spacing[1] must be > 0"), std::string::npos) << what_of(m);
  m.spacing = Vec3::Ones();
  EXPECT_NE(what_of(m, {.connectivity = 8}).find("connectivity"), std::string::npos);
}

TEST(CenterlineExtraction, AnisotropicSpacingTubeStaysCentred) {
  // quarter arc of radius 30 in the xy-plane, tube radius 5, spacing (0.4, 0.6, 0.8) mm, both ends
  // cut by the volume border x = 0 and y = 0
  const double R = 30.0, rad = 5.0;
  MatX3 arc(401, 3);
  for (Index i = 0; i <= 400; ++i) {
    const double t = 0.5 * kPi * static_cast<double>(i) / 400.0;
    arc.row(i) << R * std::cos(t), R * std::sin(t), 0.0;
  }
  const Vec3 h(0.4, 0.6, 0.8);
  const MaskVolume m = tube_volume(arc, rad, {93, 63, 19}, h, Vec3(0.0, 0.0, -7.2));
  const SkeletonResult r = extract_centerline(m);
  ASSERT_EQ(r.open_end_sizes.size(), 2u);
  double max_dev = 0.0;
  for (Index i = 0; i < r.curve.rows(); ++i)
    max_dev = std::max(max_dev, torus_deviation(r.curve.row(i).transpose(), R));
  EXPECT_LE(max_dev, 0.5 * h.maxCoeff());  // within half the coarsest spacing
  for (Index i = 0; i < r.atoms.rows(); ++i) {
    if (torus_arc_from_ends(r.atoms.row(i).transpose(), R) < 2 * rad) continue;
    EXPECT_NEAR(r.radii[i], rad, 0.5) << "atom " << i;
  }
  std::printf("[ figures  ] anisotropic (0.4, 0.6, 0.8) arc tube: max deviation %.4f mm\n", max_dev);
  expect_even_spacing(r);
}

TEST(CenterlineExtraction, DirectionAndOriginMapTheResultRigidly) {
  const MaskVolume m0 = quarter_torus_volume({.R = 20.0, .r = 4.0, .h = 0.5});
  MaskVolume m1 = m0;
  const Mat3 D = (Eigen::AngleAxisd(0.5, Vec3::UnitZ()) * Eigen::AngleAxisd(-0.3, Vec3(1, 1, 0).normalized()))
                     .toRotationMatrix();
  m1.direction = D;
  m1.origin = Vec3(5.0, -3.0, 2.0);
  const SkeletonResult r0 = extract_centerline(m0), r1 = extract_centerline(m1);
  ASSERT_EQ(r0.atoms.rows(), r1.atoms.rows());
  const Vec3 shift = m1.origin - D * m0.origin;
  for (Index i = 0; i < r0.atoms.rows(); ++i)
    EXPECT_NEAR((D * r0.atoms.row(i).transpose() + shift - r1.atoms.row(i).transpose()).norm(), 0.0, 1e-9);
  EXPECT_TRUE((r0.radii.array() == r1.radii.array()).all());
  EXPECT_EQ(r0.path_voxels, r1.path_voxels);
}

TEST(CenterlineExtraction, UserEndpointsOverrideTheDoubleSweep) {
  const MaskVolume m = ellipsoid_volume();
  SkeletonSettings s;
  s.start = UserEndpoint{Vec3(-30.2, 0.1, 0.3)};
  s.end = UserEndpoint{Vec3(29.9, -0.2, 0.0)};
  const SkeletonResult r = extract_centerline(m, s);
  EXPECT_NEAR((r.ends[0].position - Vec3(-30, 0, 0)).norm(), 0.0, 1e-12);  // snapped to the nearest voxel
  EXPECT_NEAR((r.ends[1].position - Vec3(30, 0, 0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(r.ends[0].kind, EndKind::Closed);
}

TEST(CenterlineExtraction, ClosedEndModeIgnoresBorderContactAndTrimsBothEnds) {
  const MaskVolume m = quarter_torus_volume();
  const SkeletonResult r = extract_centerline(m, {.end_mode = EndMode::Closed});
  EXPECT_EQ(r.ends[0].kind, EndKind::Closed);
  EXPECT_EQ(r.ends[1].kind, EndKind::Closed);
  EXPECT_GT(r.ends[0].trimmed, 0.0);
  EXPECT_GT(r.ends[1].trimmed, 0.0);
  bool noted = false;
  for (const auto& n : r.notes)
    noted = noted || n.find("end mode closed: 2 open end(s)") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(CenterlineExtraction, OneOpenEndStartsThereAndTrimsOnlyTheClosedEnd) {
  MatX3 seg(2, 3);
  seg << 0.0, 10.0, 10.0, 30.0, 10.0, 10.0;  // from the border x = 0 into the volume
  const MaskVolume m = tube_volume(seg, 4.0, {81, 41, 41}, Vec3::Constant(0.5), Vec3::Zero());
  const SkeletonResult r = extract_centerline(m);
  ASSERT_EQ(r.open_end_sizes.size(), 1u);
  EXPECT_EQ(r.ends[0].kind, EndKind::Open);
  EXPECT_EQ(r.ends[1].kind, EndKind::Closed);
  EXPECT_EQ(r.ends[0].trimmed, 0.0);
  EXPECT_GT(r.ends[1].trimmed, 0.0);
  EXPECT_NEAR((r.atoms.row(0).transpose() - Vec3(0, 10, 10)).norm(), 0.0, 1e-12);  // cut-face centroid
  EXPECT_GT(r.ends[1].position.x(), 33.0);  // the far tip (hemispherical cap up to x = 34)
  // on the axis up to the centre of the cap (beyond it the path runs to the tip voxel found by DFS)
  for (Index i = 0; i < r.atoms.rows(); ++i) {
    if (r.atoms(i, 0) > 30.0) continue;
    EXPECT_LE(std::hypot(r.atoms(i, 1) - 10.0, r.atoms(i, 2) - 10.0), 0.25) << "atom " << i;
  }
}

TEST(CenterlineExtraction, SixConnectivityGivesAFaceConnectedPath) {
  const MaskVolume m = quarter_torus_volume({.R = 20.0, .r = 3.0, .h = 0.5});
  const SkeletonResult r = extract_centerline(m, {.connectivity = 6});
  EXPECT_EQ(max_steps(m, r.path_voxels).second, 1);
  const SkeletonResult r26 = extract_centerline(m);
  EXPECT_EQ(max_steps(m, r26.path_voxels).first, 1);
  EXPECT_GT(max_steps(m, r26.path_voxels).second, 1);  // diagonal steps are used
}

TEST(CenterlineExtraction, PenalizedDijkstraJoinsTheSameEndpointsInsideTheObject) {
  const MaskVolume m = quarter_torus_volume();
  const SkeletonResult tree = extract_centerline(m);
  const SkeletonResult pd = extract_centerline(m, {.path_method = PathMethod::PenalizedDijkstra});
  EXPECT_EQ(pd.path_voxels.front(), tree.path_voxels.front());
  EXPECT_EQ(pd.path_voxels.back(), tree.path_voxels.back());
  EXPECT_EQ(max_steps(m, pd.path_voxels).first, 1);
  double max_dev = 0.0;
  for (Index v : pd.path_voxels) {
    EXPECT_EQ(m.data[v], 1);
    const auto c = ijk_of(m, v);
    max_dev = std::max(max_dev, torus_deviation(m.to_world(Vec3(c[0], c[1], c[2])), 40.0));
  }
  EXPECT_LT(max_dev, 5.0);
  std::printf("[ figures  ] penalized Dijkstra on the quarter torus: raw path max deviation %.3f mm\n",
              max_dev);
}

TEST(CenterlineExtraction, KeptDistanceFieldReproducesTheRadii) {
  const MaskVolume m = ellipsoid_volume();
  const SkeletonResult r = extract_centerline(m, {.keep_distance_field = true});
  ASSERT_FALSE(r.dfb.data.empty());
  for (Index i = 0; i < r.atoms.rows(); ++i) {
    const double dfb = sample_trilinear(r.dfb, r.atoms.row(i).transpose());
    EXPECT_NEAR(r.radii[i], std::max(dfb - 0.5, 0.5), 1e-12);  // §3.5.5
  }
  const Centerline c = r.centerline();
  EXPECT_EQ(c.size(), 40);
}

}  // namespace
}  // namespace medspring
