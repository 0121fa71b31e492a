// Eight 4-float rows at a time in 256-bit vectors (GCC vector extensions with AVX): the transposes and
// lane-wise helpers of the single-precision passes (volume_f32.cpp: eight tetrahedra a vector;
// spring_f32.cpp: eight springs a vector). Internal to the physics layer. MEDSPRING_F32_LANES is defined
// where they are compiled (GCC, AVX targets); elsewhere the passes take one record at a time.
#pragma once

#if defined(__GNUC__) && !defined(__clang__) && defined(__AVX__)
#define MEDSPRING_F32_LANES 1
#include <immintrin.h>

namespace medspring::detail::lanes {

typedef float F8 __attribute__((vector_size(32)));

/// Rows p[0..8) (4 floats each) -> their x, y, z and w as 8-lane vectors.
[[gnu::always_inline]] inline void rows_to_lanes(const float* const (&p)[8], F8 (&o)[4]) {
  __m256 a[4];
  for (int j = 0; j < 4; ++j)
    a[j] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p[j])), _mm_loadu_ps(p[j + 4]), 1);
  const __m256 t0 = _mm256_unpacklo_ps(a[0], a[1]), t1 = _mm256_unpacklo_ps(a[2], a[3]);
  const __m256 t2 = _mm256_unpackhi_ps(a[0], a[1]), t3 = _mm256_unpackhi_ps(a[2], a[3]);
  o[0] = (F8)_mm256_shuffle_ps(t0, t1, 0x44);
  o[1] = (F8)_mm256_shuffle_ps(t0, t1, 0xEE);
  o[2] = (F8)_mm256_shuffle_ps(t2, t3, 0x44);
  o[3] = (F8)_mm256_shuffle_ps(t2, t3, 0xEE);
}

/// The inverse: lanes l[0..4) (x, y, z, w of eight rows) -> q[j] holding row j in its low half and row
/// j + 4 in its high half.
[[gnu::always_inline]] inline void lanes_to_rows(const F8 (&l)[4], __m256 (&q)[4]) {
  const __m256 t0 = _mm256_unpacklo_ps((__m256)l[0], (__m256)l[1]);
  const __m256 t1 = _mm256_unpackhi_ps((__m256)l[0], (__m256)l[1]);
  const __m256 t2 = _mm256_unpacklo_ps((__m256)l[2], (__m256)l[3]);
  const __m256 t3 = _mm256_unpackhi_ps((__m256)l[2], (__m256)l[3]);
  q[0] = _mm256_shuffle_ps(t0, t2, 0x44);
  q[1] = _mm256_shuffle_ps(t0, t2, 0xEE);
  q[2] = _mm256_shuffle_ps(t1, t3, 0x44);
  q[3] = _mm256_shuffle_ps(t1, t3, 0xEE);
}

inline F8 min8(F8 a, F8 b) {
  return (F8)_mm256_min_ps((__m256)a, (__m256)b);
}  // a < b ? a : b (minss)
inline F8 max8(F8 a, F8 b) {
  return (F8)_mm256_max_ps((__m256)a, (__m256)b);
}
inline void cross8(const F8 (&a)[3], const F8 (&b)[3], F8 (&w)[3]) {
  w[0] = a[1] * b[2] - a[2] * b[1];
  w[1] = a[2] * b[0] - a[0] * b[2];
  w[2] = a[0] * b[1] - a[1] * b[0];
}
inline F8 dot8(const F8 (&a)[3], const F8 (&b)[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline F8 sqrt8(F8 a) {
  return (F8)_mm256_sqrt_ps((__m256)a);
}
inline F8 abs8(F8 a) {
  return (F8)_mm256_andnot_ps(_mm256_set1_ps(-0.0f), (__m256)a);
}

}  // namespace medspring::detail::lanes

#endif
