#include "medspring/physics/stability.hpp"

#include <algorithm>
#include <cmath>

#include "medspring/physics/forces.hpp"

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
  double w2 = 0;
  for (Index a = 0; a < n; ++a)
    if (!m.fixed[a]) w2 = std::max(w2, diag[a] / m.mass[a] + off[a]);
  return std::sqrt(w2);
}

double power_iteration_omega(const Model& m, const MatX3& x, int iterations, double safety) {
  const Index n = m.num_nodes();
  if (m.free_nodes.empty()) return 0.0;
  const Eigen::SparseMatrix<double> K =
      tangent_stiffness(m, x, {.clamp_transverse = false, .include_return = true});
  VecX s(3 * n);  // M^-1/2 scaling, zero on fixed DOFs (removed from the system, §1.5)
  for (Index a = 0; a < n; ++a)
    s.segment<3>(3 * a).setConstant(m.fixed[a] ? 0.0 : 1.0 / std::sqrt(m.mass[a]));
  VecX z(3 * n);
  std::uint64_t seed = 0x9E3779B97F4A7C15ull;  // deterministic pseudo-random start
  for (Index q = 0; q < 3 * n; ++q) {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    z[q] = (static_cast<double>(seed >> 11) / 9007199254740992.0 - 0.5) * s[q];
  }
  double lambda = 0;
  for (int it = 0; it < iterations; ++it) {
    const double nz = z.norm();
    if (nz == 0) return 0.0;
    z /= nz;
    const VecX y = s.cwiseProduct(K * s.cwiseProduct(z));
    lambda = z.dot(y);
    z = y;
  }
  return safety * std::sqrt(std::max(lambda, 0.0));
}

}  // namespace medspring
