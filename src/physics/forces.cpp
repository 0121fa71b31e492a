#include "medspring/physics/forces.hpp"

#include <algorithm>
#include <cmath>

#include "compression_rows.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/stability.hpp"
#include "spring_kernel.hpp"
#include "tet_kernel.hpp"
#include "volume_f32.hpp"

namespace medspring {

namespace {

constexpr double kMinLength = detail::kMinSpringLength;

// The compression terms are fused into the volume pass (fuse_compression_terms): the force passes without
// the stiffening bound (all sub-steps of a frame but its last) add their forces with the volume terms'. The
// pass with the bound keeps them separate: add_compression_forces evaluates the forces with the bound.
bool compression_fused(const Model& m) {
  return m.volume.size() > 0 && m.volume.kc.size() == static_cast<std::size_t>(m.volume.size());
}

// Spring pass of the force evaluation (vector form of eqs. 1 and 5, §1.3). Returns max kappa_s/k_s
// (1 without Stiff). A plain scalar scatter loop over the springs in their order.
template <bool Soft, bool Stiff>
double spring_forces(const Model& m, const double* x, double* f) {
  const detail::SpringArrays S(m);
  const Index ns = m.springs.size();
  double stiff = 1.0;
  for (Index s = 0; s < ns; ++s) {
    detail::add_spring_force<Soft, Stiff>(S, s, x, stiff, f);
  }
  return stiff;
}

// Fused pass of a model with volume terms (issue 23): one loop over the tetrahedra evaluates each volume
// term and the (at most two) springs it owns from its four corners, loaded and scattered once; the loose
// springs (on no tetrahedron edge, or beyond two per tetrahedron) follow in the plain loop. Returns the
// larger of the springs' max kappa/k and the terms' stiffening (1 without Stiff).
template <bool Soft, bool Stiff, bool Comp = false>
double fused_forces(const Model& m, const double* x, double* f) {
  if constexpr (!Comp && !Stiff) {
    if (compression_fused(m)) return fused_forces<Soft, Stiff, true>(m, x, f);  // with compression terms
  }
  const VolumeTerms& T = m.volume;
  const detail::SpringParams P{m.springs.L0.data(), m.springs.k.data(), m.springs.kp.data(), m.inv_k.data()};
  const VolumeTerms::Packed* R = T.packed.data();
  double ss = 1.0, sv = 1.0;
  Index t = 0;
  for (; t < T.owned_end[0]; ++t) detail::tet_record<0, Soft, Stiff, false, Comp>(R[t], P, x, f, ss, sv);
  for (; t < T.owned_end[1]; ++t) detail::tet_record<1, Soft, Stiff, false, Comp>(R[t], P, x, f, ss, sv);
  for (; t < T.owned_end[2]; ++t) detail::tet_record<2, Soft, Stiff, false, Comp>(R[t], P, x, f, ss, sv);
  const detail::SpringArrays S(m);
  for (const Index s : T.loose_springs) {
    detail::add_spring_force<Soft, Stiff>(S, s, x, ss, f);
  }
  return std::max(ss, sv);
}

// §5.2 bending option: g = k_b (D - D0), f_a -= g, f_b += 2 g, f_c -= g.
void bending_forces(const BendingTerms& B, const MatX3& x, MatX3& f) {
  for (Index t = 0; t < B.size(); ++t) {
    const Vec3 D = (x.row(B.a[t]) - 2.0 * x.row(B.b[t]) + x.row(B.c[t])).transpose();
    const Vec3 g = B.kb[t] * (D - B.D0.row(t).transpose());
    f.row(B.a[t]) -= g.transpose();
    f.row(B.b[t]) += 2.0 * g.transpose();
    f.row(B.c[t]) -= g.transpose();
  }
}

// Compression stiffening (issue 23, compression_terms.hpp): its forces and, for the stable step, the
// Gershgorin bound of its mass-scaled Hessian at x added to the others' bound (Weyl: omega^2 <= stiff
// omega_rest^2 + that bound). `rows`: scratch of kCompressionRowsPerNode #N doubles (State::stiff_rows; a
// local one when the caller has none).
double with_compression(const Model& m, const double* x, double* f, bool stiffening, double stiff,
                        double* rows) {
  if (m.compression.size() == 0) return stiff;
  if (!stiffening && compression_fused(m)) return stiff;  // its forces came with the volume pass
  if (!stiffening) {
    add_compression_forces(m.compression, x, f);
    return stiff;
  }
  VecX local;
  if (!rows) {
    local.resize(kCompressionRowsPerNode * m.num_nodes());
    rows = local.data();
  }
  const double w2 = m.omega_rest * m.omega_rest;
  const double b =
      add_compression_forces(m.compression, x, f, m.mass.data(), m.fixed.data(), rows, m.num_nodes());
  return w2 > 0 ? stiff + b / w2 : stiff;
}

}  // namespace

namespace detail {

bool volume_f32_substep(const Model& m, const LocalStiffening* local) {
  return m.volume.size() > 0 && m.volume_f32 && local && local->f32 &&
         (compression_fused(m) || m.compression.size() == 0);
}

namespace {

// The volume terms' forces and stiffening, then the compression terms' forces and bound (its scratch after
// the local rule's: compression_rows.hpp). The compression bound c (omega^2 / omega_rest^2, by Weyl) is added
// to whichever rule gives the volume terms' part, and the local rule's gate counts it: the rows are scattered
// where [s_springs + c, global + c] holds more than one sub-step count of the frame.
double volume_and_compression(const Model& m, const double* X, double* Fo, bool stiffening, double stiff,
                              const LocalStiffening* local) {
  const Index n = m.num_nodes();
  const double w2 = m.omega_rest * m.omega_rest;
  double* crows = local ? local->scratch + n + m.volume.size() : nullptr;
  if (m.volume.size() == 0) return with_compression(m, X, Fo, stiffening, stiff, crows);
  if (stiffening && local && m.volume.rest_rows.size() == 4 * m.volume.packed.size() && w2 > 0) {
    // Local stiffening (docs/volumetric-speed.md "Stable step"): with K_t(x) <= s_t K_t(x0) per term (the
    // assumption of the global rule), K(x) <= s_springs K(x0) + sum_t (s_t - 1)+ K_t(x0), so by Weyl
    // omega^2 <= s_springs omega_rest^2 + the Gershgorin bound of the sum, row_max. Never above the global
    // rule max(s_springs, s_terms), never below s_springs: scattered only where that range holds more
    // than one sub-step count (the same sub-steps as always scattering, without its cost elsewhere).
    // With the compression terms fused (compression_fused), the volume pass also adds their forces, as on
    // the other sub-steps, and the traces of their bound's blocks (below): no compression pass unless the
    // blocks themselves decide the sub-step count.
    const bool comp = m.compression.size() > 0, fused = compression_fused(m);
    double* trows = comp ? crows + kCompressionRowsPerNode * n : nullptr;  // the traces after the blocks
    double sv, ct = 0.0;
    // single precision (Model::volume_f32, volume_f32.hpp): this pass too, bound included
    const bool f32 = m.volume_f32 && local->f32 && (fused || !comp);
    if (fused) {
      double* s = trows + n;  // m_i^-1/2, 0 on a fixed node
      for (Index i = 0; i < n; ++i)
        s[i] = m.fixed[static_cast<std::size_t>(i)] ? 0.0 : 1.0 / std::sqrt(m.mass[i]);
      sv = f32 ? add_volume_and_compression_forces_inc_f32(*m.volume_f32, X, Fo, local->f32,
                                                           local->scratch + n, s, trows, local->par)
               : add_volume_and_compression_forces_inc(m.volume, X, Fo, local->scratch + n, s, trows, n);
      double tm = 0.0;
      for (Index i = 0; i < n; ++i) tm = trows[i] > tm ? trows[i] : tm;
      ct = tm / w2;
    } else if (f32) {
      sv = add_volume_and_compression_forces_inc_f32(*m.volume_f32, X, Fo, local->f32, local->scratch + n,
                                                     nullptr, nullptr, local->par);
    } else {
      sv = add_volume_forces_inc(m.volume, X, Fo, local->scratch + n);
      if (comp)
        ct = add_compression_forces_trace(m.compression, X, Fo, m.mass.data(), m.fixed.data(), trows, n) / w2;
    }
    const double global = std::max(stiff, sv);
    auto count = [&](double v) { return stable_substeps(m, v, local->frame_dt, local->safety); };
    // The result is R + c: R in [stiff, global] the volume terms' rule (exact once their rows are
    // scattered), c in [c_tr / 3, c_tr] the compression terms' block bound (c_tr: the largest trace of the
    // blocks, with the forces; the blocks themselves take a pass over the compressed terms). Each is refined
    // only while the range left holds more than one sub-step count: the same sub-steps as computing both
    // always.
    if (count(global + ct) <= count(stiff + ct / 3)) return global + ct;
    const double R =
        std::min(global, stiff + volume_row_max(m.volume, local->scratch + n, local->scratch, n) / w2);
    if (!comp || count(R + ct) <= count(R + ct / 3)) return R + ct;
    if (fused) return R + fused_compression_blocks(m.volume, X, trows + n, crows, n) / w2;
    return R + compression_block_bound(m.compression, X, m.mass.data(), m.fixed.data(), crows, n) / w2;
  }
  if (!stiffening && volume_f32_substep(m, local)) {
    // opt-in single precision (set_volume_single_precision; volume_f32.hpp): the sub-steps without the bound
    add_volume_and_compression_forces_f32(*m.volume_f32, X, Fo, local->f32, true, local->par);
    return stiff;
  }
  if (!stiffening && compression_fused(m)) {
    add_volume_and_compression_forces(m.volume, X, Fo);
    return stiff;
  }
  const double sv = add_volume_forces(m.volume, X, Fo, stiffening);
  return with_compression(m, X, Fo, stiffening, stiffening ? std::max(stiff, sv) : stiff, crows);
}

}  // namespace

double volume_forces(const Model& m, const double* X, double* Fo, bool stiffening, double stiff,
                     const LocalStiffening* local) {
  return volume_and_compression(m, X, Fo, stiffening, stiff, local);
}

double internal_forces(const Model& m, const MatX3& x, const MatX3& f_ext, MatX3& f, bool stiffening) {
  return internal_forces(m, x, f_ext, f, stiffening, nullptr);
}

namespace {
double internal_forces_terms(const Model& m, const MatX3& x, const MatX3& f_ext, MatX3& f, bool stiffening,
                             const LocalStiffening* local);
}  // namespace

double internal_forces(const Model& m, const MatX3& x, const MatX3& f_ext, MatX3& f, bool stiffening,
                       const LocalStiffening* local) {
  const double stiff = internal_forces_terms(m, x, f_ext, f, stiffening, local);
  if (m.thin.size() == 0) return stiff;  // issue 23: thin-tetrahedron terms (their growth bound: max)
  return std::max(stiff, add_thin_tet_forces(m.thin, x, f, stiffening));
}

namespace {
double internal_forces_terms(const Model& m, const MatX3& x, const MatX3& f_ext, MatX3& f, bool stiffening,
                             const LocalStiffening* local) {
  const double* X = x.data();
  double* Fo = f.data();
  return_forces(m, X, f_ext.data(), Fo, 0, m.num_nodes());  // external force and return springs (§1.4)
  double stiff = 1.0;
  if (m.volume.size() > 0 && m.volume.planned_springs == m.num_springs()) {  // fused pass (issue 23)
    if (m.has_soft_springs)
      stiff = stiffening ? fused_forces<true, true>(m, X, Fo) : fused_forces<true, false>(m, X, Fo);
    else
      stiff = stiffening ? fused_forces<false, true>(m, X, Fo) : fused_forces<false, false>(m, X, Fo);
    if (m.bending.size() > 0) bending_forces(m.bending, x, f);
    return with_compression(m, X, Fo, stiffening, stiff, local ? local->scratch : nullptr);
  }
  if (m.has_soft_springs)
    stiff = stiffening ? spring_forces<true, true>(m, X, Fo) : spring_forces<true, false>(m, X, Fo);
  else
    stiff = stiffening ? spring_forces<false, true>(m, X, Fo) : spring_forces<false, false>(m, X, Fo);
  if (m.bending.size() > 0) bending_forces(m.bending, x, f);
  if (m.volume.size() > 0 || m.compression.size() > 0)
    stiff = volume_forces(m, X, Fo, stiffening, stiff, local);
  return stiff;
}
}  // namespace

}  // namespace detail

double internal_forces(const Model& m, const MatX3& x, const MatX3& f_ext, MatX3& f) {
  return detail::internal_forces(m, x, f_ext, f, true);
}

double potential_energy(const Model& m, const MatX3& x) {
  double e = 0;
  for (Index a = 0; a < m.num_nodes(); ++a) e += 0.5 * m.kr[a] * (x.row(a) - m.x0.row(a)).squaredNorm();
  const Springs& S = m.springs;
  for (Index s = 0; s < S.size(); ++s) {
    const double L = (x.row(S.j[s]) - x.row(S.i[s])).norm();
    if (L < kMinLength) continue;
    e += spring_energy(S.k[s], S.kp[s], L - S.L0[s]);
  }
  const BendingTerms& B = m.bending;
  for (Index t = 0; t < B.size(); ++t) {
    const Vec3 D = (x.row(B.a[t]) - 2.0 * x.row(B.b[t]) + x.row(B.c[t])).transpose();
    e += 0.5 * B.kb[t] * (D - B.D0.row(t).transpose()).squaredNorm();
  }
  if (m.volume.size() > 0) e += volume_energy(m.volume, x);
  if (m.compression.size() > 0) e += compression_energy(m.compression, x);
  if (m.thin.size() > 0) e += thin_tet_energy(m.thin, x);
  return e;
}

double total_energy(const Model& m, const MatX3& x, const MatX3& v) {
  double e = potential_energy(m, x);
  for (Index a = 0; a < m.num_nodes(); ++a) e += 0.5 * m.mass[a] * v.row(a).squaredNorm();
  return e;
}

Eigen::SparseMatrix<double> tangent_stiffness(const Model& m, const MatX3& x, const StiffnessOptions& opt) {
  const Index n = m.num_nodes();
  std::vector<Eigen::Triplet<double>> T;
  T.reserve(static_cast<std::size_t>(m.num_springs()) * 36 + static_cast<std::size_t>(n) * 3 +
            static_cast<std::size_t>(m.bending.size()) * 81);
  auto block = [&](Index r, Index c, const Mat3& B) {
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q) T.emplace_back(3 * r + p, 3 * c + q, B(p, q));
  };
  if (opt.include_return)
    for (Index a = 0; a < n; ++a)
      for (int p = 0; p < 3; ++p) T.emplace_back(3 * a + p, 3 * a + p, m.kr[a]);
  const Springs& S = m.springs;
  for (Index s = 0; s < S.size(); ++s) {
    const Vec3 e = (x.row(S.j[s]) - x.row(S.i[s])).transpose();
    const double L = e.norm();
    if (L < kMinLength) continue;
    const Vec3 nh = e / L;
    const double d = L - S.L0[s];
    const double phi = spring_tension(S.k[s], S.kp[s], d);
    const double dphi = spring_tension_derivative(S.k[s], S.kp[s], d);
    double tr = phi / L;
    if (opt.clamp_transverse) tr = std::max(tr, 0.0);
    const Mat3 nn = nh * nh.transpose();
    const Mat3 Ks = dphi * nn + tr * (Mat3::Identity() - nn);  // §1.3
    block(S.i[s], S.i[s], Ks);
    block(S.j[s], S.j[s], Ks);
    block(S.i[s], S.j[s], -Ks);
    block(S.j[s], S.i[s], -Ks);
  }
  const BendingTerms& B = m.bending;
  for (Index t = 0; t < B.size(); ++t) {
    const Index idx[3] = {B.a[t], B.b[t], B.c[t]};
    const double w[3] = {1.0, -2.0, 1.0};
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q) block(idx[p], idx[q], B.kb[t] * w[p] * w[q] * Mat3::Identity());
  }
  if (m.volume.size() > 0) add_volume_stiffness_triplets(m.volume, x, T);
  if (m.compression.size() > 0) add_compression_stiffness_triplets(m.compression, x, T);
  if (m.thin.size() > 0) add_thin_tet_stiffness_triplets(m.thin, x, T);  // co-rotated (Gauss-Newton)
  Eigen::SparseMatrix<double> K(3 * n, 3 * n);
  K.setFromTriplets(T.begin(), T.end());
  return K;
}

double max_residual(const Model& m, const MatX3& x, const MatX3& f_ext) {
  MatX3 f(m.num_nodes(), 3);
  internal_forces(m, x, f_ext, f);
  double r = 0;
  for (Index a : m.free_nodes) r = std::max(r, f.row(a).norm());
  return r;
}

}  // namespace medspring
