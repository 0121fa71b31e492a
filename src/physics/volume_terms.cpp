#include "medspring/physics/volume_terms.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "compression_rows.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/compression_terms.hpp"
#include "tet_kernel.hpp"
#include "volume_f32.hpp"  // detail::packed_record_inverted

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

inline double volume_of(const Tet& q) {
  return q.e1.dot(q.e2.cross(q.e3)) / 6.0;
}

// The per-term set-up every pass shares: corners, edges, volume gradient, V, V0 and kv of term t at x.
struct TermAt {
  Index id[4];
  Tet q;
  Vec3 g[4];
  double V, V0, kv;
};

inline TermAt term_at(const VolumeTerms& T, const double* x, Index t) {
  const auto u = static_cast<std::size_t>(t);
  TermAt r{{T.a[u], T.b[u], T.c[u], T.d[u]}, corners(T, x, t), {}, 0.0, T.V0[u], T.kv[u]};
  volume_gradient(r.q, r.g);
  r.V = volume_of(r.q);
  return r;
}

// The packed record of term t (no owned springs).
VolumeTerms::Packed record(const VolumeTerms& T, Index t) {
  const auto u = static_cast<std::size_t>(t);
  VolumeTerms::Packed r{};
  const Index id[4] = {T.a[u], T.b[u], T.c[u], T.d[u]};
  for (int k = 0; k < 4; ++k) r.n[k] = static_cast<std::int32_t>(id[k]);
  r.s[0] = r.s[1] = -1;
  r.alpha = T.kv[u] / (36.0 * T.V0[u]);
  r.V06 = 6.0 * T.V0[u];
  r.iG0 = T.G0[u] > 0 ? 1.0 / T.G0[u] : 0.0;
  r.kv = T.kv[u];
  r.kc6 = T.kc.size() == T.a.size() ? T.kc[u] / 6.0 : 0.0;
  return r;
}

}  // namespace

double signed_tet_volume(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  return (p1 - p0).dot((p2 - p0).cross(p3 - p0)) / 6.0;
}

// add_volume_forces, add_volume_and_compression_forces, add_volume_forces_inc and
// add_volume_and_compression_forces_inc: volume_passes.cpp (compiled without FP contraction).

double fused_compression_blocks(const VolumeTerms& T, const double* x, const double* s, double* brows,
                                Index nodes) {
  require(static_cast<Index>(T.packed.size()) == T.size() && T.kc.size() == T.packed.size(),
          "volume terms: not finalized or no fused compression terms");
  constexpr int R6 = kCompressionRowsPerNode;
  std::fill(brows, brows + R6 * nodes, 0.0);
  bool any = false;
  for (const auto& r : T.packed) {
    double P[4][3];
    detail::load_corners(r, x, P);
    double e[3][3], c[4][3];  // c[k]: 6 dV/dx of corner k
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) e[k][d] = P[k + 1][d] - P[0][d];
    detail::cross3(e[1], e[2], c[1]);
    detail::cross3(e[2], e[0], c[2]);
    detail::cross3(e[0], e[1], c[3]);
    for (int d = 0; d < 3; ++d) c[0][d] = -(c[1][d] + c[2][d] + c[3][d]);
    const double dv6 = e[0][0] * c[1][0] + e[0][1] * c[1][1] + e[0][2] * c[1][2] - r.V06;
    if (!(dv6 < 0.0)) continue;  // J >= 1: no curvature (the blocks' pass runs where most are compressed)
    any = true;
    const double l2 = detail::max_edge2(e);
    const detail::CompDh h = detail::compression_dh6(dv6, r.V06);
    const double iJ = r.V06 * r.V06 * h.r;
    const double d2 = detail::max_nb(iJ * iJ - 1.0, 0.0);
    const double a = 36.0 * r.kc6 * (h.W * h.r) * d2;          // kc h'' / V0
    const double hb = std::abs(r.kc6 * h.d1) * std::sqrt(l2);  // |kc h'| L_max / 6
    double gn[4], sk[4], S = 0.0, sigma = 0.0;
    for (int k = 0; k < 4; ++k) {
      gn[k] = std::sqrt(c[k][0] * c[k][0] + c[k][1] * c[k][1] + c[k][2] * c[k][2]) * (1.0 / 6.0);
      sk[k] = s[r.n[k]];
      S += sk[k];
      sigma += sk[k] * gn[k];
    }
    for (int k = 0; k < 4; ++k) {
      // w g g^T + beta I with g = c / 6, w = a sigma s_k / |g_k| (block_term): w / 36 c c^T
      const double w36 = gn[k] > 0.0 ? a * sigma * sk[k] / gn[k] * (1.0 / 36.0) : 0.0;
      const double beta = hb * sk[k] * (S - sk[k]);
      const double* g = c[k];
      double* B = brows + R6 * static_cast<std::ptrdiff_t>(r.n[k]);
      B[0] += w36 * g[0] * g[0] + beta;
      B[1] += w36 * g[1] * g[1] + beta;
      B[2] += w36 * g[2] * g[2] + beta;
      B[3] += w36 * g[0] * g[1];
      B[4] += w36 * g[0] * g[2];
      B[5] += w36 * g[1] * g[2];
    }
  }
  return any ? compression_block_max(brows, nodes) : 0.0;
}

