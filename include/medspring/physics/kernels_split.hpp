// Heavy rows split across threads in the one-block-per-model kernel (docs/gpu.md, "Load balance"): a node
// with more springs than a chunk (the hybrid kidney's atoms, up to 74 spokes) is gathered as several table
// rows of at most `chunk` springs each, by different threads; each writes its partial force to a slot,
// and after a barrier one thread sums the node's slots in spring order and advances the node. The other
// nodes run hd::node_substep unchanged. MEDSPRING_HD like kernels.hpp: the CUDA kernel and the CPU-side
// test run these functions.
#pragma once

#include "medspring/physics/kernels.hpp"

namespace medspring::hd {

/// The split rows of a table built by make_split_table (physics/spring_table.hpp).
struct SplitRows {
  int rows = 0;                     // table rows (whole nodes + chunks)
  const int* part = nullptr;        // (rows) -1: the row is a whole node; else the chunk's slot
  int heavy = 0;                    // split nodes
  const int* heavy_node = nullptr;  // (heavy) node
  const int* part_begin = nullptr;  // (heavy + 1) slots of split node h: part_begin[h] .. part_begin[h+1]
};

/// A chunk row's spring force sum (its springs in table order), written to out[0..2].
template <bool Soft, bool Stiff, int U = 1, bool Packed = false, class R>
MEDSPRING_HD inline void chunk_force(const SpringTable<R>& T, int r, const R* x, R& stiff, R* out) {
  R f[3] = {R(0), R(0), R(0)};  // registers
  gather_spring_forces<Soft, Stiff, U, Packed>(T, r, row_node(T, r), x, stiff, f);
  out[0] = f[0];
  out[1] = f[1];
  out[2] = f[2];
}

/// Phase 1 of a substep for thread t: whole rows as block_rows does (x read, xo written, v in place);
/// chunk rows write their springs' force sum to parts[3 slot ..]. Returns the largest kNode* code.
template <bool Soft, bool Stiff, class R>
MEDSPRING_HD inline int split_phase1(const NodeArrays<R>& N, const SpringTable<R>& T, const SplitRows& S,
                                     int t, int threads, R h, R vmax2, const R* loads, const R* x, R* v,
                                     R* xo, R* parts, R& stiff) {
  int code = kNodeOk;
  for (int r = t; r < S.rows; r += threads) {
    const int p = S.part[r];
    if (p < 0) {
      const int c = node_substep<Soft, Stiff>(N, T, r, h, vmax2, loads, x, v, xo, v, stiff);
      code = c > code ? c : code;
    } else {
      chunk_force<Soft, Stiff>(T, r, x, stiff, parts + 3 * p);
    }
  }
  return code;
}

/// A split node's update from its chunks' force sums parts[3 p0 ..], p0 .. p0 + count - 1 in spring order:
/// load and return spring first, then the chunks, then node_substep's symplectic update (v read from v,
/// written to vo; vo == v: in place, as the block kernel). A pinned node keeps x (and v). Returns kNode*.
template <class R>
MEDSPRING_HD inline int split_node_advance(const NodeArrays<R>& N, int a, R h, R vmax2, const R* loads,
                                           const R* x, const R* v, R* xo, R* vo, const R* parts, int count) {
  if (N.fixed[a]) {
    keep_node(3 * a, x, v, xo, vo);
    return kNodeOk;
  }
  R g[3];
  load_and_return_force(N, a, loads, x, g);
  for (int p = 0; p < count; ++p) {
    g[0] += parts[3 * p];
    g[1] += parts[3 * p + 1];
    g[2] += parts[3 * p + 2];
  }
  return advance_node(N, a, h, vmax2, x, v, g, xo, vo);
}

/// Phase 2 (after a barrier) for thread t: each split node h = t, t + threads, ...: load and return
/// spring, plus its chunks' sums in spring order, then node_substep's update (a pinned node keeps x, v).
template <class R>
MEDSPRING_HD inline int split_phase2(const NodeArrays<R>& N, const SplitRows& S, int t, int threads, R h,
                                     R vmax2, const R* loads, const R* x, R* v, R* xo, const R* parts) {
  int code = kNodeOk;
  for (int k = t; k < S.heavy; k += threads) {
    const int p0 = S.part_begin[k];
    const int e = split_node_advance(N, S.heavy_node[k], h, vmax2, loads, x, v, xo, v, parts + 3 * p0,
                                     S.part_begin[k + 1] - p0);
    code = e > code ? e : code;
  }
  return code;
}

/// The grid kernel's rows with heavy nodes split (make_grid_split_table, physics/spring_table.hpp): one
/// thread per row as the grid kernel; a heavy node's chunks lie in consecutive rows of one warp, the first
/// of them its lead. Phase 1 (grid_split_gather): whole rows run node_substep, chunk rows write their
/// springs' force sum to parts[3 slot ..]; after the warp's barrier (__syncwarp: the chunks of a node are
/// in the lead's warp) phase 2 (grid_split_finish): each lead advances its node (split_node_advance).
struct GridSplit {
  int rows = 0;                     // table rows (whole nodes, chunks, padding)
  const int* part = nullptr;        // (rows) -1: whole node; -2: padding (no work); else the chunk's slot
  const int* lead = nullptr;        // (rows) k: the first chunk of split node k; else -1
  const int* part_begin = nullptr;  // (heavy + 1) slots of split node k: part_begin[k] .. part_begin[k+1]
  const int* heavy_node = nullptr;  // (heavy) node
};

template <bool Soft, bool Stiff, int U = 1, bool Packed = false, class R>
MEDSPRING_HD inline int grid_split_gather(const NodeArrays<R>& N, const SpringTable<R>& T, const GridSplit& G,
                                          int r, R h, R vmax2, const R* loads, const R* x, const R* v, R* xo,
                                          R* vo, R* parts, R& stiff) {
  const int p = G.part[r];
  if (p == -1) return node_substep<Soft, Stiff, U, Packed>(N, T, r, h, vmax2, loads, x, v, xo, vo, stiff);
  if (p >= 0) {
    chunk_force<Soft, Stiff, U, Packed>(T, r, x, stiff, parts + 3 * p);
  }
  return kNodeOk;
}

template <class R>
MEDSPRING_HD inline int grid_split_finish(const NodeArrays<R>& N, const GridSplit& G, int r, R h, R vmax2,
                                          const R* loads, const R* x, const R* v, R* xo, R* vo,
                                          const R* parts) {
  const int k = G.lead[r];
  if (k < 0) return kNodeOk;
  const int p0 = G.part_begin[k];
  return split_node_advance(N, G.heavy_node[k], h, vmax2, loads, x, v, xo, vo, parts + 3 * p0,
                            G.part_begin[k + 1] - p0);
}

}  // namespace medspring::hd
