#include "medspring/physics/stability.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "medspring/physics/compression_terms.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/volume_terms.hpp"
#include "stiffness_product.hpp"

namespace medspring {

double gershgorin_omega(const Model& m, const MatX3& x) {
  // §2.2: omega^2 <= max_i [(k_r,i + sum kappa_s)/m_i + sum kappa_s / sqrt(m_i m_j)], free rows only.
  const Index n = m.num_nodes();
  VecX diag = m.kr;
  VecX off = VecX::Zero(n);
  const Springs& S = m.springs;
  for (Index s = 0; s < S.size(); ++s) {
    const Index a = S.i[s], b = S.j[s];
    const double L = (x.row(b) - x.row(a)).norm();
    const double d = L - S.L0[s];
    const double phi = spring_tension(S.k[s], S.kp[s], d);
    const double kappa =
        std::max(std::abs(spring_tension_derivative(S.k[s], S.kp[s], d)), L > 0 ? std::abs(phi) / L : 0.0);
    diag[a] += kappa;
    diag[b] += kappa;
    const double c = kappa / std::sqrt(m.mass[a] * m.mass[b]);
    if (!m.fixed[b]) off[a] += c;
    if (!m.fixed[a]) off[b] += c;
  }
  const BendingTerms& B = m.bending;
  for (Index t = 0; t < B.size(); ++t) {  // row sums of kb w w^T, w = (1, -2, 1): 4, 8, 4 (16 k_b bound)
    diag[B.a[t]] += B.kb[t];
    diag[B.b[t]] += 4 * B.kb[t];
    diag[B.c[t]] += B.kb[t];
    off[B.a[t]] += 3 * B.kb[t] / m.mass[B.a[t]];
    off[B.b[t]] += 4 * B.kb[t] / m.mass[B.b[t]];
    off[B.c[t]] += 3 * B.kb[t] / m.mass[B.c[t]];
  }
  if (m.volume.size() > 0) add_volume_gershgorin(m.volume, x, m.mass, m.fixed, diag, off);
  if (m.compression.size() > 0) add_compression_gershgorin(m.compression, x, m.mass, m.fixed, diag, off);
  if (m.thin.size() > 0)
    add_thin_tet_gershgorin(m.thin, m.mass, m.fixed, diag, off);  // rest = co-rotated rows
  double w2 = 0;
  for (Index a = 0; a < n; ++a)
    if (!m.fixed[a]) w2 = std::max(w2, diag[a] / m.mass[a] + off[a]);
  return std::sqrt(w2);
}

double power_iteration_omega(const Model& m, const MatX3& x, int iterations, double safety) {
  const Index n = m.num_nodes();
  if (m.free_nodes.empty()) return 0.0;
  // Matrix-free K_t z (springs + return springs + bending), so that million-node models need no
  // assembled matrix.
  const Springs& S = m.springs;
  const Index ns = S.size();
  // K_s = ca n n^T + cb I = ce e e^T + cb I with ce = ca / L^2 and e = x_j - x_i, recomputed from x in
  // every product: no stored directions (a 1M-node build stays within its memory budget) and no square
  // root or division per spring and product (they made this loop divider-bound: issue 15, 56 % of the
  // 3M-node build). The same matrix to rounding.
  VecX ce(ns), cb(ns);
  for (Index q = 0; q < ns; ++q) {
    const Vec3 e = (x.row(S.j[q]) - x.row(S.i[q])).transpose();
    const double L2 = e.squaredNorm();
    const double L = std::sqrt(L2);
    if (L < 1e-9) {
      ce[q] = cb[q] = 0;
      continue;
    }
    const double d = L - S.L0[q];
    cb[q] = spring_tension(S.k[q], S.kp[q], d) / L;
    ce[q] = (spring_tension_derivative(S.k[q], S.kp[q], d) - cb[q]) / L2;
  }
  const double* X = x.data();
  VecX sc(n);  // M^-1/2 per node, zero on fixed DOFs (removed from the system, §1.5)
  for (Index a = 0; a < n; ++a) sc[a] = m.fixed[a] ? 0.0 : 1.0 / std::sqrt(m.mass[a]);
  VecX w;  // M^-1/2 q, for the bending and volume terms only
  // y = M^-1/2 K_t M^-1/2 q (stiffness_product.hpp): springs read M^-1/2 q on the fly
  auto apply_A = [&](const VecX& qv, VecX& y) {
    detail::stiffness_product<true>(m, x, sc.data(), qv, y, &w, false, [&](Index q, const Vec3& d) {
      const Index i = 3 * S.i[q], j = 3 * S.j[q];
      const double ex = X[j] - X[i], ey = X[j + 1] - X[i + 1], ez = X[j + 2] - X[i + 2];
      const double g = ce[q] * (ex * d.x() + ey * d.y() + ez * d.z());  // as before: the same bits
      return Vec3(g * ex + cb[q] * d.x(), g * ey + cb[q] * d.y(), g * ez + cb[q] * d.z());
    });
  };
  // Lanczos (issue 15: the 30 power-iteration products were 56 % of a 3M-node build): `iterations`
  // products span the Krylov space of the start vector, and the largest eigenvalue of the tridiagonal
  // projection (a Ritz value) is the largest Rayleigh quotient over that space: at least the power
  // iteration's estimate after as many products, never above lambda_max (to rounding). It converges
  // like a Chebyshev polynomial of the spectral gap, far faster than the power iteration, so 15
  // products replace 30. Still an estimate from below: `safety` (1.05) covers the rest, and
  // tests/physics/stability_test.cpp checks the bound against Eigen's dense eigenvalues.
  VecX qv(3 * n), qprev = VecX::Zero(3 * n), y(3 * n);
  std::uint64_t seed = 0x9E3779B97F4A7C15ull;  // deterministic pseudo-random start
  for (Index q = 0; q < 3 * n; ++q) {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    qv[q] = (static_cast<double>(seed >> 11) / 9007199254740992.0 - 0.5) * sc[q / 3];
  }
  const double n0 = qv.norm();
  if (n0 == 0) return 0.0;
  qv /= n0;
  std::vector<double> alpha, beta;
  double beta_prev = 0;
  iterations = std::max(iterations, 1);
  for (int it = 0; it < iterations; ++it) {
    apply_A(qv, y);
    const double al = qv.dot(y);
    y -= al * qv + beta_prev * qprev;
    alpha.push_back(al);
    const double be = y.norm();
    if (!(be > 1e-12 * std::max(std::abs(al), 1e-300)) || it + 1 == iterations) break;  // invariant space
    beta.push_back(be);
    qprev.swap(qv);
    qv = y / be;
    beta_prev = be;
  }
  const auto k = static_cast<Index>(alpha.size());
  double lambda = alpha[0];
  if (k > 1) {
    VecX d = Eigen::Map<const VecX>(alpha.data(), k);
    VecX e = Eigen::Map<const VecX>(beta.data(), k - 1);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
    es.computeFromTridiagonal(d, e, Eigen::EigenvaluesOnly);
    lambda = es.eigenvalues().maxCoeff();
  }
  return safety * std::sqrt(std::max(lambda, 0.0));
}

}  // namespace medspring

