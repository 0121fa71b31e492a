// Host-side interface of the substep kernel (kernels.cu): plain structs and a launch function, so that
// engine.cpp (host compiler, Eigen) and kernels.cu (nvcc, no Eigen) share no heavy header.
#pragma once

#include <cuda_runtime_api.h>

#include <cstddef>

#include "medspring/physics/kernels.hpp"
#include "medspring/physics/kernels_models.hpp"
#include "medspring/physics/kernels_split.hpp"

namespace medspring::gpu::detail {

/// Per-frame scalars on the device (reset before each batch of substeps).
struct FrameScalars {
  int fail_first;  // first substep of the batch whose guard tripped (INT_MAX: none)
  int fail_code;   // hd::kNodeTooFast / kNodeNonFinite (max over the failing nodes)
};

/// One substep for a batch of models of the same topology. Model b's arrays start at
/// pointer + b * stride of their kind (strides 0 share one array).
template <class R>
struct SubstepArgs {
  hd::NodeArrays<R> nodes;   // model 0; node arrays of model b at + b * node_stride (x0: 3x), its load
                             // slots at + b * slot_stride
  hd::SpringTable<R> table;  // model 0; parameter arrays of model b at + b * entry_stride
  long long node_stride = 0, slot_stride = 0, entry_stride = 0;
  int batch = 1;
  const R* loads = nullptr;  // this substep's load rows: model b at + b * 3 * load_rows
  int load_rows = 0;
  const R* x = nullptr;  // (B x 3n) read
  const R* v = nullptr;
  R* xo = nullptr;  // (B x 3n) written
  R* vo = nullptr;
  R h = 0, vmax2 = 0;
  // Each model its own substeps, as its CPU run takes them: model b runs substep `substep` iff substep <
  // count_model[b], with step h_model[b]; past its count it carries its state over to the written
  // buffers (so every model's buffer parity stays the batch's). nullptr: every model runs, with h.
  const R* h_model = nullptr;
  const int* count_model = nullptr;
  int substep = 0;            // index within the batch of substeps
  bool soft = false;          // some spring is soft (clamped law)
  bool stiff = false;         // evaluate the stiffening into stiff_bits
  bool guard = true;          // flag |v| > v_max / non-finite into scalars
  int gather = 1;             // entries gathered at a time (hd::gather_spring_forces' U)
  bool models_first = false;  // grid x = model, y = row block (Options::batch_order)
  // Models per thread (Options::models_per_thread; 2 or 4, else 1): thread r of model group g takes row
  // r of models g M .. g M + M - 1 (hd::node_substep_models; the spring table shared: entry_stride 0).
  int models_per_thread = 1;
  unsigned long long* stiff_bits = nullptr;  // this substep's slots, model b at + b: double bits, atomicMax
  FrameScalars* scalars = nullptr;
  // The grid kernel's heavy rows split (hd::GridSplit, make_grid_split_table); split.rows == 0: one row
  // per node (RowOrder::HeavyLast). parts: the chunks' force sums, model b at + b * parts_stride.
  hd::GridSplit split;
  R* parts = nullptr;
  long long parts_stride = 0;
};

template <class R>
cudaError_t launch_substep(const SubstepArgs<R>& args, int block, cudaStream_t stream);

/// The one-block-per-model kernel (docs/gpu.md): block b runs `count` substeps of model b with its
/// positions (two buffers) and velocities in shared memory, reading s.x, s.v once and writing s.xo, s.vo
/// (distinct from s.x, s.v) once at the end. The table's rows are dealt to the block's threads (thread t:
/// rows t, t + threads, ...; RowOrder::Balanced). Guard: a model whose substep kk trips stops there and
/// records kk (fail_first, atomicMin); then no block's output may be used: the host re-runs the
/// substeps before the failure with the guard off (they give the same result, bit for bit).
template <class R>
struct BlockArgs {
  SubstepArgs<R> s;  // as the grid kernel; s.loads: substep 0's table; s.stiff_bits: slots of
                     // substep 0 (substep kk, model b at + kk * batch + b)
  long long load_substep_stride = 0;  // elements between consecutive substeps' load tables
  int count = 1;                      // substeps (with s.count_model: at most; model b runs its own count)
  int stiff_mode = 1;                 // stiffening of substep kk into its slot: 0 never, 1 the model's last
                                      // substep, 2 every one
  int threads = 256;                  // block size (<= kBlockThreads, a multiple of 32)
  hd::SplitRows split;                // the table's rows: whole nodes and chunks of heavy ones
  int parts = 0;                      // partial-force slots (split.part_begin[split.heavy])
};
inline constexpr int kBlockThreads = 256;

/// Shared memory of one block for a model of n nodes: two position buffers, the velocities, and the
/// partial forces of the split rows.
template <class R>
constexpr std::size_t block_shared_bytes(long long n, long long parts = 0) {
  return static_cast<std::size_t>(9 * n + 3 * parts) * sizeof(R);
}

/// Raises the kernels' dynamic shared memory limit to `bytes` (needed above 48 KiB; outside graph capture).
template <class R>
cudaError_t prepare_block_frame(std::size_t bytes);

template <class R>
cudaError_t launch_block_frame(const BlockArgs<R>& args, cudaStream_t stream);

}  // namespace medspring::gpu::detail
