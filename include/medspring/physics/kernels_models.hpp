// Several models per thread in the grid kernel (gpu::Options::models_per_thread, docs/gpu.md): one thread
// takes the same table row of M consecutive models of a batch that shares its spring table (topology and
// spring parameters), so that each table entry -- the other end's index, the rest length and the stiffness
// parameters (or their compact class) -- is loaded once and applied to M models' positions: the table's
// traffic divided by M, and M independent position gathers in flight per entry. Each model's terms are
// those of hd::node_substep, summed in the same order, so each model's result is the one of M single-model
// calls (bit for bit where the compiler contracts both alike: physics_tests HdModels.*). MEDSPRING_HD like
// kernels.hpp: the CUDA kernel (src/gpu/kernels.cu, substep_models_kernel) and the CPU-side test run them.
#pragma once

#include "medspring/physics/kernels_split.hpp"

namespace medspring::hd {

/// Where model m of a group starts, relative to model 0 of the group (elements). The spring table is
/// shared (one copy for every model).
struct ModelStrides {
  long long state = 0;  // positions and velocities: 3 n
  long long node = 0;   // node parameters (x0 3x, mass, damping, k_r, fixed): 0 when the batch shares them
  long long slot = 0;   // load slots: n
  long long loads = 0;  // this substep's load rows: 3 x rows
  long long parts = 0;  // the grid kernel's split rows' partial sums
};

/// Model m's node arrays: N's per-node pointers moved by m strides (compact classes are shared).
template <class R>
MEDSPRING_HD inline NodeArrays<R> model_nodes(const NodeArrays<R>& N, const ModelStrides& S, int m) {
  NodeArrays<R> Nm = N;
  const long long ns = S.node * m;
  Nm.x0 += 3 * ns;
  if (Nm.mass) {
    Nm.mass += ns;
    Nm.damping += ns;
    Nm.kr += ns;
  }
  Nm.fixed += ns;
  Nm.load_slot += S.slot * m;
  return Nm;
}

/// Adds the spring forces on node a = row_node(T, r) of each model m with bit m of `mask` set (positions
/// x + m S.state) to f[3 m .. 3 m + 2]: each table entry is loaded once, the M models' other-end positions
/// are loaded before any force is formed, then each model's force is formed and added -- per model the
/// terms of gather_spring_forces, in the same order. stiff[m]: model m's stiffening (with Stiff).
template <bool Soft, bool Stiff, int M, class R>
MEDSPRING_HD inline void gather_spring_forces_models(const SpringTable<R>& T, int r, int a, const R* x,
                                                     long long xs, unsigned mask, R* stiff, R* f) {
  static_assert(M >= 1 && M <= 8, "models per thread: 1..8");
  const int slice = r / kSlice;
  const int w = T.slice_width[slice];
  int e = T.slice_begin[slice] + (r - slice * kSlice);
  R xa[M], ya[M], za[M];  // registers: indexed by unrolled constants only
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int m = 0; m < M; ++m) {
    xa[m] = ya[m] = za[m] = R(0);
    if (!((mask >> m) & 1u)) continue;
    const R* xm = x + xs * m;
    xa[m] = xm[3 * a];
    ya[m] = xm[3 * a + 1];
    za[m] = xm[3 * a + 2];
  }
  for (int j = 0; j < w; ++j, e += kSlice) {
    const int b = T.other[e];  // the entry, once for the M models
    const R l0 = T.L0[e];
    R k, kp, ik;
    spring_params(T, e, k, kp, ik);
    R px[M], py[M], pz[M];
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
    for (int m = 0; m < M; ++m) {
      px[m] = py[m] = pz[m] = R(0);
      if (!((mask >> m) & 1u)) continue;
      const R* xm = x + xs * m;
      px[m] = xm[3 * b];
      py[m] = xm[3 * b + 1];
      pz[m] = xm[3 * b + 2];
    }
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
    for (int m = 0; m < M; ++m) {
      if (!((mask >> m) & 1u)) continue;
      R fx, fy, fz;
      if (!spring_force<Soft, Stiff>(px[m] - xa[m], py[m] - ya[m], pz[m] - za[m], l0, k, kp, ik, stiff[m], fx,
                                     fy, fz))
        continue;
      f[3 * m] += fx;
      f[3 * m + 1] += fy;
      f[3 * m + 2] += fz;
    }
  }
}