namespace medspring {

namespace {

// Largest eigenvalue of the symmetric tridiagonal (d[0..k), e[0..k-1)) by bisection on Sturm counts.
double tridiagonal_max(const double* d, const double* e, int k) {
  double lo = d[0], hi = d[0];
  for (int i = 0; i < k; ++i) {
    const double r = (i > 0 ? std::abs(e[i - 1]) : 0.0) + (i + 1 < k ? std::abs(e[i]) : 0.0);
    lo = std::min(lo, d[i] - r);
    hi = std::max(hi, d[i] + r);
  }
  auto below = [&](double lambda) {  // eigenvalues < lambda
    int count = 0;
    double q = d[0] - lambda;
    for (int i = 0;; ++i) {
      if (q < 0) ++count;
      if (i + 1 == k) break;
      if (q == 0) q = 1e-300;
      q = d[i + 1] - lambda - e[i] * e[i] / q;
    }
    return count;
  };
  for (int it = 0; it < 200 && hi - lo > 1e-15 * std::max(std::abs(hi), std::abs(lo)); ++it) {
    const double mid = 0.5 * (lo + hi);
    (below(mid) == k ? hi : lo) = mid;
  }
  return hi;
}

inline Vec3 at3(const double* v, Index i) {
  return {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
}
inline void add3(double* y, Index i, const Vec3& v) {
  y[3 * i] += v.x();
  y[3 * i + 1] += v.y();
  y[3 * i + 2] += v.z();
}

// y += H_t p for one tetrahedron term whose Hessian is a g g^T + b d^2V (g = dV/dx at x), matrix-free: the
// volume term (a = kv / V0, b = kv (V - V0) / V0) and the compression term (a = kc h''(J) / V0, b = kc
// h'(J)). (d^2 V) p as volume_terms.cpp's volume_gradient_derivative.
template <class Coef>
inline void tet_product(const double* X, const double* P, double* Y, const Index id[4], Coef&& coef) {
  const Vec3 xa = at3(X, id[0]), e1 = at3(X, id[1]) - xa, e2 = at3(X, id[2]) - xa, e3 = at3(X, id[3]) - xa;
  Vec3 g[4];
  g[1] = e2.cross(e3) / 6.0;
  g[2] = e3.cross(e1) / 6.0;
  g[3] = e1.cross(e2) / 6.0;
  g[0] = -(g[1] + g[2] + g[3]);
  double a = 0, b = 0;
  if (!coef(e1.dot(g[1]), a, b)) return;
  const Vec3 p0 = at3(P, id[0]), p1 = at3(P, id[1]) - p0, p2 = at3(P, id[2]) - p0, p3 = at3(P, id[3]) - p0;
  const double gp = g[1].dot(p1) + g[2].dot(p2) + g[3].dot(p3);  // sum_k g_k . p_k (the g_k sum to 0)
  Vec3 h[4];
  h[1] = (p2.cross(e3) + e2.cross(p3)) / 6.0;
  h[2] = (p3.cross(e1) + e3.cross(p1)) / 6.0;
  h[3] = (p1.cross(e2) + e1.cross(p2)) / 6.0;
  h[0] = -(h[1] + h[2] + h[3]);
  for (int k = 0; k < 4; ++k) add3(Y, id[k], a * gp * g[k] + b * h[k]);
}

// y = S K_t S q (S = diag(z.sc)), the exact tangent at x: return springs, springs (z.ce, z.cb), bending,
// and the volume and compression terms matrix-free (the compression terms' own product assembles a 12 x 12
// matrix per term: 4.4 ms per product on the 2,012-node kidney, about 20 force passes).
void tangent_product(const Model& m, const MatX3& x, TangentScratch& z, const VecX& qv, VecX& y) {
  const Index n = m.num_nodes();
  const double* X = x.data();
  double* W = z.w.data();
  for (Index a = 0; a < n; ++a)
    for (int c = 0; c < 3; ++c) W[3 * a + c] = z.sc[a] * qv[3 * a + c];
  double* Y = y.data();
  for (Index a = 0; a < n; ++a)
    for (int c = 0; c < 3; ++c) Y[3 * a + c] = m.kr[a] * W[3 * a + c];
  const Springs& S = m.springs;
  for (Index q = 0; q < S.size(); ++q) {
    const Index i = S.i[q], j = S.j[q];
    const Vec3 e = at3(X, j) - at3(X, i), d = at3(W, i) - at3(W, j);
    const Vec3 k = z.ce[q] * e.dot(d) * e + z.cb[q] * d;  // power_iteration_omega's spring action
    add3(Y, i, k);
    add3(Y, j, -k);
  }
  const BendingTerms& B = m.bending;
  for (Index t = 0; t < B.size(); ++t) {
    const Vec3 g = B.kb[t] * (at3(W, B.a[t]) - 2.0 * at3(W, B.b[t]) + at3(W, B.c[t]));
    add3(Y, B.a[t], g);
    add3(Y, B.b[t], -2.0 * g);
    add3(Y, B.c[t], g);
  }
  const VolumeTerms& V = m.volume;
  for (Index t = 0; t < V.size(); ++t) {
    const auto u = static_cast<std::size_t>(t);
    const Index id[4] = {V.a[u], V.b[u], V.c[u], V.d[u]};
    tet_product(X, W, Y, id, [&](double vol, double& a, double& b) {
      a = V.kv[u] / V.V0[u];
      b = V.kv[u] * (vol - V.V0[u]) / V.V0[u];
      return true;
    });
  }
  const CompressionTerms& C = m.compression;
  for (Index t = 0; t < C.size(); ++t) {
    const auto u = static_cast<std::size_t>(t);
    const Index id[4] = {C.a[u], C.b[u], C.c[u], C.d[u]};
    tet_product(X, W, Y, id, [&](double vol, double& a, double& b) {
      const double J = vol / C.V0[u];
      if (J >= 1.0) return false;
      const CompressionH hj = compression_h(J);
      a = C.kc[u] / C.V0[u] * hj.d2;
      b = C.kc[u] * hj.d1;
      return true;
    });
  }
  for (Index a = 0; a < n; ++a)
    for (int c = 0; c < 3; ++c) Y[3 * a + c] *= z.sc[a];
}

}  // namespace

void size_tangent_scratch(const Model& m, TangentScratch& z) {
  const Index n = m.num_nodes(), ns = m.springs.size();
  if (z.q.size() == 3 * n && z.ce.size() == ns && z.x.rows() == n) return;
  for (VecX* v : {&z.q, &z.qprev, &z.y, &z.w}) v->setZero(3 * n);
  z.sc.setZero(n);
  z.ce.setZero(ns);
  z.cb.setZero(ns);
  z.x.setZero(n, 3);
  z.k = 0;
  z.done = true;
}

void tangent_lanczos_start(const Model& m, const MatX3& x, int iterations, TangentScratch& z) {
  const Index n = m.num_nodes();
  size_tangent_scratch(m, z);
  z.k = 0;
  z.beta_prev = 0;
  z.iterations = std::clamp(iterations, 1, TangentScratch::kMaxProducts);
  z.done = true;  // until the start vector is in place
  if (m.free_nodes.empty()) return;
  z.x = x;  // the snapshot: the estimate's products read it, whatever the state does meanwhile
  const Springs& S = m.springs;
  const Index ns = S.size();
  for (Index q = 0; q < ns; ++q) {  // as power_iteration_omega
    const Vec3 e = (z.x.row(S.j[q]) - z.x.row(S.i[q])).transpose();
    const double L2 = e.squaredNorm();
    const double L = std::sqrt(L2);
    if (L < 1e-9) {
      z.ce[q] = z.cb[q] = 0;
      continue;
    }
    const double d = L - S.L0[q];
    z.cb[q] = spring_tension(S.k[q], S.kp[q], d) / L;
    z.ce[q] = (spring_tension_derivative(S.k[q], S.kp[q], d) - z.cb[q]) / L2;
  }
  for (Index a = 0; a < n; ++a) z.sc[a] = m.fixed[a] ? 0.0 : 1.0 / std::sqrt(m.mass[a]);
  VecX& qv = z.q;
  z.qprev.setZero();
  std::uint64_t seed = 0x9E3779B97F4A7C15ull;  // power_iteration_omega's start
  for (Index q = 0; q < 3 * n; ++q) {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    qv[q] = (static_cast<double>(seed >> 11) / 9007199254740992.0 - 0.5) * z.sc[q / 3];
  }
  const double n0 = qv.norm();
  if (n0 == 0) return;
  qv /= n0;
  z.done = false;
}

bool tangent_lanczos_advance(const Model& m, int products, TangentScratch& z) {
  VecX &qv = z.q, &qprev = z.qprev, &y = z.y;
  for (int p = 0; p < products && !z.done; ++p) {
    tangent_product(m, z.x, z, qv, y);
    ++z.products;
    const double al = qv.dot(y);
    y -= al * qv + z.beta_prev * qprev;
    z.alpha[z.k++] = al;
    const double be = y.norm();
    if (!(be > 1e-12 * std::max(std::abs(al), 1e-300)) || z.k == z.iterations) {
      z.done = true;  // the iterations asked for, or an invariant space
      break;
    }
    z.beta[z.k - 1] = be;
    qprev.swap(qv);
    qv = y / be;
    z.beta_prev = be;
  }
  return z.done;
}

double tangent_lanczos_omega2(const TangentScratch& z) {
  return z.k > 0 ? std::max(tridiagonal_max(z.alpha, z.beta, z.k), 0.0) : 0.0;
}

double tangent_omega2(const Model& m, const MatX3& x, int iterations, TangentScratch& z) {
  tangent_lanczos_start(m, x, iterations, z);
  tangent_lanczos_advance(m, TangentScratch::kMaxProducts, z);
  return tangent_lanczos_omega2(z);
}

}  // namespace medspring
