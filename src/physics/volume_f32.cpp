// The single-precision volume pass (volume_f32.hpp; issue 23, docs/volumetric-speed.md "A single-precision
// volume pass"). GCC on x86 (SSE2): 4-float GCC vector extensions, the corners loaded and the forces added 16
// bytes at a time. Elsewhere (Clang: the sanitizer and fuzz builds) the same arithmetic on a plain 4-float
// struct.
#include "volume_f32.hpp"

#include <atomic>
#include <cstddef>
#include <cstring>
#include <limits>
#include <memory>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "f32_lanes.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/compression_terms.hpp"
#include "medspring/physics/model.hpp"
#include "spring_f32.hpp"
#include "spring_gather.hpp"

namespace medspring {

namespace {

#if defined(__GNUC__) && !defined(__clang__) && defined(__SSE2__)
#define MEDSPRING_VOLUME_F32_VECTOR 1
typedef float F4 __attribute__((vector_size(16)));
typedef int I4 __attribute__((vector_size(16)));
inline F4 yzx(F4 a) {
  return __builtin_shuffle(a, I4{1, 2, 0, 3});
}
inline F4 zxy(F4 a) {
  return __builtin_shuffle(a, I4{2, 0, 1, 3});
}
inline F4 splat(float s) {
  return F4{s, s, s, s};
}
inline F4 with_w(F4 a, float w) {  // a with its fourth lane set to w
  a[3] = w;
  return a;
}
#else
struct F4 {
  float v[4];
  float operator[](int i) const { return v[i]; }
};
inline F4 operator+(F4 a, F4 b) {
  return {{a.v[0] + b.v[0], a.v[1] + b.v[1], a.v[2] + b.v[2], a.v[3] + b.v[3]}};
}
inline F4 operator-(F4 a, F4 b) {
  return {{a.v[0] - b.v[0], a.v[1] - b.v[1], a.v[2] - b.v[2], a.v[3] - b.v[3]}};
}
inline F4 operator*(F4 a, F4 b) {
  return {{a.v[0] * b.v[0], a.v[1] * b.v[1], a.v[2] * b.v[2], a.v[3] * b.v[3]}};
}
inline F4 operator-(F4 a) {
  return {{-a.v[0], -a.v[1], -a.v[2], -a.v[3]}};
}
inline F4 yzx(F4 a) {
  return {{a.v[1], a.v[2], a.v[0], a.v[3]}};
}
inline F4 zxy(F4 a) {
  return {{a.v[2], a.v[0], a.v[1], a.v[3]}};
}
inline F4 splat(float s) {
  return {{s, s, s, s}};
}
inline F4 with_w(F4 a, float w) {
  a.v[3] = w;
  return a;
}
#endif

inline F4 ld(const float* p) {
  F4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void st(float* p, F4 v) {
  std::memcpy(p, &v, sizeof v);
}
// u x v (the fourth lane: a3 b3 - a3 b3 = 0 for finite lanes)
inline F4 cross(F4 a, F4 b) {
  return yzx(a) * zxy(b) - zxy(a) * yzx(b);
}
inline float dot3(F4 a, F4 b) {
  const F4 p = a * b;
  return p[0] + p[1] + p[2];
}
// min and max as minss / maxss (no branch on J < 1 or J < J_min; tet_kernel.hpp's min_nb, max_nb)
inline float min_f(float a, float b) {
#if defined(__SSE2__)
  return _mm_cvtss_f32(_mm_min_ss(_mm_set_ss(a), _mm_set_ss(b)));
#else
  return a < b ? a : b;
#endif
}
inline float max_f(float a, float b) {
#if defined(__SSE2__)
  return _mm_cvtss_f32(_mm_max_ss(_mm_set_ss(a), _mm_set_ss(b)));
#else
  return a > b ? a : b;
#endif
}

// The outputs of the pass with the stable step's bound (Stiff): the records' 1 / G0, the increments
// (s_t - 1)+ per record (doubles, for volume_row_max), and the largest s_t so far.
struct StiffOut {
  const float* iG0;
  double* inc;
  float sv;
};

// The tetrahedron's forces: f_k = s (6 dV/dx_k), s = -alpha (6V - 6V0) - kc h'(J) / 6 (tet_record with Comp,
// compression_dh6, in float). u: the displacement mirror (4 floats a node), g: the force mirror.
// With Stiff, also the stable step's bound of tet_record with Stiff and Local (record t's curvature growth
// s_t, into so), and with Comp the compression bound's traces (compression_trace): u's fourth float holds
// m_i^-1/2 and g's fourth float gathers the traces (the forces' fourth lane is set to them).
template <bool Comp, bool Diff, bool Stiff = false>
[[gnu::always_inline]] inline void record_f32(const VolumeTermsF32::Record& r, const float* u, float* g,
                                              StiffOut* so = nullptr, std::size_t t = 0) {
  const F4 u0 = ld(u + 4 * static_cast<std::ptrdiff_t>(r.n[0]));
  const F4 u1 = ld(u + 4 * static_cast<std::ptrdiff_t>(r.n[1]));
  const F4 u2 = ld(u + 4 * static_cast<std::ptrdiff_t>(r.n[2]));
  const F4 u3 = ld(u + 4 * static_cast<std::ptrdiff_t>(r.n[3]));
  const F4 E0 = ld(r.E[0]), E1 = ld(r.E[1]), E2 = ld(r.E[2]);
  const F4 D0 = u1 - u0, D1 = u2 - u0, D2 = u3 - u0;
  const F4 e0 = E0 + D0, e1 = E1 + D1, e2 = E2 + D2;  // fourth lanes: not used (alpha, 6 V0, kc / 6 are E's)
  const F4 c0 = cross(e1, e2), c1 = cross(e2, e0), c2 = cross(e0, e1);
  const float alpha = E0[3], V06 = E1[3];
  float dv6;  // 6V - 6V0
  if constexpr (Diff)
    dv6 = dot3(D0, c0) + dot3(E0, cross(D1, e2) + cross(E1, D2));
  else
    dv6 = dot3(e0, c0) - V06;
  float s = -alpha * dv6;
  [[maybe_unused]] float W = 0.0f, rr = 0.0f, d1 = 0.0f;
  if constexpr (Comp) {  // compression_dh6, compression_scalar
    constexpr float jm = static_cast<float>(kCompressionJMin), d2m = 1.0f / (jm * jm) - 1.0f;
    const float kc6 = E2[3];
    const float lo = (jm - 1.0f) * V06;
    const float d = max_f(min_f(dv6, 0.0f), lo);
    const float bl = min_f(dv6 - lo, 0.0f);
    W = V06 + d;
    rr = 1.0f / (V06 * W);
    d1 = rr * (d2m * bl * W - d * d);
    s += -kc6 * d1;
  }
  const F4 S = splat(s);
  const F4 F1 = S * c0, F2 = S * c1, F3 = S * c2;
  const F4 F0 = -(F1 + F2 + F3);
  F4 Fk[4] = {F0, F1, F2, F3};
  // tet_record's bound: s_t = (|dV/dx|^2 + |V - V0| L_max / 2) / G0
  if constexpr (Stiff) {
    const F4 cs = c0 + c1 + c2;  // -6 dV/dx of corner a
    const float gg = dot3(c0, c0) + dot3(c1, c1) + dot3(c2, c2) + dot3(cs, cs);
    float l2 = max_f(max_f(dot3(e0, e0), dot3(e1, e1)), dot3(e2, e2));
    l2 = max_f(max_f(l2, dot3(e1 - e0, e1 - e0)), max_f(dot3(e2 - e1, e2 - e1), dot3(e0 - e2, e0 - e2)));
    const float sq = std::sqrt(l2);
    const float q = (gg * (1.0f / 36.0f) + std::abs(dv6) * sq * (1.0f / 12.0f)) * so->iG0[t];
    so->inc[t] = static_cast<double>(max_f(q - 1.0f, 0.0f));  // (s_t - 1)+; NaN gives 0, as the double pass
    so->sv = max_f(q, so->sv);                                // a NaN q leaves sv (the double pass's branch)
    float tr[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    if constexpr (Comp) {  // compression_trace
      const float kc6 = E2[3];
      const float iJ = V06 * V06 * rr;
      const float a = 36.0f * kc6 * (W * rr) * max_f(iJ * iJ - 1.0f, 0.0f);
      const float hb = std::abs(kc6 * d1) * sq;
      const float gn[4] = {std::sqrt(dot3(cs, cs)) * (1.0f / 6.0f), std::sqrt(dot3(c0, c0)) * (1.0f / 6.0f),
                           std::sqrt(dot3(c1, c1)) * (1.0f / 6.0f), std::sqrt(dot3(c2, c2)) * (1.0f / 6.0f)};
      const float sk[4] = {u0[3], u1[3], u2[3], u3[3]};
      const float Ss = sk[0] + sk[1] + sk[2] + sk[3];
      const float sigma = sk[0] * gn[0] + sk[1] * gn[1] + sk[2] * gn[2] + sk[3] * gn[3];
      for (int k = 0; k < 4; ++k) tr[k] = sk[k] * (a * sigma * gn[k] + 3.0f * hb * (Ss - sk[k]));
    }
    for (int k = 0; k < 4; ++k) Fk[k] = with_w(Fk[k], tr[k]);
  }
  for (int k = 0; k < 4; ++k) {
    float* o = g + 4 * static_cast<std::ptrdiff_t>(r.n[k]);
    st(o, ld(o) + Fk[k]);
  }
}

#if defined(MEDSPRING_VOLUME_F32_VECTOR) && defined(__AVX__)
#define MEDSPRING_VOLUME_F32_X8 1
// Eight records at a time in 256-bit vectors (one tetrahedron a lane): the corners' and the records' 4-float
// rows transposed in registers (no gathers), the arithmetic of record_f32 lane-wise (the same operations: the
// same numbers), the forces transposed back to 4-float rows and added record by record, corner by corner.
using detail::lanes::abs8;
using detail::lanes::cross8;
using detail::lanes::dot8;
using detail::lanes::F8;
using detail::lanes::lanes_to_rows;
using detail::lanes::max8;
using detail::lanes::min8;
using detail::lanes::rows_to_lanes;
using detail::lanes::sqrt8;

// The corners of records [i, i + 8) (their rows' float offsets in the mirrors, 4 n) and the lanes of their
// rest edges: from the blocks (Blk), or transposed from the records' rows (the former layout, for the A/B).
template <bool Blk>
[[gnu::always_inline]] inline void load_records8(const VolumeTermsF32& F, std::size_t i,
                                                 std::ptrdiff_t (&n)[4][8], F8 (&E)[3][4]) {
  if constexpr (Blk) {
    const VolumeTermsF32::Block& b = F.blk[i / 8];
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 8; ++j) n[k][j] = 4 * static_cast<std::ptrdiff_t>(b.n[k][j]);
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 4; ++d) E[k][d] = (F8)_mm256_load_ps(b.E[k][d]);
  } else {
    const VolumeTermsF32::Record* r = F.rec.data() + i;
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 8; ++j) n[k][j] = 4 * static_cast<std::ptrdiff_t>(r[j].n[k]);
    for (int k = 0; k < 3; ++k) {
      const float* const p[8] = {r[0].E[k], r[1].E[k], r[2].E[k], r[3].E[k],
                                 r[4].E[k], r[5].E[k], r[6].E[k], r[7].E[k]};
      rows_to_lanes(p, E[k]);
    }
  }
}

// The rows of the mirror u at the corners n[k][0..8) as x, y, z and w lanes.
[[gnu::always_inline]] inline void corner_lanes(const float* u, const std::ptrdiff_t (&n)[4][8],
                                                F8 (&U)[4][4]) {
  for (int k = 0; k < 4; ++k) {
    const float* const p[8] = {u + n[k][0], u + n[k][1], u + n[k][2], u + n[k][3],
                               u + n[k][4], u + n[k][5], u + n[k][6], u + n[k][7]};
    rows_to_lanes(p, U[k]);
  }
}

// record_f32 for the eight records [i0, i0 + 8), lane-wise; with Stiff, svv gathers the largest s_t lane by
// lane.
template <bool Comp, bool Diff, bool Stiff, bool Blk>
[[gnu::always_inline]] inline void records8_f32(const VolumeTermsF32& F, std::size_t i0, const float* u,
                                                float* g, StiffOut* so, F8* svv) {
  std::ptrdiff_t n[4][8];
  F8 U[4][4], E[3][4];
  load_records8<Blk>(F, i0, n, E);
  corner_lanes(u, n, U);
  const F8 alpha = E[0][3], V06 = E[1][3];
  F8 D[3][3], e[3][3], Ek[3][3];
  for (int k = 0; k < 3; ++k)
    for (int d = 0; d < 3; ++d) {
      D[k][d] = U[k + 1][d] - U[0][d];
      Ek[k][d] = E[k][d];
      e[k][d] = E[k][d] + D[k][d];
    }
  F8 c[3][3];
  cross8(e[1], e[2], c[0]);
  cross8(e[2], e[0], c[1]);
  cross8(e[0], e[1], c[2]);
  F8 dv6;
  if constexpr (Diff) {
    F8 a[3], b[3], ab[3];
    cross8(D[1], e[2], a);
    cross8(Ek[1], D[2], b);
    for (int d = 0; d < 3; ++d) ab[d] = a[d] + b[d];
    dv6 = dot8(D[0], c[0]) + dot8(Ek[0], ab);
  } else {
    dv6 = dot8(e[0], c[0]) - V06;
  }
  F8 s = -alpha * dv6;
  [[maybe_unused]] F8 W{}, rr{}, d1{};
  if constexpr (Comp) {
    constexpr float jm = static_cast<float>(kCompressionJMin), d2m = 1.0f / (jm * jm) - 1.0f;
    const F8 zero{}, kc6 = E[2][3];
    const F8 lo = (jm - 1.0f) * V06;
    const F8 d = max8(min8(dv6, zero), lo);
    const F8 bl = min8(dv6 - lo, zero);
    W = V06 + d;
    rr = 1.0f / (V06 * W);
    d1 = rr * (d2m * bl * W - d * d);
    s += -kc6 * d1;
  }
  F8 Fk[4][4];
  for (int d = 0; d < 3; ++d) {
    Fk[1][d] = s * c[0][d];
    Fk[2][d] = s * c[1][d];
    Fk[3][d] = s * c[2][d];
    Fk[0][d] = -(Fk[1][d] + Fk[2][d] + Fk[3][d]);
  }
  for (int k = 0; k < 4; ++k) Fk[k][3] = F8{};
  if constexpr (Stiff) {  // record_f32's bound, lane-wise
    F8 cs[3];
    for (int d = 0; d < 3; ++d) cs[d] = c[0][d] + c[1][d] + c[2][d];
    const F8 g0 = dot8(cs, cs), g1 = dot8(c[0], c[0]), g2 = dot8(c[1], c[1]), g3 = dot8(c[2], c[2]);
    F8 l2 = max8(max8(dot8(e[0], e[0]), dot8(e[1], e[1])), dot8(e[2], e[2]));
    for (int k = 0; k < 3; ++k) {
      const int j = (k + 1) % 3;
      F8 q[3];
      for (int d = 0; d < 3; ++d) q[d] = e[j][d] - e[k][d];
      l2 = max8(l2, dot8(q, q));
    }
    const F8 sq = sqrt8(l2);
    const F8 q = ((g0 + g1 + g2 + g3) * (1.0f / 36.0f) + abs8(dv6) * sq * (1.0f / 12.0f)) *
                 (F8)_mm256_loadu_ps(so->iG0 + i0);
    const F8 st1 = max8(q - 1.0f, F8{});
    _mm256_storeu_pd(so->inc + i0, _mm256_cvtps_pd(_mm256_castps256_ps128((__m256)st1)));
    _mm256_storeu_pd(so->inc + i0 + 4, _mm256_cvtps_pd(_mm256_extractf128_ps((__m256)st1, 1)));
    *svv = max8(q, *svv);
    if constexpr (Comp) {  // compression_trace
      const F8 kc6 = E[2][3];
      const F8 iJ = V06 * V06 * rr;
      const F8 a = 36.0f * kc6 * (W * rr) * max8(iJ * iJ - 1.0f, F8{});
      const F8 hb = abs8(kc6 * d1) * sq;
      const F8 gn[4] = {sqrt8(g0) * (1.0f / 6.0f), sqrt8(g1) * (1.0f / 6.0f), sqrt8(g2) * (1.0f / 6.0f),
                        sqrt8(g3) * (1.0f / 6.0f)};
      const F8 Ss = U[0][3] + U[1][3] + U[2][3] + U[3][3];
      const F8 as = a * (U[0][3] * gn[0] + U[1][3] * gn[1] + U[2][3] * gn[2] + U[3][3] * gn[3]);
      for (int k = 0; k < 4; ++k) Fk[k][3] = U[k][3] * (as * gn[k] + 3.0f * hb * (Ss - U[k][3]));
    }
  }
  for (int k = 0; k < 4; ++k) {
    __m256 q[4];
    lanes_to_rows(Fk[k], q);
    for (int j = 0; j < 4; ++j) {  // records j and j + 4, in the records' order
      float* o = g + n[k][j];
      _mm_storeu_ps(o, _mm_add_ps(_mm_loadu_ps(o), _mm256_castps256_ps128(q[j])));
    }
    for (int j = 0; j < 4; ++j) {
      float* o = g + n[k][j + 4];
      _mm_storeu_ps(o, _mm_add_ps(_mm_loadu_ps(o), _mm256_extractf128_ps(q[j], 1)));
    }
  }
}
#endif

std::atomic<bool> g_f32_x8{true};
std::atomic<bool> g_f32_blocks{true};

#if defined(MEDSPRING_VOLUME_F32_X8)
// The blocks of F are the layout of the eight-a-vector passes (and are on).
bool use_blocks(const VolumeTermsF32& F) {
  return g_f32_blocks.load(std::memory_order_relaxed) && F.blk.size() == F.rec.size() / 8;
}
#endif

#if defined(MEDSPRING_VOLUME_F32_X8)
// count_inverted_f32 for the eight records [i, i + 8): bit j of `inv` set when record j is inverted for sure,
// of `amb` when the float 6V cannot decide (within the band, or not finite).
template <bool Blk>
[[gnu::always_inline]] inline void inverted8(const VolumeTermsF32& F, std::size_t i, const float* u,
                                             unsigned& inv, unsigned& amb) {
  std::ptrdiff_t n[4][8];
  F8 U[4][4], E[3][4];
  load_records8<Blk>(F, i, n, E);
  corner_lanes(u, n, U);
  F8 D[3][3], e[3][3], Ek[3][3], a[3];
  F8 s[4];  // |u_k|_1
  for (int k = 0; k < 4; ++k) s[k] = abs8(U[k][0]) + abs8(U[k][1]) + abs8(U[k][2]);
  for (int k = 0; k < 3; ++k) {
    a[k] = s[k + 1] + s[0];
    for (int d = 0; d < 3; ++d) {
      D[k][d] = U[k + 1][d] - U[0][d];
      Ek[k][d] = E[k][d];
      e[k][d] = E[k][d] + D[k][d];
      a[k] += abs8(E[k][d]) + abs8(D[k][d]);  // a_k >= |E_k| + |D_k| + |u_k+1| + |u_0| >= |e_k|
    }
  }
  F8 c0[3], p1[3], p2[3], ab[3];
  cross8(e[1], e[2], c0);
  cross8(D[1], e[2], p1);
  cross8(Ek[1], D[2], p2);
  for (int d = 0; d < 3; ++d) ab[d] = p1[d] + p2[d];
  const F8 v6 = E[1][3] + (dot8(D[0], c0) + dot8(Ek[0], ab));  // 6 V0 + (6V - 6V0), record_f32's Diff form
  // The float 6V is within a few tens of eps_f a0 a1 a2 of the exact 6V of the positions (the roundings of
  // the displacements, the rest edges and 6 V0, and those of the products): 64 eps_f of it is certain.
  const F8 band = (64.0f * std::numeric_limits<float>::epsilon()) * (a[0] * a[1] * a[2]);
  inv = static_cast<unsigned>(_mm256_movemask_ps((__m256)(v6 < -band)));
  amb = static_cast<unsigned>(_mm256_movemask_ps((__m256)((v6 < -band) | (v6 > band)))) ^ 0xFFu;
}
#endif

// Records [r0, nr) (default: all) into the force mirror g.
template <bool Comp, bool Diff, bool Stiff = false>
void records_f32(const VolumeTermsF32& F, const float* u, float* g, StiffOut* so = nullptr,
                 std::size_t r0 = 0, std::size_t nr = std::numeric_limits<std::size_t>::max()) {
  const VolumeTermsF32::Record* r = F.rec.data();
  nr = nr < F.rec.size() ? nr : F.rec.size();
  std::size_t i = r0;
#if defined(MEDSPRING_VOLUME_F32_X8)
  if (g_f32_x8.load(std::memory_order_relaxed)) {
    for (; i < nr && i % 8 != 0; ++i) record_f32<Comp, Diff, Stiff>(r[i], u, g, so, i);  // to a block's start
    F8 svv = F8{} + 1.0f;
    if (use_blocks(F))
      for (; i + 8 <= nr; i += 8) records8_f32<Comp, Diff, Stiff, true>(F, i, u, g, so, &svv);
    else
      for (; i + 8 <= nr; i += 8) records8_f32<Comp, Diff, Stiff, false>(F, i, u, g, so, &svv);
    if constexpr (Stiff)
      for (int l = 0; l < 8; ++l) so->sv = max_f(svv[l], so->sv);
  }
#endif
  for (; i < nr; ++i) record_f32<Comp, Diff, Stiff>(r[i], u, g, so, i);
}

}  // namespace