bool fuse_compression_terms(VolumeTerms& T, const CompressionTerms& C) {
  T.kc.clear();
  const Index nt = T.size();
  if (nt == 0 || C.size() != nt || static_cast<Index>(T.packed.size()) != nt || T.planned_springs >= 0)
    return false;
  for (Index t = 0; t < nt; ++t)
    if (C.a[t] != T.a[t] || C.b[t] != T.b[t] || C.c[t] != T.c[t] || C.d[t] != T.d[t]) return false;
  T.kc = C.kc;
  for (Index t = 0; t < nt; ++t)
    T.packed[static_cast<std::size_t>(t)].kc6 = T.kc[static_cast<std::size_t>(t)] / 6.0;
  return true;
}

double volume_row_max(const VolumeTerms& T, const double* inc, double* rows, Index nodes) {
  require(T.rest_rows.size() == 4 * T.packed.size(), "volume terms: no rest rows (set_volume_rest_rows)");
  std::fill(rows, rows + nodes, 0.0);
  const double* rr = T.rest_rows.data();
  const std::size_t nt = T.packed.size();
  for (std::size_t t = 0; t < nt; ++t) {  // branch-free: about half the terms stiffen
    const auto& r = T.packed[t];
    const double d = inc[t];
    for (int k = 0; k < 4; ++k) rows[r.n[k]] += d * rr[4 * t + static_cast<std::size_t>(k)];
  }
  double m = 0.0;
  for (Index i = 0; i < nodes; ++i) m = rows[i] > m ? rows[i] : m;
  return m;
}

double add_volume_forces_local(const VolumeTerms& T, const double* x, double* f, double* rows, Index nodes,
                               double& row_max) {
  require(T.rest_rows.size() == 4 * T.packed.size(), "volume terms: no rest rows (set_volume_rest_rows)");
  double* inc = rows + nodes;
  const double sv = add_volume_forces_inc(T, x, f, inc);
  row_max = volume_row_max(T, inc, rows, nodes);
  return sv;
}

void set_volume_rest_rows(VolumeTerms& T, const MatX3& x0, const VecX& mass,
                          const std::vector<std::uint8_t>& fixed) {
  require(static_cast<Index>(T.packed.size()) == T.size(), "volume terms: rest rows before finalize");
  T.rest_rows.assign(4 * T.packed.size(), 0.0);
  for (std::size_t t = 0; t < T.packed.size(); ++t) {
    const auto& r = T.packed[t];
    const Index id[4] = {r.n[0], r.n[1], r.n[2], r.n[3]};
    const Vec3 xa = x0.row(id[0]).transpose();
    const Tet q{xa, x0.row(id[1]).transpose() - xa, x0.row(id[2]).transpose() - xa,
                x0.row(id[3]).transpose() - xa};
    Vec3 g[4];
    volume_gradient(q, g);
    const double c = r.kv * 6.0 / r.V06;  // kv / V0
    for (int k = 0; k < 4; ++k) {
      if (fixed[static_cast<std::size_t>(id[k])]) continue;
      double row = 0;
      for (int l = 0; l < 4; ++l) {
        if (fixed[static_cast<std::size_t>(id[l])]) continue;
        row += g[k].norm() * g[l].norm() / std::sqrt(mass[id[k]] * mass[id[l]]);
      }
      T.rest_rows[4 * t + static_cast<std::size_t>(k)] = c * row;
    }
  }
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
    const TermAt r = term_at(T, x0.data(), t);
    const double V = r.V;
    const double L = longest_edge(r.q);
    require(std::abs(V) > 1e-12 * L * L * L, w, ": volume[", t, "]: degenerate tetrahedron (nodes ", id[0],
            " ", id[1], " ", id[2], " ", id[3], ", volume ", V, " mm^3)");
    require(V > 0, w, ": volume[", t, "]: inverted tetrahedron (nodes ", id[0], " ", id[1], " ", id[2], " ",
            id[3], ", volume ", V, " mm^3)");
    T.V0[static_cast<std::size_t>(t)] = V;
    T.G0[static_cast<std::size_t>(t)] =
        r.g[0].squaredNorm() + r.g[1].squaredNorm() + r.g[2].squaredNorm() + r.g[3].squaredNorm();
  }
  require(n <= std::numeric_limits<std::int32_t>::max(), w, ": volume terms need node indices below 2^31");
  T.kc.clear();  // fuse_compression_terms sets it again
  T.packed.resize(nt);
  for (Index t = 0; t < T.size(); ++t) T.packed[static_cast<std::size_t>(t)] = record(T, t);
  T.owned_end[0] = T.owned_end[1] = T.owned_end[2] = T.size();
  T.loose_springs.clear();
  T.planned_springs = -1;
  T.rest_rows.clear();
}

