// The gather pass's springs in single precision (spring_f32.hpp). Compiled with -fno-math-errno
// (physics/CMakeLists.txt) so that the scalar square roots need no call.
#include "spring_f32.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "f32_lanes.hpp"
#include "medspring/physics/kernels.hpp"

namespace medspring::detail {

void build_springs_f32(const Model& m, SpringsF32& S) {
  const Springs& sp = m.springs;
  const auto ns = static_cast<std::size_t>(sp.size());
  S = SpringsF32{};
  for (auto* v : {&S.ex, &S.ey, &S.ez, &S.le, &S.c, &S.k, &S.kp, &S.ik}) v->resize(ns);
  S.i.resize(ns);
  S.j.resize(ns);
  for (std::size_t s = 0; s < ns; ++s) {
    const auto si = static_cast<Index>(s);
    const Index a = sp.i[si], b = sp.j[si];
    S.i[s] = static_cast<std::int32_t>(a);
    S.j[s] = static_cast<std::int32_t>(b);
    const Vec3 E = (m.x0.row(b) - m.x0.row(a)).transpose();
    S.ex[s] = static_cast<float>(E.x());
    S.ey[s] = static_cast<float>(E.y());
    S.ez[s] = static_cast<float>(E.z());
    S.le[s] = std::sqrt(S.ex[s] * S.ex[s] + S.ey[s] * S.ey[s] + S.ez[s] * S.ez[s]);
    S.c[s] = static_cast<float>(E.norm() - sp.L0[si]);
    S.k[s] = static_cast<float>(sp.k[si]);
    S.kp[s] = static_cast<float>(sp.kp[si]);
    S.ik[s] = static_cast<float>(m.inv_k[si]);
  }
}

void fill_displacements_f32(const VolumeTermsF32& F, const double* x, float* u) {
  const double* x0 = F.x0.data();
  for (Index i = 0; i < F.nodes; ++i) {
    for (int d = 0; d < 3; ++d) u[4 * i + d] = static_cast<float>(x[3 * i + d] - x0[3 * i + d]);
    u[4 * i + 3] = 0.0f;
  }
}

namespace {

constexpr float kMin2 = static_cast<float>(hd::kMinSpringLength * hd::kMinSpringLength);

// The arrays of a SpringsF32 as restrict pointers (loaded once: the slot stores cannot alias them).
struct Arrays {
  const std::int32_t* __restrict I;
  const std::int32_t* __restrict J;
  const float* __restrict ex;
  const float* __restrict ey;
  const float* __restrict ez;
  const float* __restrict le;
  const float* __restrict c;
  const float* __restrict k;
  const float* __restrict kp;
  const float* __restrict ik;
  explicit Arrays(const SpringsF32& S)
      : I(S.i.data()),
        J(S.j.data()),
        ex(S.ex.data()),
        ey(S.ey.data()),
        ez(S.ez.data()),
        le(S.le.data()),
        c(S.c.data()),
        k(S.k.data()),
        kp(S.kp.data()),
        ik(S.ik.data()) {}
};

// Spring s, one at a time: the arithmetic of springs8 on scalars (the same operations in the same order).
// One division: r = 1 / (L (L + |E|)) gives both 1 / (L + |E|) = L r and 1 / L = (L + |E|) r.
template <bool Stiff>
inline void spring1(const Arrays& S, std::size_t s, const float* __restrict u, float* __restrict Fi,
                    float* __restrict Fj, float& km) {
  const float* ui = u + 4 * static_cast<std::ptrdiff_t>(S.I[s]);
  const float* uj = u + 4 * static_cast<std::ptrdiff_t>(S.J[s]);
  const float E[3] = {S.ex[s], S.ey[s], S.ez[s]};
  float D[3], e[3];
  for (int d = 0; d < 3; ++d) {
    D[d] = uj[d] - ui[d];
    e[d] = E[d] + D[d];
  }
  const float L2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
  const bool ok = L2 >= kMin2;  // else skipped (§1.3)
  const float L = std::sqrt(ok ? L2 : 1.0f);
  const float ED = E[0] * D[0] + E[1] * D[1] + E[2] * D[2], DD = D[0] * D[0] + D[1] * D[1] + D[2] * D[2];
  const float Ls = L + S.le[s];
  const float r = 1.0f / (L * Ls);
  const float dl = (2.0f * ED + DD) * (L * r) + S.c[s];  // L - L0
  const float kp_d2 = S.kp[s] * dl * dl;
  const float phi = dl * (S.k[s] + kp_d2);  // eq. (5)
  const float t = ok ? phi * (Ls * r) : 0.0f;
  if constexpr (Stiff) {
    const float dphi = S.k[s] + 3.0f * kp_d2, at = std::abs(t);
    float kap = (dphi < at ? at : dphi) * S.ik[s];
    kap = ok && kap >= 0.0f ? kap : 0.0f;  // NaN and skipped springs do not count
    km = km < kap ? kap : km;
  }
  for (int d = 0; d < 3; ++d) {
    Fi[4 * s + static_cast<std::size_t>(d)] = t * e[d];
    Fj[4 * s + static_cast<std::size_t>(d)] = -(t * e[d]);
  }
  Fi[4 * s + 3] = 0.0f;
  Fj[4 * s + 3] = -0.0f;
}

#if defined(MEDSPRING_F32_LANES)
using lanes::F8;
typedef int I8 __attribute__((vector_size(32)));

inline F8 ld8(const float* p) {
  return (F8)_mm256_loadu_ps(p);
}

// The rows of u at the nodes n[0..8) as x, y, z and w lanes.
[[gnu::always_inline]] inline void node_lanes(const float* __restrict u, const std::int32_t* n, F8 (&o)[4]) {
  const float* const p[8] = {
      u + 4 * static_cast<std::ptrdiff_t>(n[0]), u + 4 * static_cast<std::ptrdiff_t>(n[1]),
      u + 4 * static_cast<std::ptrdiff_t>(n[2]), u + 4 * static_cast<std::ptrdiff_t>(n[3]),
      u + 4 * static_cast<std::ptrdiff_t>(n[4]), u + 4 * static_cast<std::ptrdiff_t>(n[5]),
      u + 4 * static_cast<std::ptrdiff_t>(n[6]), u + 4 * static_cast<std::ptrdiff_t>(n[7])};
  lanes::rows_to_lanes(p, o);
}

// Springs [s, s + 8), one a lane: both ends' rows transposed in registers, the rest edges and constants
// loaded lane by lane, the forces transposed back to rows (t e, 0) and stored with their negations.
template <bool Stiff>
[[gnu::always_inline]] inline void springs8(const Arrays& S, std::size_t s, const float* __restrict u,
                                            float* __restrict Fi, float* __restrict Fj, F8& km) {
  F8 Ui[4], Uj[4];
  node_lanes(u, S.I + s, Ui);
  node_lanes(u, S.J + s, Uj);
  const F8 E[3] = {ld8(S.ex + s), ld8(S.ey + s), ld8(S.ez + s)};
  F8 D[3], e[3];
  for (int d = 0; d < 3; ++d) {
    D[d] = Uj[d] - Ui[d];
    e[d] = E[d] + D[d];
  }
  const F8 one = F8{} + 1.0f, zero{};
  const F8 L2 = lanes::dot8(e, e);
  const I8 ok = L2 >= F8{} + kMin2;  // else skipped (§1.3)
  const F8 L = lanes::sqrt8(ok ? L2 : one);
  const F8 Ls = L + ld8(S.le + s);
  const F8 r = one / (L * Ls);
  const F8 dl = (2.0f * lanes::dot8(E, D) + lanes::dot8(D, D)) * (L * r) + ld8(S.c + s);  // L - L0
  const F8 K = ld8(S.k + s), KP = ld8(S.kp + s);
  const F8 kp_d2 = KP * dl * dl;
  const F8 phi = dl * (K + kp_d2);  // eq. (5)
  const F8 t = ok ? phi * (Ls * r) : zero;
  if constexpr (Stiff) {
    const F8 dphi = K + 3.0f * kp_d2, at = lanes::abs8(t);
    F8 kap = (dphi < at ? at : dphi) * ld8(S.ik + s);
    kap = (ok & (kap >= zero)) ? kap : zero;  // NaN and skipped springs do not count
    km = lanes::max8(kap, km);
  }
  const F8 l[4] = {t * e[0], t * e[1], t * e[2], zero};
  __m256 q[4];
  lanes::lanes_to_rows(l, q);
  const __m256 sign = _mm256_set1_ps(-0.0f);
  for (int j = 0; j < 4; ++j) {
    const __m256 n = _mm256_xor_ps(q[j], sign);  // exactly the negated force
    _mm_storeu_ps(Fi + 4 * (s + static_cast<std::size_t>(j)), _mm256_castps256_ps128(q[j]));
    _mm_storeu_ps(Fi + 4 * (s + static_cast<std::size_t>(j) + 4), _mm256_extractf128_ps(q[j], 1));
    _mm_storeu_ps(Fj + 4 * (s + static_cast<std::size_t>(j)), _mm256_castps256_ps128(n));
    _mm_storeu_ps(Fj + 4 * (s + static_cast<std::size_t>(j) + 4), _mm256_extractf128_ps(n, 1));
  }
}
#endif

template <bool Stiff>
double slots(const SpringsF32& springs, const float* __restrict u, float* __restrict F, bool x8) {
  const Arrays S(springs);
  const std::size_t ns = springs.size();
  float* __restrict Fi = F;
  float* __restrict Fj = F + 4 * ns;
  float km = 0.0f;
  std::size_t s = 0;
#if defined(MEDSPRING_F32_LANES)
  if (x8) {
    F8 kv{};
    for (; s + 8 <= ns; s += 8) springs8<Stiff>(S, s, u, Fi, Fj, kv);
    if constexpr (Stiff)
      for (int l = 0; l < 8; ++l) km = km < kv[l] ? kv[l] : km;
  }
#else
  (void)x8;
#endif
  for (; s < ns; ++s) spring1<Stiff>(S, s, u, Fi, Fj, km);
  for (int d = 0; d < 4; ++d) F[8 * ns + static_cast<std::size_t>(d)] = 0.0f;  // the zero slot
  if constexpr (!Stiff) return 1.0;
  return hd::max_of(1.0, static_cast<double>(km));
}

}  // namespace

double spring_slots_f32(const SpringsF32& S, const float* u, float* F, bool stiffening, bool x8) {
  return stiffening ? slots<true>(S, u, F, x8) : slots<false>(S, u, F, x8);
}

}  // namespace medspring::detail
