#include "medspring/physics/compression_terms.hpp"

#include <algorithm>
#include <cmath>

#include "compression_rows.hpp"
#include "medspring/core/check.hpp"

namespace medspring {

namespace {

// One term at x: corners, edges from corner a, volume gradient g (dV/dx per corner), V.
struct At {
  Index id[4];
  Vec3 e[3];
  Vec3 g[4];
  double V;
};

inline Vec3 row(const double* x, Index i) {
  return {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
}

inline At term_at(const CompressionTerms& T, const double* x, Index t) {
  At r;
  r.id[0] = T.a[t];
  r.id[1] = T.b[t];
  r.id[2] = T.c[t];
  r.id[3] = T.d[t];
  const Vec3 xa = row(x, r.id[0]);
  for (int k = 0; k < 3; ++k) r.e[k] = row(x, r.id[k + 1]) - xa;
  r.g[1] = r.e[1].cross(r.e[2]) / 6.0;
  r.g[2] = r.e[2].cross(r.e[0]) / 6.0;
  r.g[3] = r.e[0].cross(r.e[1]) / 6.0;
  r.g[0] = -(r.g[1] + r.g[2] + r.g[3]);
  r.V = r.e[0].dot(r.g[1]);
  return r;
}

inline double longest_edge(const At& r) {
  return std::max({r.e[0].norm(), r.e[1].norm(), r.e[2].norm(), (r.e[1] - r.e[0]).norm(),
                   (r.e[2] - r.e[0]).norm(), (r.e[2] - r.e[1]).norm()});
}

inline Mat3 skew(const Vec3& v) {
  Mat3 S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

// The 12 x 12 Hessian of the term at r: kc / V0 h'' g g^T + kc h' d^2V. d^2V: d g_1 / d x_2 = -[e3]x / 6,
// d g_1 / d x_3 = [e2]x / 6, and cyclically (e_k = x_k - x_0); corner a's rows and columns follow from the
// translation invariance (each block row sums to zero).
Eigen::Matrix<double, 12, 12> hessian(const At& r, double kc, double V0, const CompressionH& hj,
                                      bool gauss_newton) {
  Eigen::Matrix<double, 12, 12> H;
  H.setZero();
  const double a = kc / V0 * hj.d2;
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < 4; ++l) H.block<3, 3>(3 * k, 3 * l) = a * r.g[k] * r.g[l].transpose();
  if (gauss_newton || hj.d1 == 0.0) return H;
  Mat3 D[4][4];
  for (auto& rowb : D)
    for (auto& b : rowb) b.setZero();
  // corners 1..3 = b, c, d (edges e[0..2])
  D[1][2] = -skew(r.e[2]) / 6.0;
  D[1][3] = skew(r.e[1]) / 6.0;
  D[2][3] = -skew(r.e[0]) / 6.0;
  D[2][1] = D[1][2].transpose();
  D[3][1] = D[1][3].transpose();
  D[3][2] = D[2][3].transpose();
  for (int k = 1; k < 4; ++k) {
    D[k][0] = -(D[k][1] + D[k][2] + D[k][3]);
    D[0][k] = D[k][0].transpose();
  }
  D[0][0] = -(D[0][1] + D[0][2] + D[0][3]);
  const double b = kc * hj.d1;
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < 4; ++l) H.block<3, 3>(3 * k, 3 * l) += b * D[k][l];
  return H;
}

}  // namespace

CompressionH compression_h(double J) {
  if (J >= 1.0) return {};
  if (J >= kCompressionJMin) {
    const double u = J - 1.0;
    return {u - std::log(J) - 0.5 * u * u, 1.0 - 1.0 / J - u, 1.0 / (J * J) - 1.0};
  }
  const CompressionH m = compression_h(kCompressionJMin);
  const double t = J - kCompressionJMin;
  return {m.h + m.d1 * t + 0.5 * m.d2 * t * t, m.d1 + m.d2 * t, m.d2};
}

void finalize_compression_terms(CompressionTerms& T, const MatX3& x0, const std::string& w) {
  const auto nt = static_cast<std::size_t>(T.size());
  require(T.b.size() == nt && T.c.size() == nt && T.d.size() == nt && T.kc.size() == nt, w,
          ": compression terms arrays have inconsistent sizes");
  T.V0.resize(nt);
  const Index n = static_cast<Index>(x0.rows());
  for (Index t = 0; t < T.size(); ++t) {
    const Index id[4] = {T.a[t], T.b[t], T.c[t], T.d[t]};
    for (int k = 0; k < 4; ++k) {
      require(id[k] >= 0 && id[k] < n, w, ": compression[", t, "]: node ", id[k], " out of range [0, ", n,
              ")");
      for (int l = 0; l < k; ++l)
        require(id[k] != id[l], w, ": compression[", t, "]: node ", id[k],
                " repeated (degenerate tetrahedron)");
    }
    const auto s = static_cast<std::size_t>(t);
    require(std::isfinite(T.kc[s]) && T.kc[s] >= 0, w, ": compression[", t, "].kc: must be >= 0 (got ",
            T.kc[s], ")");
    const At r = term_at(T, x0.data(), t);
    const double L = longest_edge(r);
    require(std::abs(r.V) > 1e-12 * L * L * L, w, ": compression[", t, "]: degenerate tetrahedron (nodes ",
            id[0], " ", id[1], " ", id[2], " ", id[3], ", volume ", r.V, " mm^3)");
    require(r.V > 0, w, ": compression[", t, "]: inverted tetrahedron (nodes ", id[0], " ", id[1], " ", id[2],
            " ", id[3], ", volume ", r.V, " mm^3)");
    T.V0[s] = r.V;
  }
}

namespace {

// h' and h'' of compression_h (the same expressions, so the same bits) without h itself: the force and bound
// passes need no logarithm.
inline CompressionH compression_dh(double J) {
  if (J >= kCompressionJMin) return {0.0, 1.0 - 1.0 / J - (J - 1.0), 1.0 / (J * J) - 1.0};
  constexpr double Jm = kCompressionJMin;
  const double d1m = 1.0 - 1.0 / Jm - (Jm - 1.0), d2m = 1.0 / (Jm * Jm) - 1.0;
  return {0.0, d1m + d2m * (J - Jm), d2m};
}

// The per-corner data of the block bound of a compressed term (compression_terms.hpp): r_k = s_k / |g_k| =
// (m_k |g_k|^2)^-1/2, s_k = r_k |g_k| (no division beyond one per corner), sigma = sum s_k |g_k|, and the
// weights w_k = a sigma r_k of the blocks w_k g_k g_k^T and beta_k = |b| L_max / 6 s_k sum_{l != k} s_l.
struct BlockTerm {
  double w[4], beta[4];
};
inline BlockTerm block_term(const At& r, double kc, double V0, const CompressionH& hj, const double* mass,
                            const std::uint8_t* fixed) {
  const double a = kc / V0 * hj.d2;  // >= 0: h'' > 0 below J = 1
  const double L2 = std::max({r.e[0].squaredNorm(), r.e[1].squaredNorm(), r.e[2].squaredNorm(),
                              (r.e[1] - r.e[0]).squaredNorm(), (r.e[2] - r.e[0]).squaredNorm(),
                              (r.e[2] - r.e[1]).squaredNorm()});
  const double hb = std::abs(kc * hj.d1) * std::sqrt(L2) / 6.0;  // norm bound of a d^2V block
  double is[4], ir[4], sigma = 0, ssum = 0;
  for (int k = 0; k < 4; ++k) {
    const double gg = r.g[k].squaredNorm();
    if (fixed[r.id[k]]) {
      is[k] = ir[k] = 0.0;
    } else if (gg > 0) {
      ir[k] = 1.0 / std::sqrt(mass[r.id[k]] * gg);
      is[k] = ir[k] * std::sqrt(gg);
    } else {
      ir[k] = 0.0;  // no gradient at this corner: no rank-one part there
      is[k] = 1.0 / std::sqrt(mass[r.id[k]]);
    }
    sigma += ir[k] * gg;  // s_k |g_k|
    ssum += is[k];
  }
  BlockTerm bt;
  for (int k = 0; k < 4; ++k) {
    bt.w[k] = a * sigma * ir[k];
    bt.beta[k] = hb * is[k] * (ssum - is[k]);
  }
  return bt;
}

// max over nodes of the bound tr/3 + sqrt(2/3 |dev B|_F^2) >= lambda_max(B) of the 3x3 blocks in rows.
double block_rows_max(const double* rows, Index nodes) {
  double row_max = 0;
  for (Index n = 0; n < nodes; ++n) {
    const double* B = rows + kCompressionRowsPerNode * n;
    const double tr = B[0] + B[1] + B[2];
    if (tr <= row_max) continue;  // B is positive semi-definite: lambda_max(B) <= tr B
    const double m = tr / 3.0;    // lambda_max <= m + sqrt(2/3 |B - m I|_F^2)
    const double d0 = B[0] - m, d1 = B[1] - m, d2 = B[2] - m;
    const double dev2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * (B[3] * B[3] + B[4] * B[4] + B[5] * B[5]);
    row_max = std::max(row_max, m + std::sqrt(2.0 / 3.0 * dev2));
  }
  return row_max;
}

// Adds the forces of the compressed terms (when f is given); with Trace the traces of their 3x3 blocks into
// trows (#N), with Blocks the blocks into brows (kCompressionRowsPerNode #N); returns whether a term is
// compressed.
template <bool Trace, bool Blocks>
bool compression_pass(const CompressionTerms& T, const double* x, double* f, const double* mass,
                      const std::uint8_t* fixed, double* trows, double* brows) {
  bool any = false;
  for (Index t = 0; t < T.size(); ++t) {
    const auto i = static_cast<std::size_t>(t);
    const At r = term_at(T, x, t);
    const double J = r.V / T.V0[i];
    if (J >= 1.0) continue;  // zero in tension and at rest: no force, no curvature
    any = true;
    const CompressionH hj = compression_dh(J);  // h itself (a logarithm) is not needed here
    if (f) {
      const double c = -T.kc[i] * hj.d1;
      for (int k = 0; k < 4; ++k) {
        double* o = f + 3 * r.id[k];
        o[0] += c * r.g[k].x();
        o[1] += c * r.g[k].y();
        o[2] += c * r.g[k].z();
      }
    }
    if constexpr (Trace || Blocks) {
      const BlockTerm bt = block_term(r, T.kc[i], T.V0[i], hj, mass, fixed);
      for (int k = 0; k < 4; ++k) {
        const Vec3& g = r.g[k];
        const double w = bt.w[k], beta = bt.beta[k];
        if constexpr (Trace) trows[r.id[k]] += w * g.squaredNorm() + 3.0 * beta;
        if constexpr (Blocks) {
          double* B = brows + kCompressionRowsPerNode * r.id[k];
          B[0] += w * g.x() * g.x() + beta;
          B[1] += w * g.y() * g.y() + beta;
          B[2] += w * g.z() * g.z() + beta;
          B[3] += w * g.x() * g.y();
          B[4] += w * g.x() * g.z();
          B[5] += w * g.y() * g.z();
        }
      }
    }
  }
  return any;
}

double row_max(const double* rows, Index nodes) {
  double m = 0;
  for (Index n = 0; n < nodes; ++n) m = rows[n] > m ? rows[n] : m;
  return m;
}

}  // namespace

double add_compression_forces(const CompressionTerms& T, const double* x, double* f, const double* mass,
                              const std::uint8_t* fixed, double* rows, Index nodes) {
  if (!(mass && fixed && rows)) {
    compression_pass<false, false>(T, x, f, nullptr, nullptr, nullptr, nullptr);
    return 0.0;
  }
  std::fill(rows, rows + kCompressionRowsPerNode * nodes, 0.0);
  return compression_pass<false, true>(T, x, f, mass, fixed, nullptr, rows) ? block_rows_max(rows, nodes)
                                                                            : 0.0;
}

double add_compression_forces_trace(const CompressionTerms& T, const double* x, double* f, const double* mass,
                                    const std::uint8_t* fixed, double* rows, Index nodes) {
  std::fill(rows, rows + nodes, 0.0);
  return compression_pass<true, false>(T, x, f, mass, fixed, rows, nullptr) ? row_max(rows, nodes) : 0.0;
}

double compression_block_bound(const CompressionTerms& T, const double* x, const double* mass,
                               const std::uint8_t* fixed, double* rows, Index nodes) {
  std::fill(rows, rows + kCompressionRowsPerNode * nodes, 0.0);
  return compression_pass<false, true>(T, x, nullptr, mass, fixed, nullptr, rows)
             ? block_rows_max(rows, nodes)
             : 0.0;
}

double compression_block_max(const double* rows, Index nodes) {
  return block_rows_max(rows, nodes);
}

double compression_energy(const CompressionTerms& T, const MatX3& x) {
  double e = 0;
  for (Index t = 0; t < T.size(); ++t) {
    const auto i = static_cast<std::size_t>(t);
    const double J = term_at(T, x.data(), t).V / T.V0[i];
    e += T.kc[i] * T.V0[i] * compression_h(J).h;
  }
  return e;
}

std::uint64_t count_inverted(const CompressionTerms& T, const MatX3& x) {
  std::uint64_t n = 0;
  for (Index t = 0; t < T.size(); ++t) n += term_at(T, x.data(), t).V <= 0.0 ? 1 : 0;
  return n;
}

void add_compression_stiffness_product(const CompressionTerms& T, const MatX3& x, const VecX& p, VecX& y,
                                       bool gauss_newton) {
  for (Index t = 0; t < T.size(); ++t) {
    const auto i = static_cast<std::size_t>(t);
    const At r = term_at(T, x.data(), t);
    const double J = r.V / T.V0[i];
    if (J >= 1.0) continue;
    const auto H = hessian(r, T.kc[i], T.V0[i], compression_h(J), gauss_newton);
    Eigen::Matrix<double, 12, 1> q;
    for (int k = 0; k < 4; ++k) q.segment<3>(3 * k) = p.segment<3>(3 * r.id[k]);
    const Eigen::Matrix<double, 12, 1> hq = H * q;
    for (int k = 0; k < 4; ++k) y.segment<3>(3 * r.id[k]) += hq.segment<3>(3 * k);
  }
}

void add_compression_stiffness_triplets(const CompressionTerms& T, const MatX3& x,
                                        std::vector<Eigen::Triplet<double>>& out) {
  for (Index t = 0; t < T.size(); ++t) {
    const auto i = static_cast<std::size_t>(t);
    const At r = term_at(T, x.data(), t);
    const double J = r.V / T.V0[i];
    if (J >= 1.0) continue;
    const auto H = hessian(r, T.kc[i], T.V0[i], compression_h(J), false);
    for (int k = 0; k < 4; ++k)
      for (int l = 0; l < 4; ++l)
        for (int u = 0; u < 3; ++u)
          for (int v = 0; v < 3; ++v)
            out.emplace_back(3 * r.id[k] + u, 3 * r.id[l] + v, H(3 * k + u, 3 * l + v));
  }
}

void add_compression_gershgorin(const CompressionTerms& T, const MatX3& x, const VecX& mass,
                                const std::vector<std::uint8_t>& fixed, VecX& diag, VecX& off) {
  for (Index t = 0; t < T.size(); ++t) {
    const auto i = static_cast<std::size_t>(t);
    const At r = term_at(T, x.data(), t);
    const double J = r.V / T.V0[i];
    if (J >= 1.0) continue;
    const CompressionH hj = compression_h(J);
    const double a = T.kc[i] / T.V0[i] * hj.d2;
    const double hb = std::abs(T.kc[i] * hj.d1) * longest_edge(r) / 3.0;  // bound of a d^2V block
    for (int k = 0; k < 4; ++k) {
      const Index n = r.id[k];
      diag[n] += a * r.g[k].squaredNorm() + hb;
      for (int l = 0; l < 4; ++l) {
        if (l == k) continue;
        const Index m = r.id[l];
        if (fixed[static_cast<std::size_t>(m)]) continue;
        off[n] += (a * r.g[k].norm() * r.g[l].norm() + hb) / std::sqrt(mass[n] * mass[m]);
      }
    }
  }
}

}  // namespace medspring
