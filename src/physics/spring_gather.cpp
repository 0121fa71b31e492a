// The gather pass of the serial symplectic step (spring_gather.hpp). Compiled with -fno-math-errno
// (physics/CMakeLists.txt) so that the square roots of the spring pass vectorise; nothing reads errno.
#include "spring_gather.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__AVX512VL__) && defined(__GNUC__) && !defined(__clang__)
#define MEDSPRING_FUSED_SPRING_PASS 1
#include <immintrin.h>
#endif

#include "medspring/physics/kernels.hpp"
#include "spring_f32.hpp"
#include "spring_kernel.hpp"

namespace medspring::detail {

namespace {

// Row widths the node pass is unrolled for (build_spring_gather picks one per model).
constexpr int kWidths[] = {4, 6, 8, 10, 12, 16};

}  // namespace

std::atomic<Index> g_gather_max_f32{kSpringGatherMaxSpringsF32};

void build_spring_gather(Model& m) {
  m.gather = SpringGather{};
  const Index n = m.num_nodes(), ns = m.num_springs();
  // volume terms: their pass adds into st.f, which the node pass reads (issue 23); not with the fused pass
  // of terms that own springs (plan_owned_springs)
  // a model with the float volume pass has float slots (16 bytes, half the double ones): twice the springs
  const Index most = m.volume_f32 && m.volume_f32->springs.size() == static_cast<std::size_t>(ns)
                         ? g_gather_max_f32.load(std::memory_order_relaxed)
                         : kSpringGatherMaxSprings;
  if (ns == 0 || ns > most || m.has_soft_springs || m.bending.size() > 0 ||
      (m.volume.size() > 0 && m.volume.planned_springs >= 0) || m.thin.size() > 0)  // thin: internal_forces
    return;
  const auto un = static_cast<std::size_t>(n);
  std::vector<Index> degree(un + 1, 0);
  for (Index s = 0; s < ns; ++s) {
    ++degree[static_cast<std::size_t>(m.springs.i[s])];
    ++degree[static_cast<std::size_t>(m.springs.j[s])];
  }
  // the row width of least estimated cost: a row slot costs one vector add (padding included), an
  // overflow slot about two (a loop of its own), a node that overflows about ten (a mispredicted exit)
  int W = kWidths[0];
  double best = -1;
  for (const int w : kWidths) {
    double cost = static_cast<double>(n) * w;
    for (std::size_t a = 0; a < un; ++a)
      if (degree[a] > w) cost += 2.0 * static_cast<double>(degree[a] - w) + 10.0;
    if (best < 0 || cost < best) {
      best = cost;
      W = w;
    }
  }
  SpringGather& G = m.gather;
  G.width = W;
  G.nodes = n;
  G.springs = ns;
  constexpr Index kSlotBytes = 4 * sizeof(double);  // rows hold byte offsets: no scaling in the node pass
  const Index zero = 2 * ns * kSlotBytes;
  G.row.assign(un * static_cast<std::size_t>(W), zero);
  // slots of every node in increasing spring index (CSR), then split into the row and the overflow
  std::vector<Index> begin(un + 1, 0);
  for (std::size_t a = 0; a < un; ++a) begin[a + 1] = begin[a] + degree[a];
  std::vector<Index> slots(static_cast<std::size_t>(begin[un]));
  std::vector<Index> fill(begin.begin(), begin.end() - 1);
  for (Index s = 0; s < ns; ++s) {
    slots[static_cast<std::size_t>(fill[static_cast<std::size_t>(m.springs.i[s])]++)] = s;
    slots[static_cast<std::size_t>(fill[static_cast<std::size_t>(m.springs.j[s])]++)] = ns + s;
  }
  G.extra_begin.assign(un + 1, 0);
  for (std::size_t a = 0; a < un; ++a) {
    const Index d = degree[a];
    for (Index e = 0; e < d; ++e) {
      const Index slot = slots[static_cast<std::size_t>(begin[a] + e)] * kSlotBytes;
      if (e < W)
        G.row[a * static_cast<std::size_t>(W) + static_cast<std::size_t>(e)] = slot;
      else
        G.extra.push_back(slot);
    }
    G.extra_begin[a + 1] = static_cast<Index>(G.extra.size());
  }
}

bool gather_ready(const Model& m, State& st) {
  const SpringGather& G = m.gather;
  if (G.empty() || G.nodes != m.num_nodes() || G.springs != m.num_springs()) return false;
  const Index slots = 2 * G.springs + 1;
  if (st.spring_force.size() != 4 * slots) st.spring_force.setZero(4 * slots);  // once per state
  return true;
}

namespace {

constexpr Index kBlock = 128;

// Four doubles (x, y, z, 0) of a slot force: one vector load and add per slot in the node pass. GCC and
// Clang vector extensions (lane-wise IEEE operations); the buffer is Eigen-allocated (>= 16-byte
// aligned), so the type asks for 8-byte alignment only.
typedef double v4d __attribute__((
    vector_size(32), aligned(8)));  // springs per block of the spring pass (the gathered vectors stay in L1)
// Four floats of a float slot (spring_f32.hpp): 16 bytes, at half the byte offset of the double slot.
typedef float v4f __attribute__((vector_size(16), aligned(4)));

// Spring vectors e = x_j - x_i of springs [0, nb) of a block. Scalar loads: the gather instructions
// the vectoriser would use here are slower than them.
#if defined(__GNUC__) && !defined(__clang__)
__attribute__((optimize("no-tree-vectorize")))
#endif
void spring_vectors(Index nb, const Index* __restrict I, const Index* __restrict J, const double* __restrict x,
                    double* __restrict ex, double* __restrict ey, double* __restrict ez) {
  for (Index q = 0; q < nb; ++q) {
    const Index a = 3 * I[q], b = 3 * J[q];
    ex[q] = x[b] - x[a];
    ey[q] = x[b + 1] - x[a + 1];
    ez[q] = x[b + 2] - x[a + 2];
  }
}

// Forces of springs [0, nb) of a block from their vectors: hd::spring_force's arithmetic written without
// branches (a spring shorter than kMinSpringLength gets the force 0). The tension over the length t goes
// to tt (vectorised loop); the force t e is then stored into the slot of the end i and its negation into
// that of the end j, as (x, y, z, 0). With Stiff, the largest kappa/k of the block is folded into
// `stiff_bits`: the bit pattern of a non-negative double orders like the double, so the maximum
// vectorises as an integer maximum.
template <bool Stiff>
inline void block_forces(Index nb, const double* __restrict ex, const double* __restrict ey,
                         const double* __restrict ez, const double* __restrict L0, const double* __restrict K,
                         const double* __restrict KP, const double* __restrict IK, double* __restrict tt,
                         std::int64_t& stiff_bits) {
  std::int64_t sm = stiff_bits;
  for (Index q = 0; q < nb; ++q) {
    const double L2 = ex[q] * ex[q] + ey[q] * ey[q] + ez[q] * ez[q];
    const bool ok = L2 >= hd::kMinSpringLength * hd::kMinSpringLength;  // else skipped (§1.3)
    const double L = std::sqrt(ok ? L2 : 1.0);
    const double inv = 1.0 / L;
    const double d = L - L0[q];
    const double kp_d2 = KP[q] * d * d;
    const double phi = d * (K[q] + kp_d2);  // eq. (5)
    const double t = ok ? phi * inv : 0.0;  // phi / L
    if constexpr (Stiff) {
      const double dphi = K[q] + 3.0 * kp_d2;
      const double at = std::abs(t);
      double kap = (dphi < at ? at : dphi) * IK[q];  // hd::max_of(dphi, |t|) / k
      kap = ok && kap >= 0.0 ? kap : 0.0;            // NaN and skipped springs do not count
      std::int64_t bits;
      std::memcpy(&bits, &kap, sizeof bits);
      sm = sm < bits ? bits : sm;
    }
    tt[q] = t;
  }
  stiff_bits = sm;
}

#if defined(MEDSPRING_FUSED_SPRING_PASS)
typedef double v4r __attribute__((vector_size(32)));        // registers (32-byte aligned type)
typedef std::int64_t v4i __attribute__((vector_size(32)));  // lane masks and bit patterns

// Springs [s0, s1) (s1 - s0 a multiple of 4), four at a time in registers: one masked 32-byte load per
// end ((x, y, z) and a zero: the masked lane is neither read nor faulted, so the last node's row is
// safe), a 4 x 4 transpose to (ex, ey, ez), block_forces' arithmetic lane-wise (the same expressions:
// the same bits), and the slot stores t e as (x, y, z, 0) and its negation. Returns the running maximum
// of the stiffening bits (see block_forces). With Chunk (the fused node-range step, threaded_step.cpp)
// only t e, to Fi[s - s0].
template <bool Stiff, bool Chunk = false>
v4i fused_forces(Index s0, Index s1, const Springs& S, const double* __restrict IKp,
                 const double* __restrict x, v4d* __restrict Fi, v4d* __restrict Fj, v4i sm) {
  const Index* __restrict I = S.i.data();
  const Index* __restrict J = S.j.data();
  const double* __restrict L0p = S.L0.data();
  const double* __restrict Kp = S.k.data();
  const double* __restrict KPp = S.kp.data();
  const v4r one = {1.0, 1.0, 1.0, 1.0}, zero = {0.0, 0.0, 0.0, 0.0};
  constexpr double kmin2 = hd::kMinSpringLength * hd::kMinSpringLength;
  const v4r min2 = {kmin2, kmin2, kmin2, kmin2};
  for (Index s = s0; s < s1; s += 4) {
    __m256d e[4];
    for (int k = 0; k < 4; ++k)
      e[k] = _mm256_sub_pd(_mm256_maskz_loadu_pd(0x7, x + 3 * J[s + k]),
                           _mm256_maskz_loadu_pd(0x7, x + 3 * I[s + k]));
    const __m256d t0 = _mm256_unpacklo_pd(e[0], e[1]);  // e0x e1x e0z e1z
    const __m256d t1 = _mm256_unpackhi_pd(e[0], e[1]);  // e0y e1y 0 0
    const __m256d t2 = _mm256_unpacklo_pd(e[2], e[3]);
    const __m256d t3 = _mm256_unpackhi_pd(e[2], e[3]);
    const v4r ex = _mm256_permute2f128_pd(t0, t2, 0x20);
    const v4r ey = _mm256_permute2f128_pd(t1, t3, 0x20);
    const v4r ez = _mm256_permute2f128_pd(t0, t2, 0x31);
    const v4r L0 = _mm256_loadu_pd(L0p + s), K = _mm256_loadu_pd(Kp + s), KP = _mm256_loadu_pd(KPp + s);
    const v4r L2 = ex * ex + ey * ey + ez * ez;
    const v4i ok = L2 >= min2;  // else skipped (§1.3)
    const v4r L = _mm256_sqrt_pd(ok ? L2 : one);
    const v4r inv = one / L;
    const v4r d = L - L0;
    const v4r kp_d2 = KP * d * d;
    const v4r phi = d * (K + kp_d2);  // eq. (5)
    const v4r t = ok ? phi * inv : zero;
    if constexpr (Stiff) {
      const v4r IK = _mm256_loadu_pd(IKp + s);
      const v4r dphi = K + 3.0 * kp_d2;
      const v4r at = _mm256_andnot_pd(-zero, t);
      v4r kap = (dphi < at ? at : dphi) * IK;
      kap = (ok & (kap >= zero)) ? kap : zero;  // NaN and skipped springs do not count
      const v4i bits = reinterpret_cast<v4i>(kap);
      sm = sm < bits ? bits : sm;
    }
    for (int k = 0; k < 4; ++k) {
      const v4d f = reinterpret_cast<v4r>(e[k]) * t[k];  // (t ex, t ey, t ez, t 0)
      if constexpr (Chunk) {
        Fi[s - s0 + k] = f;
      } else {
        Fi[s + k] = f;
        Fj[s + k] = -f;  // exactly the negated force: f_j -= f of the scatter pass
      }
    }
  }
  return sm;
}
#endif

// The spring pass: every slot's force into F ((2 #S + 1) x 4: slot s = spring s at its end i, #S + s at
// its end j, 2 #S zero). Returns max(1, max kappa/k) with Stiff, else 1.
template <bool Stiff>
double slot_forces(const Model& m, const double* __restrict x, double* __restrict F) {
  const Index ns = m.num_springs();
  const Springs& S = m.springs;
  v4d* Fi = reinterpret_cast<v4d*>(F);
  v4d* Fj = Fi + ns;
  std::int64_t sm = 0;  // bits of +0.0
  alignas(64) double ex[kBlock], ey[kBlock], ez[kBlock], tt[kBlock];
  Index first = 0;
#if defined(MEDSPRING_FUSED_SPRING_PASS)
  first = ns - ns % 4;
  const v4i sv = fused_forces<Stiff>(0, first, S, m.inv_k.data(), x, Fi, Fj, v4i{0, 0, 0, 0});
  for (int k = 0; k < 4; ++k) sm = sm < sv[k] ? sv[k] : sm;
#endif
  for (Index s0 = first; s0 < ns; s0 += kBlock) {
    const Index nb = std::min(kBlock, ns - s0);
    spring_vectors(nb, S.i.data() + s0, S.j.data() + s0, x, ex, ey, ez);
    block_forces<Stiff>(nb, ex, ey, ez, S.L0.data() + s0, S.k.data() + s0, S.kp.data() + s0,
                        m.inv_k.data() + s0, tt, sm);
    for (Index q = 0; q < nb; ++q) {
      const double t = tt[q];
      const v4d f = {t * ex[q], t * ey[q], t * ez[q], 0.0};
      Fi[s0 + q] = f;
      Fj[s0 + q] = -f;  // exactly the negated force: f_j -= f of the scatter pass
    }
  }
  if constexpr (!Stiff) return 1.0;
  double stiff;
  std::memcpy(&stiff, &sm, sizeof stiff);
  return hd::max_of(1.0, stiff);
}

// The node pass: every node's force (load, return spring, with Vol the volume terms' force already in
// st.f, its slots in increasing spring index) into st.f and, for a free node, the symplectic update (§2.1)
// in place: the spring pass has read every position already. With F32 the slots are floats
// (spring_slots_f32), summed in float and added to the rest once. Returns 0, or 1 / 2 after restoring the
// free nodes already advanced.
// With VM, the volume terms' force comes from the nvm float force mirrors vm[0 .. nvm) (4 floats a node, in
// that order; the threaded sub-step, threaded_volume.hpp), not from st.f.
template <int W, bool Guard, bool Vol, bool F32 = false, bool VM = false>
int node_pass(const Model& m, State& st, double h, double vmax2, const float* const* vm = nullptr,
              int nvm = 0) {
  const SpringGather& Gt = m.gather;
  const Index n = m.num_nodes();
  const char* __restrict F4 = reinterpret_cast<const char*>(st.spring_force.data());
  const Index* __restrict row = Gt.row.data();
  const Index* __restrict xb = Gt.extra_begin.data();
  const Index* __restrict xs = Gt.extra.data();
  const double* __restrict FE = st.f_ext.data();
  const double* __restrict X0 = m.x0.data();
  const double* __restrict KR = m.kr.data();
  const double* __restrict Mv = m.mass.data();
  const double* __restrict C = st.step_coef.data();
  const std::uint8_t* __restrict fixed = m.fixed.data();
  double* X = st.x.data();  // not restrict: the guard's undo writes them too
  double* V = st.v.data();
  double* G = st.f.data();
  Index advanced = 0;  // free nodes advanced so far (m.free_nodes is in increasing order)
  for (Index a = 0; a < n; ++a) {
    const Index q = 3 * a;
#if defined(MEDSPRING_FUSED_SPRING_PASS)
    // load and return spring (§1.4) lane-wise from masked loads: hd::return_force's arithmetic
    const v4r xa = _mm256_maskz_loadu_pd(0x7, X + q);
    v4d acc = _mm256_maskz_loadu_pd(0x7, FE + q) - KR[a] * (xa - v4r(_mm256_maskz_loadu_pd(0x7, X0 + q)));
    if constexpr (Vol && !VM) acc += _mm256_maskz_loadu_pd(0x7, G + q);
#else
    double g[3];
    hd::return_force(FE + q, X + q, X0 + q, KR[a], g);  // load and return spring (§1.4)
    v4d acc = {g[0], g[1], g[2], 0.0};                  // lane-wise adds: the same sums as three scalar ones
    if constexpr (Vol && !VM) acc += v4d{G[q], G[q + 1], G[q + 2], 0.0};
#endif
    if constexpr (VM) {
      v4d vol{};
      for (int j = 0; j < nvm; ++j)
        vol += __builtin_convertvector(*reinterpret_cast<const v4f*>(vm[j] + 4 * a), v4d);
      acc += vol;
    }
    const Index* r = row + static_cast<std::size_t>(a) * W;
    if constexpr (F32) {
      // four partial sums: a chain of W / 4 dependent adds instead of W (the chain of one sum bounded the
      // pass: its adds' latency, not the loads)
      v4f p[4] = {};
#pragma GCC unroll 16
      for (int k = 0; k < W; ++k) p[k & 3] += *reinterpret_cast<const v4f*>(F4 + (r[k] >> 1));
      for (Index e = xb[a]; e < xb[a + 1]; ++e) p[0] += *reinterpret_cast<const v4f*>(F4 + (xs[e] >> 1));
      acc += __builtin_convertvector((p[0] + p[1]) + (p[2] + p[3]), v4d);
    } else {
#pragma GCC unroll 16
      for (int k = 0; k < W; ++k) acc += *reinterpret_cast<const v4d*>(F4 + r[k]);
      for (Index e = xb[a]; e < xb[a + 1]; ++e) acc += *reinterpret_cast<const v4d*>(F4 + xs[e]);
    }
#if defined(MEDSPRING_FUSED_SPRING_PASS)
    if constexpr (Vol) {  // the next node loads its row of G: no masked store over it (see below)
      _mm_storeu_pd(G + q, _mm256_castpd256_pd128(v4r(acc)));
      _mm_store_sd(G + q + 2, _mm256_extractf128_pd(v4r(acc), 1));
    } else {
      _mm256_mask_storeu_pd(G + q, 0x7, acc);
    }
    if (fixed[a]) continue;
    // hd::symplectic_velocity / symplectic_position lane-wise (equal to rounding: FMA contraction)
    const v4r vn = (Mv[a] * v4r(_mm256_maskz_loadu_pd(0x7, V + q)) + h * acc) * C[a];
    const double v2 = vn[0] * vn[0] + vn[1] * vn[1] + vn[2] * vn[2];
    if constexpr (Guard) {
      if (!hd::velocity_ok(v2, vmax2)) {  // also catches NaN
        undo_symplectic(m, st, h, m.free_nodes.data(), advanced);
        return std::isfinite(v2) ? 1 : 2;
      }
    }
    // 16 + 8-byte stores: a masked 32-byte store would block the next node's loads of its rows
    // (the store's masked lane overlaps them; no store forwarding from masked stores)
    const v4r xn = xa + h * vn;
    _mm_storeu_pd(V + q, _mm256_castpd256_pd128(vn));
    _mm_store_sd(V + q + 2, _mm256_extractf128_pd(vn, 1));
    _mm_storeu_pd(X + q, _mm256_castpd256_pd128(xn));
    _mm_store_sd(X + q + 2, _mm256_extractf128_pd(xn, 1));
    ++advanced;
  }
#else
    const double gx = acc[0], gy = acc[1], gz = acc[2];
    g[0] = gx;
    g[1] = gy;
    g[2] = gz;
    G[q] = gx;
    G[q + 1] = gy;
    G[q + 2] = gz;
    if (fixed[a]) continue;
    double vn[3];
    const double v2 = hd::symplectic_velocity(Mv[a], C[a], h, V + q, g, vn);
    if constexpr (Guard) {
      if (!hd::velocity_ok(v2, vmax2)) {  // also catches NaN
        undo_symplectic(m, st, h, m.free_nodes.data(), advanced);
        return std::isfinite(v2) ? 1 : 2;
      }
    }
    V[q] = vn[0];
    V[q + 1] = vn[1];
    V[q + 2] = vn[2];
    hd::symplectic_position(h, X + q, vn, X + q);
    ++advanced;
  }
#endif
  return 0;
}

template <bool Guard, bool Vol, bool F32 = false, bool VM = false>
int node_pass_any(const Model& m, State& st, double h, double vmax2, const float* const* vm = nullptr,
                  int nvm = 0) {
  switch (m.gather.width) {
    case 4:
      return node_pass<4, Guard, Vol, F32, VM>(m, st, h, vmax2, vm, nvm);
    case 6:
      return node_pass<6, Guard, Vol, F32, VM>(m, st, h, vmax2, vm, nvm);
    case 8:
      return node_pass<8, Guard, Vol, F32, VM>(m, st, h, vmax2, vm, nvm);
    case 10:
      return node_pass<10, Guard, Vol, F32, VM>(m, st, h, vmax2, vm, nvm);
    case 12:
      return node_pass<12, Guard, Vol, F32, VM>(m, st, h, vmax2, vm, nvm);
    default:
      return node_pass<16, Guard, Vol, F32, VM>(m, st, h, vmax2, vm, nvm);
  }
}

std::atomic<bool> g_springs_f32{true};

// A sub-step with the springs in float (spring_f32.hpp): with the float volume pass, whose displacement
// mirror they read. Without the stable step's bound the volume pass runs first and leaves the mirror; with
// it, the springs' stiffening enters the volume pass's rule, so the springs fill the mirror themselves and
// run first (the volume pass refills it: the same numbers).
int gather_substep_f32(const Model& m, State& st, double h, double vmax2, bool guard, bool stiffening,
                       const LocalStiffening* local) {
  const VolumeTermsF32& V = *m.volume_f32;
  float* F = reinterpret_cast<float*>(st.spring_force.data());
  st.f.setZero();
  if (stiffening) {
    fill_displacements_f32(V, st.x.data(), local->f32);
    const double ss = spring_slots_f32(V.springs, local->f32, F, true);
    st.stiffening = volume_forces(m, st.x.data(), st.f.data(), true, ss, local);
  } else {
    volume_forces(m, st.x.data(), st.f.data(), false, 1.0, local);  // the float pass: u in local->f32
    spring_slots_f32(V.springs, local->f32, F, false);
  }
  return guard ? node_pass_any<true, true, true>(m, st, h, vmax2)
               : node_pass_any<false, true, true>(m, st, h, vmax2);
}

}  // namespace