void build_volume_f32(const VolumeTerms& T, const MatX3& x0, VolumeTermsF32& F) {
  require(static_cast<Index>(T.packed.size()) == T.size(), "volume terms (single precision): not finalized");
  const bool comp = !T.kc.empty();
  F.nodes = static_cast<Index>(x0.rows());
  F.comp = comp;
  F.x0.resize(static_cast<std::size_t>(3 * F.nodes));
  for (Index i = 0; i < F.nodes; ++i)
    for (int d = 0; d < 3; ++d) F.x0[static_cast<std::size_t>(3 * i + d)] = x0(i, d);
  F.rec.resize(T.packed.size());
  F.iG0.resize(T.packed.size());
  for (std::size_t t = 0; t < T.packed.size(); ++t) {
    const VolumeTerms::Packed& p = T.packed[t];
    VolumeTermsF32::Record& r = F.rec[t];
    for (int k = 0; k < 4; ++k) {
      require(p.n[k] >= 0 && p.n[k] < F.nodes, "volume terms (single precision): record ", t, " corner ", k,
              " out of range");
      r.n[k] = p.n[k];
    }
    for (int k = 0; k < 3; ++k) {
      for (int d = 0; d < 3; ++d) r.E[k][d] = static_cast<float>(x0(p.n[k + 1], d) - x0(p.n[0], d));
      r.E[k][3] = 0.0f;
    }
    // 6 V0: the kernel's own volume of the rounded edges (dot3(e0, c0) at u = 0), so that the rest is
    // exactly force-free also without Diff
    const F4 E0 = ld(r.E[0]), E1 = ld(r.E[1]), E2 = ld(r.E[2]);
    const float v06 = dot3(E0, cross(E1, E2));
    require(v06 > 0.0f, "volume terms (single precision): record ", t,
            " has no positive rest volume in float (6 V0 = ", v06, " mm^3)");
    r.E[0][3] = static_cast<float>(p.alpha);
    r.E[1][3] = v06;
    r.E[2][3] = comp ? static_cast<float>(p.kc6) : 0.0f;
    F.iG0[t] = static_cast<float>(p.iG0);
  }
  F.blk.resize(F.rec.size() / 8);
  for (std::size_t b = 0; b < F.blk.size(); ++b)
    for (int j = 0; j < 8; ++j) {
      const VolumeTermsF32::Record& r = F.rec[8 * b + static_cast<std::size_t>(j)];
      for (int k = 0; k < 4; ++k) F.blk[b].n[k][j] = r.n[k];
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 4; ++d) F.blk[b].E[k][d][j] = r.E[k][d];
    }
}