void plan_owned_springs(VolumeTerms& T, const std::vector<Index>& si, const std::vector<Index>& sj,
                        Index nodes) {
  const Index nt = T.size(), ns = static_cast<Index>(si.size());
  require(static_cast<Index>(T.packed.size()) == nt, "volume terms: plan before finalize");
  require(ns <= std::numeric_limits<std::int32_t>::max(), "volume terms: more than 2^31 springs");
  // terms around each node (CSR)
  std::vector<Index> start(static_cast<std::size_t>(nodes) + 1, 0), around(static_cast<std::size_t>(4 * nt));
  const std::vector<Index>* corner[4] = {&T.a, &T.b, &T.c, &T.d};
  for (const auto* c : corner)
    for (Index v : *c) ++start[static_cast<std::size_t>(v) + 1];
  for (Index v = 0; v < nodes; ++v)
    start[static_cast<std::size_t>(v) + 1] += start[static_cast<std::size_t>(v)];
  {
    std::vector<Index> fill(start.begin(), start.end() - 1);
    for (Index t = 0; t < nt; ++t)
      for (const auto* c : corner)
        around[static_cast<std::size_t>(fill[static_cast<std::size_t>((*c)[t])]++)] = t;
  }
  // each spring to the term on its edge that owns the fewest so far (at most two), else loose
  std::vector<VolumeTerms::Packed> rec(static_cast<std::size_t>(nt));
  std::vector<int> owned(static_cast<std::size_t>(nt), 0);
  for (Index t = 0; t < nt; ++t) rec[static_cast<std::size_t>(t)] = record(T, t);
  T.loose_springs.clear();
  for (Index s = 0; s < ns; ++s) {
    const Index a = si[static_cast<std::size_t>(s)], b = sj[static_cast<std::size_t>(s)];
    Index best = -1;
    int p = 0, q = 0;
    for (Index k = start[static_cast<std::size_t>(a)]; k < start[static_cast<std::size_t>(a) + 1]; ++k) {
      const Index t = around[static_cast<std::size_t>(k)];
      const auto& r = rec[static_cast<std::size_t>(t)];
      int lp = -1, lq = -1;
      for (int c = 0; c < 4; ++c) {
        if (r.n[c] == a) lp = c;
        if (r.n[c] == b) lq = c;
      }
      if (lq < 0 || owned[static_cast<std::size_t>(t)] >= 2) continue;
      if (best < 0 || owned[static_cast<std::size_t>(t)] < owned[static_cast<std::size_t>(best)]) {
        best = t;
        p = lp;
        q = lq;
      }
    }
    if (best < 0) {
      T.loose_springs.push_back(s);
      continue;
    }
    auto& r = rec[static_cast<std::size_t>(best)];
    const int o = owned[static_cast<std::size_t>(best)]++;
    r.s[o] = static_cast<std::int32_t>(s);
    r.pq[o] = static_cast<std::uint8_t>(4 * p + q);
  }
  // grouped by the number owned, each group in term order
  T.packed.clear();
  for (int g = 0; g < 3; ++g) {
    for (Index t = 0; t < nt; ++t)
      if (owned[static_cast<std::size_t>(t)] == g) T.packed.push_back(rec[static_cast<std::size_t>(t)]);
    T.owned_end[g] = static_cast<Index>(T.packed.size());
  }
  T.planned_springs = ns;
  T.rest_rows.clear();  // in the former record order
}

double volume_energy(const VolumeTerms& T, const MatX3& x) {
  double e = 0;
  for (Index t = 0; t < T.size(); ++t) {
    const double V = volume_of(corners(T, x.data(), t));
    const double V0 = T.V0[static_cast<std::size_t>(t)];
    e += 0.5 * T.kv[static_cast<std::size_t>(t)] * (V - V0) * (V - V0) / V0;
  }
  return e;
}

