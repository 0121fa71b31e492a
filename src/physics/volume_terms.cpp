#include "medspring/physics/volume_terms.hpp"

#include <algorithm>
#include <cmath>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

struct Tet {
  Vec3 xa, e1, e2, e3;  // corner a and the edges b - a, c - a, d - a
};

inline Vec3 row(const double* x, Index i) {
  return {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
}

inline Tet corners(const VolumeTerms& T, const double* x, Index t) {
  const Vec3 xa = row(x, T.a[t]);
  return {xa, row(x, T.b[t]) - xa, row(x, T.c[t]) - xa, row(x, T.d[t]) - xa};
}

// dV/dx of the four corners (a, b, c, d).
inline void volume_gradient(const Tet& q, Vec3 g[4]) {
  g[1] = q.e2.cross(q.e3) / 6.0;
  g[2] = q.e3.cross(q.e1) / 6.0;
  g[3] = q.e1.cross(q.e2) / 6.0;
  g[0] = -(g[1] + g[2] + g[3]);
}

// (d^2 V) p: the derivative of the gradient along p (p holds the four corners' components).
inline void volume_gradient_derivative(const Tet& q, const Vec3 p[4], Vec3 h[4]) {
  const Vec3 p1 = p[1] - p[0], p2 = p[2] - p[0], p3 = p[3] - p[0];
  h[1] = (p2.cross(q.e3) + q.e2.cross(p3)) / 6.0;
  h[2] = (p3.cross(q.e1) + q.e3.cross(p1)) / 6.0;
  h[3] = (p1.cross(q.e2) + q.e1.cross(p2)) / 6.0;
  h[0] = -(h[1] + h[2] + h[3]);
}

inline double longest_edge(const Tet& q) {
  const double l = std::max({q.e1.norm(), q.e2.norm(), q.e3.norm(), (q.e2 - q.e1).norm(),
                             (q.e3 - q.e1).norm(), (q.e3 - q.e2).norm()});
  return l;
}

inline Index node(const VolumeTerms& T, Index t, int k) {
  return k == 0 ? T.a[t] : k == 1 ? T.b[t] : k == 2 ? T.c[t] : T.d[t];
}

}  // namespace

double signed_tet_volume(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  return (p1 - p0).dot((p2 - p0).cross(p3 - p0)) / 6.0;
}

double add_volume_forces(const VolumeTerms& T, const double* x, double* f, bool stiffening) {
  double stiff = 1.0;
  for (Index t = 0; t < T.size(); ++t) {
    const Tet q = corners(T, x, t);
    Vec3 g[4];
    volume_gradient(q, g);
    const double V = q.e1.dot(q.e2.cross(q.e3)) / 6.0;
    const double V0 = T.V0[static_cast<std::size_t>(t)];
    const double s = -T.kv[static_cast<std::size_t>(t)] * (V - V0) / V0;
    for (int k = 0; k < 4; ++k) {
      const Index i = 3 * node(T, t, k);
      f[i] += s * g[k][0];
      f[i + 1] += s * g[k][1];
      f[i + 2] += s * g[k][2];
    }
    // curvature bound |g|^2 + |V - V0| |d^2V| against the rest |g0|^2 (|d^2V| <= 2 L_max / 6 per block)
    if (!stiffening) continue;
    const double gg = g[0].squaredNorm() + g[1].squaredNorm() + g[2].squaredNorm() + g[3].squaredNorm();
    const double rest = T.G0[static_cast<std::size_t>(t)];
    const double cur = gg + std::abs(V - V0) * longest_edge(q) / 3.0 * 4.0;
    if (rest > 0 && cur > rest * stiff) stiff = cur / rest;
  }
  return stiff;
}

void finalize_volume_terms(VolumeTerms& T, const MatX3& x0, const std::string& w) {
  const auto nt = static_cast<std::size_t>(T.size());
  require(T.b.size() == nt && T.c.size() == nt && T.d.size() == nt && T.kv.size() == nt, w,
          ": volume terms arrays have inconsistent sizes");
  T.V0.resize(nt);
  T.G0.resize(nt);
  const Index n = static_cast<Index>(x0.rows());
  for (Index t = 0; t < T.size(); ++t) {
    const Index id[4] = {T.a[t], T.b[t], T.c[t], T.d[t]};
    for (int k = 0; k < 4; ++k) {
      require(id[k] >= 0 && id[k] < n, w, ": volume[", t, "]: node ", id[k], " out of range [0, ", n, ")");
      for (int l = 0; l < k; ++l)
        require(id[k] != id[l], w, ": volume[", t, "]: node ", id[k], " repeated (degenerate tetrahedron)");
    }
    const double kv = T.kv[static_cast<std::size_t>(t)];
    require(std::isfinite(kv) && kv >= 0, w, ": volume[", t, "].kv: must be >= 0 (got ", kv, ")");
    const Tet q = corners(T, x0.data(), t);
    const double V = q.e1.dot(q.e2.cross(q.e3)) / 6.0;
    const double L = longest_edge(q);
    require(std::abs(V) > 1e-12 * L * L * L, w, ": volume[", t, "]: degenerate tetrahedron (nodes ", id[0],
            " ", id[1], " ", id[2], " ", id[3], ", volume ", V, " mm^3)");
    require(V > 0, w, ": volume[", t, "]: inverted tetrahedron (nodes ", id[0], " ", id[1], " ", id[2], " ",
            id[3], ", volume ", V, " mm^3)");
    Vec3 g[4];
    volume_gradient(q, g);
    T.V0[static_cast<std::size_t>(t)] = V;
    T.G0[static_cast<std::size_t>(t)] =
        g[0].squaredNorm() + g[1].squaredNorm() + g[2].squaredNorm() + g[3].squaredNorm();
  }
}