namespace {

// The pass's mirrors: u = x - x0 in float (4 floats a node, the fourth w[i], or 0 without w) and g = 0.
void fill_mirrors(const VolumeTermsF32& F, const double* x, float* u, float* g, const double* w) {
  const double* x0 = F.x0.data();
  for (Index i = 0; i < F.nodes; ++i) {
    for (int d = 0; d < 3; ++d) {
      u[4 * i + d] = static_cast<float>(x[3 * i + d] - x0[3 * i + d]);
      g[4 * i + d] = 0.0f;
    }
    u[4 * i + 3] = w ? static_cast<float>(w[i]) : 0.0f;
    g[4 * i + 3] = 0.0f;
  }
}

// f += the forces of the force mirror g.
void add_forces(const VolumeTermsF32& F, const float* g, double* f) {
  for (Index i = 0; i < F.nodes; ++i)
    for (int d = 0; d < 3; ++d) f[3 * i + d] += static_cast<double>(g[4 * i + d]);
}

// The threaded pass: share(t, g_t) on every thread of par, g_t the mirror g on the calling thread and the
// thread's own mirror, zeroed, on the others; then f += the mirrors' forces summed in thread order in double,
// and trows (unless null) gets their fourth floats summed the same way.
template <class Share>
void run_shares(const VolumeTermsF32& F, const ParallelRecords& par, float* g, double* f, double* trows,
                Share&& share) {
  const auto mf = 4 * static_cast<std::size_t>(F.nodes);
  auto run = [&](int t) {
    float* gt = t == 0 ? g : par.mirrors[static_cast<std::size_t>(t)];
    if (t > 0) std::memset(gt, 0, sizeof(float) * mf);
    share(t, gt);
  };
  par.pool->run(run);
  for (Index i = 0; i < F.nodes; ++i) {
    double v[4] = {0.0, 0.0, 0.0, 0.0};
    for (int t = 0; t < par.threads; ++t) {
      const float* gt = (t == 0 ? g : par.mirrors[static_cast<std::size_t>(t)]) + 4 * i;
      for (int d = 0; d < 4; ++d) v[d] += static_cast<double>(gt[d]);
    }
    for (int d = 0; d < 3; ++d) f[3 * i + d] += v[d];
    if (trows) trows[i] = v[3];
  }
}

}  // namespace