namespace detail {
// Whether packed record i of T is inverted or flat (6V <= 0, or not finite) at X (flat 3 #N):
// count_inverted's test, one record (the float count's fallback, count_inverted_f32, calls it for the records
// it cannot decide).
bool packed_record_inverted(const VolumeTerms& T, const double* X, std::size_t i) {
  const auto& r = T.packed[i];
  const double* a = X + 3 * static_cast<std::ptrdiff_t>(r.n[0]);
  double e[3][3];
  for (int k = 0; k < 3; ++k) {
    const double* p = X + 3 * static_cast<std::ptrdiff_t>(r.n[k + 1]);
    for (int d = 0; d < 3; ++d) e[k][d] = p[d] - a[d];
  }
  const double v6 = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) +
                    e[0][1] * (e[1][2] * e[2][0] - e[1][0] * e[2][2]) +
                    e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
  return !(v6 > 0);
}
}  // namespace detail

// Scalar loads: GCC's vectorisation of this loop emulates the corner gathers with inserts and extracts and
// was 3-4x slower (56 against ~15 us at 2,000 nodes, BM_VolumetricKidneyPhases/4).
#if defined(__GNUC__) && !defined(__clang__)
__attribute__((optimize("no-tree-vectorize")))
#endif
std::uint64_t
count_inverted(const VolumeTerms& T, const MatX3& x) {
  const double* X = x.data();
  std::uint64_t n = 0;
  if (T.packed.size() == static_cast<std::size_t>(T.size())) {  // the packed corners (32-bit, one record)
    for (std::size_t i = 0; i < T.packed.size(); ++i) n += detail::packed_record_inverted(T, X, i);
    return n;
  }
  for (Index t = 0; t < T.size(); ++t) {
    if (!(volume_of(corners(T, X, t)) > 0)) ++n;
  }
  return n;
}

void add_volume_stiffness_product(const VolumeTerms& T, const MatX3& x, const VecX& p, VecX& y,
                                  bool gauss_newton) {
  for (Index t = 0; t < T.size(); ++t) {
    const TermAt r = term_at(T, x.data(), t);
    Vec3 pk[4], h[4];
    double gp = 0;
    for (int k = 0; k < 4; ++k) {
      pk[k] = p.segment<3>(3 * r.id[k]);
      gp += r.g[k].dot(pk[k]);
    }
    const double c1 = r.kv / r.V0 * gp;
    if (gauss_newton) {
      for (int k = 0; k < 4; ++k) y.segment<3>(3 * r.id[k]) += c1 * r.g[k];
      continue;
    }
    volume_gradient_derivative(r.q, pk, h);
    const double c2 = r.kv * (r.V - r.V0) / r.V0;
    for (int k = 0; k < 4; ++k) y.segment<3>(3 * r.id[k]) += c1 * r.g[k] + c2 * h[k];
  }
}

void add_volume_stiffness_triplets(const VolumeTerms& T, const MatX3& x,
                                   std::vector<Eigen::Triplet<double>>& out) {
  for (Index t = 0; t < T.size(); ++t) {
    const TermAt r = term_at(T, x.data(), t);
    const double c2 = r.kv * (r.V - r.V0) / r.V0;
    for (int l = 0; l < 4; ++l)
      for (int cl = 0; cl < 3; ++cl) {
        Vec3 pk[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
        pk[l][cl] = 1.0;
        Vec3 h[4];
        volume_gradient_derivative(r.q, pk, h);
        const Index col = 3 * r.id[l] + cl;
        for (int k = 0; k < 4; ++k)
          for (int c = 0; c < 3; ++c) {
            const double v = r.kv / r.V0 * r.g[k][c] * r.g[l][cl] + c2 * h[k][c];
            if (v != 0.0) out.emplace_back(3 * r.id[k] + c, col, v);
          }
      }
  }
}

void add_volume_gershgorin(const VolumeTerms& T, const MatX3& x, const VecX& mass,
                           const std::vector<std::uint8_t>& fixed, VecX& diag, VecX& off) {
  for (Index t = 0; t < T.size(); ++t) {
    const TermAt r = term_at(T, x.data(), t);
    const double hb =
        std::abs(r.kv * (r.V - r.V0) / r.V0) * longest_edge(r.q) / 3.0;  // bound of a d^2V block
    for (int k = 0; k < 4; ++k) {
      const Index i = r.id[k];
      diag[i] += r.kv / r.V0 * r.g[k].squaredNorm() + hb;
      for (int l = 0; l < 4; ++l) {
        if (l == k) continue;
        const Index j = r.id[l];
        if (fixed[static_cast<std::size_t>(j)]) continue;
        off[i] += (r.kv / r.V0 * r.g[k].norm() * r.g[l].norm() + hb) / std::sqrt(mass[i] * mass[j]);
      }
    }
  }
}

}  // namespace medspring
