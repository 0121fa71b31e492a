// The volume pass across tetrahedra (issue 23, item 5, docs/volumetric-speed.md): tet_record
// (tet_kernel.hpp) without owned springs, evaluated for W (4) records at once in vector registers (GCC vector
// extensions): the corners gathered (AVX2 / AVX-512 gathers) straight from x, no intermediate buffers on
// the way in; the volume, compression and stiffening scalars lane-wise, with the same operations in the same
// order as the scalar kernel (and no FMA contraction in either: volume_passes.cpp, their one user, is
// compiled with -ffp-contract=off; GCC contracts them differently otherwise), so each lane is bit for bit the
// scalar record; the one division and the five square roots of a record run W at a time (vdivpd / vsqrtpd
// pipeline them, the scalar pass waits for each). The forces and the traces are then scattered lane by lane,
// in the records' order: the sums at each node are those of the scalar pass, bit for bit. Compiled only where
// the target has AVX2 (-march=native) and the compiler is GCC; the scalar kernel is the tail and the
// fallback. Clang builds (the sanitizer and fuzz builds) take the scalar pass: under Clang 14 the two paths
// differed in the last bit (forces ~1e-16, a trace 3e-31 against 0; cause not found), and bit for bit is
// the vector pass's contract (volume_simd_tests).
#pragma once

#include <cstddef>
#include <cstdint>

#include "tet_kernel.hpp"

#if defined(__AVX2__) && defined(__GNUC__) && !defined(__clang__)
#define MEDSPRING_TET_SIMD 1
#include <immintrin.h>
#endif