void add_volume_and_compression_forces_f32(const VolumeTermsF32& F, const double* x, double* f,
                                           float* scratch, bool diff, const ParallelRecords* par) {
  float* u = scratch;
  float* g = scratch + 4 * F.nodes;
  fill_mirrors(F, x, u, g, nullptr);
  if (par && par->threads > 1 && diff) {  // each thread its share into its mirror, summed in thread order
    run_shares(F, *par, g, f, nullptr, [&](int t, float* gt) {
      const auto ut = static_cast<std::size_t>(t);
      if (F.comp)
        records_f32<true, true>(F, u, gt, nullptr, par->begin[ut], par->begin[ut + 1]);
      else
        records_f32<false, true>(F, u, gt, nullptr, par->begin[ut], par->begin[ut + 1]);
    });
    return;
  }
  if (F.comp)
    diff ? records_f32<true, true>(F, u, g) : records_f32<true, false>(F, u, g);
  else
    diff ? records_f32<false, true>(F, u, g) : records_f32<false, false>(F, u, g);
  add_forces(F, g, f);
}

double add_volume_and_compression_forces_inc_f32(const VolumeTermsF32& F, const double* x, double* f,
                                                 float* scratch, double* inc, const double* s, double* trows,
                                                 const ParallelRecords* par) {
  require(F.iG0.size() == F.rec.size(), "volume terms (single precision): no rest curvatures");
  float* u = scratch;
  float* g = scratch + 4 * F.nodes;
  fill_mirrors(F, x, u, g, F.comp ? s : nullptr);  // m_i^-1/2 in u's fourth floats, for the traces
  if (!par || par->threads <= 1) {
    StiffOut so{F.iG0.data(), inc, 1.0f};
    if (F.comp)
      records_f32<true, true, true>(F, u, g, &so);
    else
      records_f32<false, true, true>(F, u, g, &so);
    add_forces(F, g, f);
    if (F.comp)
      for (Index i = 0; i < F.nodes; ++i) trows[i] = static_cast<double>(g[4 * i + 3]);
    return static_cast<double>(so.sv);
  }
  // the threads' shares: each its own mirror (thread 0 the one filled above) and largest s_t
  float sv[kMaxThreads];
  run_shares(F, *par, g, f, F.comp ? trows : nullptr, [&](int t, float* gt) {
    const auto ut = static_cast<std::size_t>(t);
    StiffOut so{F.iG0.data(), inc, 1.0f};
    if (F.comp)
      records_f32<true, true, true>(F, u, gt, &so, par->begin[ut], par->begin[ut + 1]);
    else
      records_f32<false, true, true>(F, u, gt, &so, par->begin[ut], par->begin[ut + 1]);
    sv[ut] = so.sv;
  });
  float svm = 1.0f;
  for (int t = 0; t < par->threads; ++t) svm = max_f(sv[static_cast<std::size_t>(t)], svm);
  return static_cast<double>(svm);
}

