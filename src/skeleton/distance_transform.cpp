#include "medspring/skeleton/distance_transform.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace medspring {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Scratch buffers of the 1D transform, sized once per volume (no per-line allocation).
struct Line {
  std::vector<double> f, d, z;
  std::vector<Index> v;
  explicit Line(Index n) : f(n), d(n), z(n + 1), v(n) {}
};

/// d(p) = min_q w (p - q)^2 + f(q) over the sites q with finite f(q): the lower envelope of
/// parabolas of Felzenszwalb & Huttenlocher (2012), Algorithm 1. All +inf when there is no site.
/// With w = 1 and integer f every intermediate value is an exact integer (< 2^53), so the result is
/// exact; the breakpoints s are quotients of integers, whose rounding never crosses an integer.
void lower_envelope(Line& L, Index n, double w) {
  Index k = -1;
  for (Index q = 0; q < n; ++q) {
    const double fq = L.f[q];
    if (fq == kInf) continue;
    if (k < 0) {
      k = 0;
      L.v[0] = q;
      L.z[0] = -kInf;
      L.z[1] = kInf;
      continue;
    }
    const double qq = static_cast<double>(q);
    double s = 0.0;
    while (true) {
      const double vk = static_cast<double>(L.v[k]);
      s = ((fq + w * qq * qq) - (L.f[L.v[k]] + w * vk * vk)) / (2.0 * w * (qq - vk));
      if (s <= L.z[k]) {
        --k;  // z[0] = -inf stops this at k = 0
      } else {
        break;
      }
    }
    ++k;
    L.v[k] = q;
    L.z[k] = s;
    L.z[k + 1] = kInf;
  }
  if (k < 0) {
    std::fill(L.d.begin(), L.d.begin() + n, kInf);
    return;
  }
  Index j = 0;
  for (Index q = 0; q < n; ++q) {
    const double qq = static_cast<double>(q);
    while (L.z[j + 1] < qq) ++j;
    const double dq = qq - static_cast<double>(L.v[j]);
    L.d[q] = w * dq * dq + L.f[L.v[j]];
  }
}

/// In-place squared distance transform of g (0 = background site, +inf = object) along `axis`.
void transform_axis(std::vector<double>& g, const std::array<Index, 3>& dims, int axis, double w) {
  const std::size_t stride[3] = {1, static_cast<std::size_t>(dims[0]),
                                 static_cast<std::size_t>(dims[0]) * static_cast<std::size_t>(dims[1])};
  const Index n = dims[axis];
  Line L(n);
  // the two axes other than `axis`
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  for (Index c2 = 0; c2 < dims[a2]; ++c2)
    for (Index c1 = 0; c1 < dims[a1]; ++c1) {
      const std::size_t base = stride[a1] * c1 + stride[a2] * c2;
      const std::size_t st = stride[axis];
      bool any_site = false, any_positive = false;
      for (Index q = 0; q < n; ++q) {
        L.f[q] = g[base + st * q];
        any_site = any_site || L.f[q] != kInf;
        any_positive = any_positive || L.f[q] > 0.0;
      }
      // an all-zero line stays zero; a line without sites stays +inf
      if (!any_positive || !any_site) continue;
      lower_envelope(L, n, w);
      for (Index q = 0; q < n; ++q) g[base + st * q] = L.d[q];
    }
}

}  // namespace

DistanceField distance_from_boundary(const MaskVolume& mask) {
  require_valid_volume(mask, "distance_from_boundary: mask");
  DistanceField out;
  const Vec3& h = mask.spacing;
  out.isotropic = std::abs(h.maxCoeff() - h.minCoeff()) <= 1e-12 * h.maxCoeff();
  const std::size_t N = mask.size();

  std::vector<double> g(N);
  for (std::size_t i = 0; i < N; ++i) g[i] = mask.data[i] ? kInf : 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double w = out.isotropic ? 1.0 : h[axis] * h[axis];
    transform_axis(g, mask.dims, axis, w);
  }

  auto copy_geometry = [&](auto& vol) {
    vol.dims = mask.dims;
    vol.spacing = mask.spacing;
    vol.origin = mask.origin;
    vol.direction = mask.direction;
  };
  copy_geometry(out.dfb);
  out.dfb.data.resize(N);
  if (out.isotropic) {
    copy_geometry(out.squared_edt);
    out.squared_edt.data.resize(N);
    const double hh = h.minCoeff();
    for (std::size_t i = 0; i < N; ++i) {
      if (g[i] == kInf) {
        out.squared_edt.data[i] = std::numeric_limits<std::int32_t>::max();
        out.dfb.data[i] = kInf;
      } else {
        out.squared_edt.data[i] = static_cast<std::int32_t>(g[i]);
        out.dfb.data[i] = hh * std::sqrt(g[i]);
      }
    }
  } else {
    for (std::size_t i = 0; i < N; ++i) out.dfb.data[i] = std::sqrt(g[i]);
  }
  return out;
}

double trilinear(const ScalarVolume& volume, const Vec3& ijk) {
  double t[3];
  Index i0[3], i1[3];
  for (int a = 0; a < 3; ++a) {
    const Index n = volume.dims[a];
    const double c = std::clamp(ijk[a], 0.0, static_cast<double>(n - 1));
    i0[a] = std::min(static_cast<Index>(std::floor(c)), n - 1);
    i1[a] = std::min(i0[a] + 1, n - 1);
    t[a] = c - static_cast<double>(i0[a]);
  }
  auto at = [&](Index i, Index j, Index k) { return volume.at(i, j, k); };
  const double c00 = (1 - t[0]) * at(i0[0], i0[1], i0[2]) + t[0] * at(i1[0], i0[1], i0[2]);
  const double c10 = (1 - t[0]) * at(i0[0], i1[1], i0[2]) + t[0] * at(i1[0], i1[1], i0[2]);
  const double c01 = (1 - t[0]) * at(i0[0], i0[1], i1[2]) + t[0] * at(i1[0], i0[1], i1[2]);
  const double c11 = (1 - t[0]) * at(i0[0], i1[1], i1[2]) + t[0] * at(i1[0], i1[1], i1[2]);
  const double c0 = (1 - t[1]) * c00 + t[1] * c10;
  const double c1 = (1 - t[1]) * c01 + t[1] * c11;
  return (1 - t[2]) * c0 + t[2] * c1;
}

}  // namespace medspring