int gather_substep(const Model& m, State& st, double h, double vmax2, bool guard, bool stiffening,
                   const LocalStiffening* local) {
  if (float_substep_applies(m, local)) return gather_substep_f32(m, st, h, vmax2, guard, stiffening, local);
  double* F = st.spring_force.data();
  const double ss = stiffening ? slot_forces<true>(m, st.x.data(), F) : slot_forces<false>(m, st.x.data(), F);
  if (m.volume.size() > 0 || m.compression.size() > 0) {  // the volume (and compression) terms' forces
                                                          // into st.f first, read by the node pass
    st.f.setZero();
    const double s = volume_forces(m, st.x.data(), st.f.data(), stiffening, ss, local);
    if (stiffening) st.stiffening = s;
    return guard ? node_pass_any<true, true>(m, st, h, vmax2) : node_pass_any<false, true>(m, st, h, vmax2);
  }
  if (stiffening) st.stiffening = ss;
  return guard ? node_pass_any<true, false>(m, st, h, vmax2) : node_pass_any<false, false>(m, st, h, vmax2);
}

bool set_gather_springs_f32(bool on) {
  return g_springs_f32.exchange(on);
}

Index set_spring_gather_max_f32(Index springs) {
  return g_gather_max_f32.exchange(springs);
}