namespace {

// count_inverted_f32 of records [i, nr), the displacement mirror u filled
std::uint64_t count_range(const VolumeTermsF32& F, const VolumeTerms& T, const double* x, const float* u,
                          std::size_t i, std::size_t nr) {
  std::uint64_t n = 0;
#if defined(MEDSPRING_VOLUME_F32_X8)
  if (g_f32_x8.load(std::memory_order_relaxed)) {
    for (; i < nr && i % 8 != 0; ++i) n += detail::packed_record_inverted(T, x, i);  // to a block's start
    const bool blocks = use_blocks(F);
    for (; i + 8 <= nr; i += 8) {
      unsigned inv = 0, amb = 0;
      if (blocks)
        inverted8<true>(F, i, u, inv, amb);
      else
        inverted8<false>(F, i, u, inv, amb);
      n += static_cast<std::uint64_t>(__builtin_popcount(inv));
      for (; amb != 0; amb &= amb - 1)  // the records the float 6V cannot decide: the double test
        n += detail::packed_record_inverted(T, x, i + static_cast<std::size_t>(__builtin_ctz(amb)));
    }
  }
#else
  (void)u;
#endif
  for (; i < nr; ++i) n += detail::packed_record_inverted(T, x, i);
  return n;
}

}  // namespace