namespace medspring::detail {

#if defined(MEDSPRING_TET_SIMD)

/// Lanes of the vector pass: 4 (AVX2, 256-bit). 8 (AVX-512F, 512-bit) with -DMEDSPRING_TET_SIMD_LANES8 on
/// an AVX-512 target: slower on the Xeon it was measured on (docs/volumetric-speed.md, h23p: the last
/// sub-step's pass 190 against 171 us, the other sub-steps' 127 against 120).
#if defined(__AVX512F__) && defined(MEDSPRING_TET_SIMD_LANES8)
inline constexpr int kTetLanes = 8;
#else
inline constexpr int kTetLanes = 4;
#endif

template <int W>
struct TetVec;
template <>
struct TetVec<4> {
  typedef double V __attribute__((vector_size(32)));
  using I = __m128i;  // 4 int32 indices
  static V gather(const double* base, I idx) { return (V)_mm256_i32gather_pd(base, idx, 8); }
  static V gather_rec(const char* base, I off) { return (V)_mm256_i32gather_pd((const double*)base, off, 1); }
  static I gather_idx(const char* base, I off) { return _mm_i32gather_epi32((const int*)base, off, 1); }
  static I times3(I n) { return _mm_add_epi32(_mm_add_epi32(n, n), n); }
  static I offsets(int stride) { return _mm_setr_epi32(0, stride, 2 * stride, 3 * stride); }
  static V vmin(V a, V b) { return (V)_mm256_min_pd((__m256d)a, (__m256d)b); }  // a < b ? a : b (minsd)
  static V vmax(V a, V b) { return (V)_mm256_max_pd((__m256d)a, (__m256d)b); }  // a > b ? a : b (maxsd)
  static V vsqrt(V a) { return (V)_mm256_sqrt_pd((__m256d)a); }
  static V vabs(V a) { return (V)_mm256_andnot_pd(_mm256_set1_pd(-0.0), (__m256d)a); }
};
#if defined(__AVX512F__) && defined(MEDSPRING_TET_SIMD_LANES8)
template <>
struct TetVec<8> {
  typedef double V __attribute__((vector_size(64)));
  using I = __m256i;  // 8 int32 indices
  static V gather(const double* base, I idx) { return (V)_mm512_i32gather_pd(idx, base, 8); }
  static V gather_rec(const char* base, I off) { return (V)_mm512_i32gather_pd(off, base, 1); }
  static I gather_idx(const char* base, I off) { return _mm256_i32gather_epi32((const int*)base, off, 1); }
  static I times3(I n) { return _mm256_add_epi32(_mm256_add_epi32(n, n), n); }
  static I offsets(int s) { return _mm256_setr_epi32(0, s, 2 * s, 3 * s, 4 * s, 5 * s, 6 * s, 7 * s); }
  static V vmin(V a, V b) { return (V)_mm512_min_pd((__m512d)a, (__m512d)b); }
  static V vmax(V a, V b) { return (V)_mm512_max_pd((__m512d)a, (__m512d)b); }
  static V vsqrt(V a) { return (V)_mm512_sqrt_pd((__m512d)a); }
  static V vabs(V a) { return (V)_mm512_abs_pd((__m512d)a); }
};
#endif

/// tet_record<0, false, Stiff, Local, Comp, Trace> of records p[0 .. W), bit for bit, and their scatter in
/// order. inc: the W records' increments (Local); vsv: the lane-wise max of the stiffening bounds (Stiff).
template <int W, bool Stiff, bool Local, bool Comp, bool Trace>
[[gnu::always_inline]] inline void tet_records_simd(const VolumeTerms::Packed* p, const double* x, double* f,
                                                    typename TetVec<W>::V& vsv, double* inc,
                                                    const CompTrace* tr) {
  using T = TetVec<W>;
  using V = typename T::V;
  using Packed = VolumeTerms::Packed;
  const auto off = T::offsets(static_cast<int>(sizeof(Packed)));
  const char* rb = reinterpret_cast<const char*>(p);
  typename T::I n[4], n3[4];
  for (int k = 0; k < 4; ++k) {
    n[k] = T::gather_idx(rb + offsetof(Packed, n) + sizeof(std::int32_t) * static_cast<std::size_t>(k), off);
    n3[k] = T::times3(n[k]);
  }
  V P[4][3];
  for (int k = 0; k < 4; ++k)
    for (int d = 0; d < 3; ++d) P[k][d] = T::gather(x + d, n3[k]);
  const V V06 = T::gather_rec(rb + offsetof(Packed, V06), off);
  const V alpha = T::gather_rec(rb + offsetof(Packed, alpha), off);
  V e[3][3];
  for (int k = 0; k < 3; ++k)
    for (int d = 0; d < 3; ++d) e[k][d] = P[k + 1][d] - P[0][d];
  V c[3][3];
  auto cross = [](const V* u, const V* v, V* w) {
    w[0] = u[1] * v[2] - u[2] * v[1];
    w[1] = u[2] * v[0] - u[0] * v[2];
    w[2] = u[0] * v[1] - u[1] * v[0];
  };
  cross(e[1], e[2], c[0]);
  cross(e[2], e[0], c[1]);
  cross(e[0], e[1], c[2]);
  const V dv6 = e[0][0] * c[0][0] + e[0][1] * c[0][1] + e[0][2] * c[0][2] - V06;
  V s = -alpha * dv6;
  const V zero{};
  V hd1 = zero, hr = zero, hW = zero, kc6 = zero;
  if constexpr (Comp) {  // compression_dh6, compression_scalar
    kc6 = T::gather_rec(rb + offsetof(Packed, kc6), off);
    constexpr double jm = kCompressionJMin, d2m = 1.0 / (jm * jm) - 1.0;
    const V lo = (jm - 1.0) * V06;
    const V d = T::vmax(T::vmin(dv6, zero), lo);
    const V bl = T::vmin(dv6 - lo, zero);
    hW = V06 + d;
    hr = 1.0 / (V06 * hW);
    hd1 = hr * (d2m * bl * hW - d * d);
    s += -kc6 * hd1;
  }
  V F[4][3];
  for (int d = 0; d < 3; ++d) {
    F[1][d] = s * c[0][d];
    F[2][d] = s * c[1][d];
    F[3][d] = s * c[2][d];
    F[0][d] = -(F[1][d] + F[2][d] + F[3][d]);
  }
  V R[4];  // the traces' shares (Trace)
  if constexpr (Stiff) {
    V gg = zero;
    for (int d = 0; d < 3; ++d) {
      const V c0 = c[0][d] + c[1][d] + c[2][d];
      gg += c[0][d] * c[0][d] + c[1][d] * c[1][d] + c[2][d] * c[2][d] + c0 * c0;
    }
    V l2 = zero;  // max_edge2
    for (int k = 0; k < 3; ++k) {
      const V a = e[k][0] * e[k][0] + e[k][1] * e[k][1] + e[k][2] * e[k][2];
      l2 = T::vmax(a, l2);
      const int j = (k + 1) % 3;
      V q = zero;
      for (int d = 0; d < 3; ++d) q += (e[j][d] - e[k][d]) * (e[j][d] - e[k][d]);
      l2 = T::vmax(q, l2);
    }
    const V sl = T::vsqrt(l2);
    const V cur = gg * (1.0 / 36.0) + T::vabs(dv6) * sl * (1.0 / 12.0);
    const V iG0 = T::gather_rec(rb + offsetof(Packed, iG0), off);
    if constexpr (Trace) {  // compression_trace
      const V iJ = V06 * V06 * hr;
      const V d2 = T::vmax(iJ * iJ - 1.0, zero);
      const V a = 36.0 * kc6 * (hW * hr) * d2;
      const V hb = T::vabs(kc6 * hd1) * sl;
      V gn[4];
      for (int k = 0; k < 3; ++k)
        gn[k + 1] = T::vsqrt(c[k][0] * c[k][0] + c[k][1] * c[k][1] + c[k][2] * c[k][2]);
      {
        const V c0[3] = {c[0][0] + c[1][0] + c[2][0], c[0][1] + c[1][1] + c[2][1],
                         c[0][2] + c[1][2] + c[2][2]};
        gn[0] = T::vsqrt(c0[0] * c0[0] + c0[1] * c0[1] + c0[2] * c0[2]);
      }
      V sk[4], S = zero, sigma = zero;
      for (int k = 0; k < 4; ++k) {
        gn[k] *= 1.0 / 6.0;
        sk[k] = T::gather(tr->s, n[k]);
        S += sk[k];
        sigma += sk[k] * gn[k];
      }
      const V as = a * sigma, h3 = 3.0 * hb;
      for (int k = 0; k < 4; ++k) R[k] = sk[k] * (as * gn[k] + h3 * (S - sk[k]));
    }
    const V g = cur * iG0;
    if constexpr (Local) {
      const V st = T::vmax(g - 1.0, zero);
      __builtin_memcpy(inc, &st, sizeof(V));
    }
    vsv = T::vmax(g, vsv);
  }
  // The scatter, lane by lane in the records' order (two records of a group may share a node).
  alignas(64) double Fb[4][3][W];
  alignas(64) double Rb[4][W];
  for (int k = 0; k < 4; ++k) {
    for (int d = 0; d < 3; ++d) __builtin_memcpy(Fb[k][d], &F[k][d], sizeof(V));
    if constexpr (Trace) __builtin_memcpy(Rb[k], &R[k], sizeof(V));
  }
  for (int l = 0; l < W; ++l) {
    const Packed& r = p[l];
    if constexpr (Trace)
      for (int k = 0; k < 4; ++k) tr->rows[r.n[k]] += Rb[k][l];
    for (int k = 0; k < 4; ++k) {
      double* o = f + 3 * static_cast<std::ptrdiff_t>(r.n[k]);
      o[0] += Fb[k][0][l];
      o[1] += Fb[k][1][l];
      o[2] += Fb[k][2][l];
    }
  }
}

#endif  // MEDSPRING_TET_SIMD

}  // namespace medspring::detail