bool float_substep_applies(const Model& m, const LocalStiffening* local) {
  return volume_f32_substep(m, local) && g_springs_f32.load(std::memory_order_relaxed) &&
         m.volume_f32->springs.size() == static_cast<std::size_t>(m.num_springs());
}

int node_pass_f32(const Model& m, State& st, double h, double vmax2, bool guard, const float* const* mirrors,
                  int count) {
  return guard ? node_pass_any<true, true, true, true>(m, st, h, vmax2, mirrors, count)
               : node_pass_any<false, true, true, true>(m, st, h, vmax2, mirrors, count);
}

}  // namespace medspring::detail

namespace medspring::detail {

void spring_chunk_forces(const Model& m, Index s0, Index nb, const double* x, double* F, bool stiffening,
                         std::int64_t& stiff_bits) {
  v4d* Fo = reinterpret_cast<v4d*>(F);
  Index done = 0;
#if defined(MEDSPRING_FUSED_SPRING_PASS)
  done = nb - nb % 4;
  const v4i z{stiff_bits, stiff_bits, stiff_bits, stiff_bits};
  const v4i sv = stiffening
                     ? fused_forces<true, true>(s0, s0 + done, m.springs, m.inv_k.data(), x, Fo, nullptr, z)
                     : fused_forces<false, true>(s0, s0 + done, m.springs, m.inv_k.data(), x, Fo, nullptr, z);
  for (int k = 0; k < 4; ++k) stiff_bits = stiff_bits < sv[k] ? sv[k] : stiff_bits;
#endif
  if (done == nb) return;
  alignas(64) double ex[kBlock], ey[kBlock], ez[kBlock], tt[kBlock];
  for (Index b0 = s0 + done; b0 < s0 + nb; b0 += kBlock) {
    const Index nk = std::min(kBlock, s0 + nb - b0);
    spring_vectors(nk, m.springs.i.data() + b0, m.springs.j.data() + b0, x, ex, ey, ez);
    const double* L0 = m.springs.L0.data() + b0;
    const double* K = m.springs.k.data() + b0;
    const double* KP = m.springs.kp.data() + b0;
    const double* IK = m.inv_k.data() + b0;
    if (stiffening)
      block_forces<true>(nk, ex, ey, ez, L0, K, KP, IK, tt, stiff_bits);
    else
      block_forces<false>(nk, ex, ey, ez, L0, K, KP, IK, tt, stiff_bits);
    for (Index q = 0; q < nk; ++q) {
      const double t = tt[q];
      Fo[b0 - s0 + q] = v4d{t * ex[q], t * ey[q], t * ez[q], 0.0};
    }
  }
}

}  // namespace medspring::detail