std::uint64_t count_inverted_f32(const VolumeTermsF32& F, const VolumeTerms& T, const double* x,
                                 float* scratch, const ParallelRecords* par) {
  require(T.packed.size() == F.rec.size(), "volume terms (single precision): ", F.rec.size(), " records for ",
          T.packed.size(), " terms");
  detail::fill_displacements_f32(F, x, scratch);
  if (!par || par->threads <= 1) return count_range(F, T, x, scratch, 0, F.rec.size());
  std::uint64_t counts[kMaxThreads];
  auto run = [&](int t) {
    const auto ut = static_cast<std::size_t>(t);
    counts[ut] = count_range(F, T, x, scratch, par->begin[ut], par->begin[ut + 1]);
  };
  par->pool->run(run);
  std::uint64_t n = 0;
  for (int t = 0; t < par->threads; ++t) n += counts[static_cast<std::size_t>(t)];
  return n;
}

void set_volume_single_precision(Model& m, bool on) {
  if (!on) {
    m.volume_f32.reset();
    if (m.finalized) detail::build_spring_gather(m);  // the double slots' limit
    return;
  }
  require(m.volume.size() > 0 && static_cast<Index>(m.volume.packed.size()) == m.volume.size(), m.name,
          ": the single-precision volume pass needs finalized volume terms (the model has ", m.volume.size(),
          ")");
  auto F = std::make_shared<VolumeTermsF32>();
  build_volume_f32(m.volume, m.x0, *F);
  detail::build_springs_f32(m, F->springs);  // the gather pass's float slots (spring_f32.hpp)
  m.volume_f32 = std::move(F);
  if (m.finalized) detail::build_spring_gather(m);  // float slots: the gather pass up to twice the springs
}

namespace detail {

void add_records_f32(const VolumeTermsF32& F, const float* u, float* g, std::size_t r0, std::size_t r1) {
  r1 = r1 < F.rec.size() ? r1 : F.rec.size();
  if (F.comp)
    records_f32<true, true>(F, u, g, nullptr, r0, r1);
  else
    records_f32<false, true>(F, u, g, nullptr, r0, r1);
}

bool set_volume_f32_x8(bool on) {
  return g_f32_x8.exchange(on);
}

bool set_volume_f32_blocks(bool on) {
  return g_f32_blocks.exchange(on);
}

bool volume_f32_vector_compiled() {
#if defined(MEDSPRING_VOLUME_F32_VECTOR)
  return true;
#else
  return false;
#endif
}

}  // namespace detail

}  // namespace medspring