double volume_energy(const VolumeTerms& T, const MatX3& x) {
  double e = 0;
  for (Index t = 0; t < T.size(); ++t) {
    const Tet q = corners(T, x.data(), t);
    const double V = q.e1.dot(q.e2.cross(q.e3)) / 6.0;
    const double V0 = T.V0[static_cast<std::size_t>(t)];
    e += 0.5 * T.kv[static_cast<std::size_t>(t)] * (V - V0) * (V - V0) / V0;
  }
  return e;
}

std::uint64_t count_inverted(const VolumeTerms& T, const MatX3& x) {
  std::uint64_t n = 0;
  for (Index t = 0; t < T.size(); ++t) {
    const Tet q = corners(T, x.data(), t);
    if (!(q.e1.dot(q.e2.cross(q.e3)) > 0)) ++n;
  }
  return n;
}

void add_volume_stiffness_product(const VolumeTerms& T, const MatX3& x, const VecX& p, VecX& y,
                                  bool gauss_newton) {
  for (Index t = 0; t < T.size(); ++t) {
    const Tet q = corners(T, x.data(), t);
    Vec3 g[4], pk[4], h[4];
    volume_gradient(q, g);
    double gp = 0;
    for (int k = 0; k < 4; ++k) {
      pk[k] = p.segment<3>(3 * node(T, t, k));
      gp += g[k].dot(pk[k]);
    }
    const double V = q.e1.dot(q.e2.cross(q.e3)) / 6.0;
    const double V0 = T.V0[static_cast<std::size_t>(t)];
    const double kv = T.kv[static_cast<std::size_t>(t)];
    const double c1 = kv / V0 * gp;
    if (gauss_newton) {
      for (int k = 0; k < 4; ++k) y.segment<3>(3 * node(T, t, k)) += c1 * g[k];
      continue;
    }
    volume_gradient_derivative(q, pk, h);
    const double c2 = kv * (V - V0) / V0;
    for (int k = 0; k < 4; ++k) y.segment<3>(3 * node(T, t, k)) += c1 * g[k] + c2 * h[k];
  }
}

void add_volume_stiffness_triplets(const VolumeTerms& T, const MatX3& x,
                                   std::vector<Eigen::Triplet<double>>& out) {
  for (Index t = 0; t < T.size(); ++t) {
    const Tet q = corners(T, x.data(), t);
    Vec3 g[4];
    volume_gradient(q, g);
    const double V = q.e1.dot(q.e2.cross(q.e3)) / 6.0;
    const double V0 = T.V0[static_cast<std::size_t>(t)];
    const double kv = T.kv[static_cast<std::size_t>(t)];
    const double c2 = kv * (V - V0) / V0;
    for (int l = 0; l < 4; ++l)
      for (int cl = 0; cl < 3; ++cl) {
        Vec3 pk[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
        pk[l][cl] = 1.0;
        Vec3 h[4];
        volume_gradient_derivative(q, pk, h);
        const Index col = 3 * node(T, t, l) + cl;
        for (int k = 0; k < 4; ++k)
          for (int r = 0; r < 3; ++r) {
            const double v = kv / V0 * g[k][r] * g[l][cl] + c2 * h[k][r];
            if (v != 0.0) out.emplace_back(3 * node(T, t, k) + r, col, v);
          }
      }
  }
}

void add_volume_gershgorin(const VolumeTerms& T, const MatX3& x, const VecX& mass,
                           const std::vector<std::uint8_t>& fixed, VecX& diag, VecX& off) {
  for (Index t = 0; t < T.size(); ++t) {
    const Tet q = corners(T, x.data(), t);
    Vec3 g[4];
    volume_gradient(q, g);
    const double V = q.e1.dot(q.e2.cross(q.e3)) / 6.0;
    const double V0 = T.V0[static_cast<std::size_t>(t)];
    const double kv = T.kv[static_cast<std::size_t>(t)];
    const double hb = std::abs(kv * (V - V0) / V0) * longest_edge(q) / 3.0;  // bound of a d^2V block norm
    for (int k = 0; k < 4; ++k) {
      const Index i = node(T, t, k);
      diag[i] += kv / V0 * g[k].squaredNorm() + hb;
      for (int l = 0; l < 4; ++l) {
        if (l == k) continue;
        const Index j = node(T, t, l);
        if (fixed[static_cast<std::size_t>(j)]) continue;
        off[i] += (kv / V0 * g[k].norm() * g[l].norm() + hb) / std::sqrt(mass[i] * mass[j]);
      }
    }
  }
}

}  // namespace medspring
