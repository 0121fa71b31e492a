#include "medspring/physics/stability.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "medspring/physics/forces.hpp"
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
