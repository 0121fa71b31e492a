// The physics of one spring and one node, written once for the CPU step (spring_kernel.hpp,
// integrators.cpp, loads.cpp, spring_law.hpp) and the CUDA kernels (src/gpu, docs/gpu.md): every
// function is MEDSPRING_HD (`__host__ __device__` under nvcc) and templated on the real type (double;
// float for the GPU's fp32 option). No Eigen, no standard library beyond <math.h>, so nvcc compiles it
// for the device. The CPU instantiations with R = double are the arithmetic the engine always did
// (same operations in the same order): results are bit-identical to before.
#pragma once

#include <math.h>

#include "medspring/core/hd.hpp"

namespace medspring::hd {

// std::max / std::min semantics (first argument kept on ties and NaN), callable on the device.
template <class R>
MEDSPRING_HD inline R max_of(R a, R b) {
  return a < b ? b : a;
}
template <class R>
MEDSPRING_HD inline R min_of(R a, R b) {
  return b < a ? b : a;
}
MEDSPRING_HD inline double abs_of(double v) {
  return ::fabs(v);
}
MEDSPRING_HD inline float abs_of(float v) {
  return ::fabsf(v);
}
MEDSPRING_HD inline double sqrt_of(double v) {
  return ::sqrt(v);
}
MEDSPRING_HD inline float sqrt_of(float v) {
  return ::sqrtf(v);
}
MEDSPRING_HD inline double copysign_of(double m, double s) {
  return ::copysign(m, s);
}
MEDSPRING_HD inline float copysign_of(float m, float s) {
  return ::copysignf(m, s);
}

/// Springs shorter than this (mm) are skipped (§1.3: direction undefined).
inline constexpr double kMinSpringLength = 1e-9;

/// Peak elongation of a soft spring (k' < 0 only): Delta* = sqrt(k / (3|k'|)).
template <class R>
MEDSPRING_HD inline R soft_peak(R k, R kp) {
  return sqrt_of(k / (R(3) * -kp));
}

/// phi(Delta) = k Delta + k' Delta^3 (eq. 5), clamped beyond the soft-spring peak (§1.7).
template <class R>
MEDSPRING_HD inline R spring_tension(R k, R kp, R delta) {
  if (kp < 0) {
    const R ds = soft_peak(k, kp);
    if (abs_of(delta) > ds) return copysign_of(k * ds + kp * ds * ds * ds, delta);
  }
  return delta * (k + kp * delta * delta);
}

/// d phi / d Delta (0 beyond the soft-spring peak).
template <class R>
MEDSPRING_HD inline R spring_tension_derivative(R k, R kp, R delta) {
  if (kp < 0 && abs_of(delta) > soft_peak(k, kp)) return R(0);
  return k + R(3) * kp * delta * delta;
}

/// Force t e on the end i of a spring with e = x_j - x_i (the end j gets -t e; a gather that evaluates
/// the spring from its end j passes e = x_i - x_j and gets exactly the negated force). False (no force)
/// for a spring shorter than kMinSpringLength. With Stiff, stiff = max(stiff, kappa / k) with
/// kappa = max(phi', |phi| / L) and ik = 1/k (0 for k = 0), the run-time stability measure (§2.2).
/// Soft: the model has soft springs (clamped law); else the plain Duffing law is used.
template <bool Soft, bool Stiff, class R>
MEDSPRING_HD inline bool spring_force(R ex, R ey, R ez, R L0, R k, R kp, R ik, R& stiff, R& fx, R& fy,
                                      R& fz) {
  const R L2 = ex * ex + ey * ey + ez * ez;
  if (L2 < R(kMinSpringLength) * R(kMinSpringLength)) return false;
  const R L = sqrt_of(L2);
  const R inv = R(1) / L;
  const R d = L - L0;
  R phi, dphi;
  if constexpr (Soft) {
    phi = spring_tension(k, kp, d);
    dphi = spring_tension_derivative(k, kp, d);
  } else {
    const R kp_d2 = kp * d * d;
    phi = d * (k + kp_d2);  // eq. (5)
    dphi = k + R(3) * kp_d2;
  }
  const R t = phi * inv;  // phi / L
  if constexpr (Stiff) stiff = max_of(stiff, max_of(dphi, abs_of(t)) * ik);
  fx = t * ex;
  fy = t * ey;
  fz = t * ez;
  return true;
}

/// f = f_ext - k_r (x - x0) of one node (external load and return spring, §1.4): out[0..3).
template <class R>
MEDSPRING_HD inline void return_force(const R* fe, const R* x, const R* x0, R kr, R* out) {
  out[0] = fe[0] - kr * (x[0] - x0[0]);
  out[1] = fe[1] - kr * (x[1] - x0[1]);
  out[2] = fe[2] - kr * (x[2] - x0[2]);
}

/// 1 / (m + h d): the implicit node damping of the symplectic step (§2.1).
template <class R>
MEDSPRING_HD inline R step_coefficient(R mass, R damping, R h) {
  return R(1) / (mass + h * damping);
}

/// Symplectic Euler with implicit damping (§2.1) of one free node: v' = (m v + h g) c with
/// c = step_coefficient(m, d, h). Returns |v'|^2 (the guard compares it with v_max^2).
template <class R>
MEDSPRING_HD inline R symplectic_velocity(R mass, R c, R h, const R* v, const R* g, R* vo) {
  vo[0] = (mass * v[0] + h * g[0]) * c;
  vo[1] = (mass * v[1] + h * g[1]) * c;
  vo[2] = (mass * v[2] + h * g[2]) * c;
  return vo[0] * vo[0] + vo[1] * vo[1] + vo[2] * vo[2];
}

/// x' = x + h v' (in place when xo == x).
template <class R>
MEDSPRING_HD inline void symplectic_position(R h, const R* x, const R* vo, R* xo) {
  xo[0] = x[0] + h * vo[0];
  xo[1] = x[1] + h * vo[1];
  xo[2] = x[2] + h * vo[2];
}

/// The guard's test (§2.5): |v|^2 within v_max^2 (false for NaN).
template <class R>
MEDSPRING_HD inline bool velocity_ok(R v2, R vmax2) {
  return v2 <= vmax2;
}

/// Profile factor in [0, 1] of a point load at time t (§1.6): PointLoad::scale.
template <class R>
MEDSPRING_HD inline R load_scale(R t, R t_on, R t_ramp, R t_release, bool ramp_down) {
  if (t < t_on) return R(0);
  R s = t_ramp > 0 ? min_of((t - t_on) / t_ramp, R(1)) : R(1);
  if (t >= t_release) {
    if (!ramp_down || t_ramp <= 0) return R(0);
    s = min_of(s, max_of(R(0), R(1) - (t - t_release) / t_ramp));
  }
  return s;
}

/// Springs of every node as a sliced ELL table of rows (slices of kSlice consecutive rows, each stored
/// column-major over the widest row of its slice, so that the threads of a warp read consecutive
/// entries). Row r holds the springs of node row_node[r] (identity when row_node is null) in increasing
/// spring index, each seen from that node: `other` is the spring's other end; padding entries point at
/// the node itself (zero length: skipped). The row order balances the work (RowOrder in
/// spring_table.hpp: heavy rows such as the kidney's atoms grouped into their own warps); a node's
/// terms and their order do not depend on it. Built by make_spring_table (physics/spring_table.hpp).
inline constexpr int kSlice = 32;
template <class R>
struct SpringTable {
  int nodes = 0;
  const int* row_node = nullptr;     // (nodes) node of row r; null: row r is node r
  const int* slice_begin = nullptr;  // (slices) first entry of the slice
  const int* slice_width = nullptr;  // (slices) entries per node in the slice
  const int* other = nullptr;        // (entries) other end node
  const R* L0 = nullptr;             // (entries) rest length
  const R* k = nullptr;              // (entries) linear stiffness
  const R* kp = nullptr;             // (entries) cubic stiffness
  const R* ik = nullptr;             // (entries) 1/k (0 for k = 0)
  // Compact parameters (compact_spring_params, spring_table.hpp): when cls is set, entry e's k, k', 1/k
  // are class cls[e]'s ck, ckp, cik (k, kp, ik unused): 2 bytes per entry instead of 3 reals, the same
  // values, so the same arithmetic. Models whose springs share a few stiffnesses (the tube, a uniform
  // material) move fewer bytes per substep.
  const unsigned short* cls = nullptr;  // (entries) parameter class
  const R* ck = nullptr;                // (classes) linear stiffness
  const R* ckp = nullptr;               // (classes) cubic stiffness
  const R* cik = nullptr;               // (classes) 1/k
  // Packed entries (pack_spring_table, spring_table.hpp; gpu::Options::packed_table): when packed is set,
  // entry e of row r (node a) is one 32-bit word: its other end's offset b - a (signed, the high
  // 32 - class_bits bits) and its class (the low class_bits bits), a class being a distinct (L0, k, k',
  // 1/k) -- cL0, ck, ckp, cik (other, L0, k, kp, ik, cls unused). 4 bytes per entry instead of 4 + 2 +
  // sizeof(R) (compact) or 4 + 4 sizeof(R); the same values, so the same arithmetic. Read by the
  // gather's Packed variant only (gather_spring_forces<..., Packed = true>).
  const unsigned* packed = nullptr;  // (entries)
  int class_bits = 0;
  const R* cL0 = nullptr;  // (classes) rest length
};

/// A packed entry's class and other end (the node of its row is a): the low `bits` bits, and a plus the
/// signed high bits (arithmetic shift).
MEDSPRING_HD inline int packed_class(unsigned word, int bits) {
  return static_cast<int>(word & ((1u << bits) - 1u));
}
MEDSPRING_HD inline int packed_other(unsigned word, int bits, int a) {
  return a + (static_cast<int>(word) >> bits);
}

/// Entry e's stiffness parameters (k, k', 1/k), from the per-entry arrays or their compact classes.
template <class R>
MEDSPRING_HD inline void spring_params(const SpringTable<R>& T, int e, R& k, R& kp, R& ik) {
  if (T.cls) {
    const int c = T.cls[e];
    k = T.ck[c];
    kp = T.ckp[c];
    ik = T.cik[c];
  } else {
    k = T.k[e];
    kp = T.kp[e];
    ik = T.ik[e];
  }
}

/// Node of table row r.
template <class R>
MEDSPRING_HD inline int row_node(const SpringTable<R>& T, int r) {
  return T.row_node ? T.row_node[r] : r;
}

/// Adds the spring forces on node a = row_node(T, r) (positions x, interleaved xyz) to f[0..3), in
/// increasing spring index: the same terms, summed in the same order, as the CPU's serial spring pass.
/// U > 1 (the gather batch, gpu::Options::gather_batch): U entries at a time have their other ends'
/// positions, rest lengths and parameters loaded before any force is formed, so that a GPU thread has U
/// independent gathers in flight instead of one (the gather is latency-bound once the table is compact);
/// the forces are then added in entry order: the same terms in the same order for every U (equal to
/// rounding: a compiler may contract f += t e into an FMA differently when it vectorises the batch).
/// Packed (pack_spring_table): the entries are packed words (T.packed), one entry at a time (U unused);
/// the same values in the same order, so the same sums.
template <bool Soft, bool Stiff, int U = 1, bool Packed = false, class R>
MEDSPRING_HD inline void gather_spring_forces(const SpringTable<R>& T, int r, int a, const R* x, R& stiff,
                                              R* f) {
  static_assert(U >= 1 && U <= 8, "gather batch: 1..8 entries");
  const int slice = r / kSlice;
  const int w = T.slice_width[slice];
  int e = T.slice_begin[slice] + (r - slice * kSlice);
  const R xa = x[3 * a], ya = x[3 * a + 1], za = x[3 * a + 2];
  if constexpr (Packed) {
    const int bits = T.class_bits;
    for (int j = 0; j < w; ++j, e += kSlice) {
      const unsigned word = T.packed[e];
      const int b = packed_other(word, bits, a), c = packed_class(word, bits);
      R fx, fy, fz;
      if (!spring_force<Soft, Stiff>(x[3 * b] - xa, x[3 * b + 1] - ya, x[3 * b + 2] - za, T.cL0[c], T.ck[c],
                                     T.ckp[c], T.cik[c], stiff, fx, fy, fz))
        continue;
      f[0] += fx;
      f[1] += fy;
      f[2] += fz;
    }
    return;
  }
  int j = 0;
  if constexpr (U > 1) {
    for (; j + U <= w; j += U, e += U * kSlice) {
      R px[U], py[U], pz[U], l0[U];  // registers: indexed by unrolled constants only
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
      for (int u = 0; u < U; ++u) {
        const int eu = e + u * kSlice, b = T.other[eu];
        px[u] = x[3 * b];
        py[u] = x[3 * b + 1];
        pz[u] = x[3 * b + 2];
        l0[u] = T.L0[eu];
      }
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
      for (int u = 0; u < U; ++u) {
        R k, kp, ik, fx, fy, fz;
        spring_params(T, e + u * kSlice, k, kp, ik);
        if (!spring_force<Soft, Stiff>(px[u] - xa, py[u] - ya, pz[u] - za, l0[u], k, kp, ik, stiff, fx, fy,
                                       fz))
          continue;
        f[0] += fx;
        f[1] += fy;
        f[2] += fz;
      }
    }
  }
  for (; j < w; ++j, e += kSlice) {
    const int b = T.other[e];
    R k, kp, ik, fx, fy, fz;
    spring_params(T, e, k, kp, ik);
    if (!spring_force<Soft, Stiff>(x[3 * b] - xa, x[3 * b + 1] - ya, x[3 * b + 2] - za, T.L0[e], k, kp, ik,
                                   stiff, fx, fy, fz))
      continue;
    f[0] += fx;
    f[1] += fy;
    f[2] += fz;
  }
}

/// Per-node arrays of a model for the fused step.
template <class R>
struct NodeArrays {
  int nodes = 0;
  const R* x0 = nullptr;                 // (3n) rest positions
  const R* mass = nullptr;               // (n)
  const R* damping = nullptr;            // (n)
  const R* kr = nullptr;                 // (n) return-spring stiffness
  const unsigned char* fixed = nullptr;  // (n) 1 = pinned
  const int* load_slot = nullptr;        // (n) row of the substep's load table, -1 = no load
  // Compact parameters (compact_node_params): when cls is set, node a's mass, damping and k_r are class
  // cls[a]'s (mass, damping, kr unused).
  const unsigned short* cls = nullptr;  // (n) parameter class
  const R* cmass = nullptr;             // (classes)
  const R* cdamping = nullptr;          // (classes)
  const R* ckr = nullptr;               // (classes)
};

/// Node a's mass, damping and return-spring stiffness, from the per-node arrays or their classes.
template <class R>
MEDSPRING_HD inline R node_mass(const NodeArrays<R>& N, int a) {
  return N.cls ? N.cmass[N.cls[a]] : N.mass[a];
}
template <class R>
MEDSPRING_HD inline R node_damping(const NodeArrays<R>& N, int a) {
  return N.cls ? N.cdamping[N.cls[a]] : N.damping[a];
}
template <class R>
MEDSPRING_HD inline R node_kr(const NodeArrays<R>& N, int a) {
  return N.cls ? N.ckr[N.cls[a]] : N.kr[a];
}

/// Outcome codes of one node's update (the guard, §2.5).
inline constexpr int kNodeOk = 0, kNodeTooFast = 1, kNodeNonFinite = 2;

/// A pinned node keeps its position and velocity (vo == v: nothing to copy).
template <class R>
MEDSPRING_HD inline void keep_node(int q, const R* x, const R* v, R* xo, R* vo) {
  xo[q] = x[q];
  xo[q + 1] = x[q + 1];
  xo[q + 2] = x[q + 2];
  if (vo != v) {
    vo[q] = v[q];
    vo[q + 1] = v[q + 1];
    vo[q + 2] = v[q + 2];
  }
}

/// Node a's external load (row N.load_slot[a] of `loads`, if any) plus its return spring, into g.
template <class R>
MEDSPRING_HD inline void load_and_return_force(const NodeArrays<R>& N, int a, const R* loads, const R* x,
                                               R* g) {
  R fe[3] = {R(0), R(0), R(0)};  // registers (a pointer to a local array would spill it to the stack)
  const int slot = N.load_slot[a];
  if (slot >= 0) {
    fe[0] = loads[3 * slot];
    fe[1] = loads[3 * slot + 1];
    fe[2] = loads[3 * slot + 2];
  }
  return_force(fe, x + 3 * a, N.x0 + 3 * a, node_kr(N, a), g);
}

/// Node a's symplectic update with implicit damping under its total force g (reads x, v; writes xo, vo;
/// vo may be v). Returns a kNode* code (the guard, §2.5).
template <class R>
MEDSPRING_HD inline int advance_node(const NodeArrays<R>& N, int a, R h, R vmax2, const R* x, const R* v,
                                     const R* g, R* xo, R* vo) {
  const int q = 3 * a;
  const R mass = node_mass(N, a);
  const R c = step_coefficient(mass, node_damping(N, a), h);
  R vn[3];
  const R v2 = symplectic_velocity(mass, c, h, v + q, g, vn);
  vo[q] = vn[0];
  vo[q + 1] = vn[1];
  vo[q + 2] = vn[2];
  symplectic_position(h, x + q, vn, xo + q);
  if (!velocity_ok(v2, vmax2)) return isfinite(v2) ? kNodeTooFast : kNodeNonFinite;
  return kNodeOk;
}

/// One fused substep of the node of table row r: force (external load from `loads` rows, return spring,
/// springs) and symplectic update with implicit damping, reading x, v and writing xo, vo. x and xo are
/// distinct buffers (every node reads its neighbours' old positions); v and vo may be one buffer (a node
/// reads only its own velocity, before writing it). A pinned node keeps x and v. Returns a kNode* code.
template <bool Soft, bool Stiff, int U = 1, bool Packed = false, class R>
MEDSPRING_HD inline int node_substep(const NodeArrays<R>& N, const SpringTable<R>& T, int r, R h, R vmax2,
                                     const R* loads, const R* x, const R* v, R* xo, R* vo, R& stiff) {
  const int a = row_node(T, r);
  const int q = 3 * a;
  if (N.fixed[a]) {
    keep_node(q, x, v, xo, vo);
    if constexpr (Stiff) {  // its springs still count for the stability measure
      R g[3] = {R(0), R(0), R(0)};
      gather_spring_forces<Soft, true, U, Packed>(T, r, a, x, stiff, g);
    }
    return kNodeOk;
  }
  R g[3];
  load_and_return_force(N, a, loads, x, g);
  gather_spring_forces<Soft, Stiff, U, Packed>(T, r, a, x, stiff, g);
  return advance_node(N, a, h, vmax2, x, v, g, xo, vo);
}

/// One thread's share of a substep in the one-block-per-model kernel (docs/gpu.md): rows t, t + threads,
/// ... of the table, reading positions x and writing xo (the block's two position buffers), velocities v
/// updated in place. Returns the largest kNode* code of its rows. The kernel runs it on every thread of
/// the block between barriers; the CPU-side test runs it for t = 0 .. threads - 1 in turn.
template <bool Soft, bool Stiff, class R>
MEDSPRING_HD inline int block_rows(const NodeArrays<R>& N, const SpringTable<R>& T, int t, int threads, R h,
                                   R vmax2, const R* loads, const R* x, R* v, R* xo, R& stiff) {
  int code = kNodeOk;
  for (int r = t; r < N.nodes; r += threads) {
    const int c = node_substep<Soft, Stiff>(N, T, r, h, vmax2, loads, x, v, xo, v, stiff);
    code = c > code ? c : code;
  }
  return code;
}

}  // namespace medspring::hd