/// One fused substep of the node of table row r in each model m with bit m of `mask` set, as M calls of
/// node_substep<Soft, Stiff> (model m: node arrays model_nodes(N, S, m), loads + m S.loads, x, v, xo, vo
/// + m S.state, step h[m], stiffening stiff[m]). Returns the largest kNode* code.
template <bool Soft, bool Stiff, int M, class R>
MEDSPRING_HD inline int node_substep_models(const NodeArrays<R>& N, const SpringTable<R>& T,
                                            const ModelStrides& S, unsigned mask, int r, const R* h, R vmax2,
                                            const R* loads, const R* x, const R* v, R* xo, R* vo, R* stiff) {
  const int a = row_node(T, r);
  const int q = 3 * a;
  R g[3 * M];
  unsigned gather = 0;  // the models whose springs are gathered: free nodes, and pinned ones for Stiff
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int m = 0; m < M; ++m) {
    g[3 * m] = g[3 * m + 1] = g[3 * m + 2] = R(0);
    if (!((mask >> m) & 1u)) continue;
    const NodeArrays<R> Nm = model_nodes(N, S, m);
    if (Nm.fixed[a]) {
      if (Stiff) gather |= 1u << m;
      continue;
    }
    gather |= 1u << m;
    load_and_return_force(Nm, a, loads + S.loads * m, x + S.state * m, g + 3 * m);
  }
  gather_spring_forces_models<Soft, Stiff, M>(T, r, a, x, S.state, gather, stiff, g);
  int code = kNodeOk;
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int m = 0; m < M; ++m) {
    if (!((mask >> m) & 1u)) continue;
    const NodeArrays<R> Nm = model_nodes(N, S, m);
    const long long o = S.state * m;
    if (Nm.fixed[a]) {
      keep_node(q, x + o, v + o, xo + o, vo + o);
      continue;
    }
    const int c = advance_node(Nm, a, h[m], vmax2, x + o, v + o, g + 3 * m, xo + o, vo + o);
    code = c > code ? c : code;
  }
  return code;
}

/// grid_split_gather for M models: whole rows run node_substep_models, chunk rows write each model's
/// springs' force sum to parts + m S.parts + 3 slot.
template <bool Soft, bool Stiff, int M, class R>
MEDSPRING_HD inline int grid_split_gather_models(const NodeArrays<R>& N, const SpringTable<R>& T,
                                                 const GridSplit& G, const ModelStrides& S, unsigned mask,
                                                 int r, const R* h, R vmax2, const R* loads, const R* x,
                                                 const R* v, R* xo, R* vo, R* parts, R* stiff) {
  const int p = G.part[r];
  if (p == -1)
    return node_substep_models<Soft, Stiff, M>(N, T, S, mask, r, h, vmax2, loads, x, v, xo, vo, stiff);
  if (p >= 0) {
    R f[3 * M];
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
    for (int m = 0; m < 3 * M; ++m) f[m] = R(0);
    gather_spring_forces_models<Soft, Stiff, M>(T, r, row_node(T, r), x, S.state, mask, stiff, f);
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
    for (int m = 0; m < M; ++m) {
      if (!((mask >> m) & 1u)) continue;
      R* out = parts + S.parts * m + 3 * p;
      out[0] = f[3 * m];
      out[1] = f[3 * m + 1];
      out[2] = f[3 * m + 2];
    }
  }
  return kNodeOk;
}

/// grid_split_finish for M models (each lead row advances its node in every model of the mask).
template <int M, class R>
MEDSPRING_HD inline int grid_split_finish_models(const NodeArrays<R>& N, const GridSplit& G,
                                                 const ModelStrides& S, unsigned mask, int r, const R* h,
                                                 R vmax2, const R* loads, const R* x, const R* v, R* xo,
                                                 R* vo, const R* parts) {
  if (G.lead[r] < 0) return kNodeOk;
  int code = kNodeOk;
  for (int m = 0; m < M; ++m) {
    if (!((mask >> m) & 1u)) continue;
    const long long o = S.state * m;
    const int c = grid_split_finish(model_nodes(N, S, m), G, r, h[m], vmax2, loads + S.loads * m, x + o,
                                    v + o, xo + o, vo + o, parts + S.parts * m);
    code = c > code ? c : code;
  }
  return code;
}

}  // namespace medspring::hd
