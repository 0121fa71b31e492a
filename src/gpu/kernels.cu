// The substep kernels. Grid kernel: one thread per table row gathers its node's return spring, load and
// springs (hd::node_substep, the same code the CPU-side test runs) and advances the node, one launch per
// substep; heavy nodes split into chunks gathered by the lanes of one warp and summed by its lead
// (hd::grid_split_gather / grid_split_finish). Block kernel: one block per model runs a frame's substeps
// with the model's state in shared memory (hd::split_phase1 / split_phase2: hd::node_substep per node,
// heavy nodes split). No atomics on forces; the stiffening max and the guard are reduced per block.
#include <climits>

#include "launch.hpp"

namespace medspring::gpu::detail {

namespace {

__device__ inline void max_bits(unsigned long long* target, double v) {
  // Non-negative doubles order like their bit patterns.
  atomicMax(target, static_cast<unsigned long long>(__double_as_longlong(v)));
}

// Model b's arrays: node arrays and spring parameters at their per-model strides (topology shared).
template <class R>
__device__ inline void model_arrays(const SubstepArgs<R>& A, int b, hd::NodeArrays<R>& N,
                                    hd::SpringTable<R>& T) {
  N = A.nodes;
  const long long ns = A.node_stride * b;
  N.x0 += 3 * ns;
  N.mass += ns;
  N.damping += ns;
  N.kr += ns;
  N.fixed += ns;
  N.load_slot += A.slot_stride * b;
  T = A.table;
  const long long es = A.entry_stride * b;
  T.L0 += es;
  T.k += es;
  T.kp += es;
  T.ik += es;
}

// Block-wide max of the threads' stiffening into *target (every thread of the block must call it).
__device__ inline void block_max_into(double s, double* warp_max, unsigned long long* target) {
  for (int o = 16; o > 0; o >>= 1) s = fmax(s, __shfl_xor_sync(0xffffffffu, s, o));
  const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
  if (lane == 0) warp_max[warp] = s;
  __syncthreads();
  if (warp == 0) {
    s = lane < static_cast<int>((blockDim.x + 31) >> 5) ? warp_max[lane] : 0.0;
    for (int o = 16; o > 0; o >>= 1) s = fmax(s, __shfl_xor_sync(0xffffffffu, s, o));
    if (lane == 0) max_bits(target, s);
  }
}

template <class R, bool Soft, bool Stiff, int U, bool Packed = false>
__global__ void substep_kernel(SubstepArgs<R> A) {
  if (A.scalars->fail_first < A.substep) return;  // an earlier substep failed: buffers left as they were
  // Block order (SubstepArgs::models_first): blockIdx.x the model and blockIdx.y the row block, so that
  // the blocks resident on a multiprocessor at once are the same rows of different models and share the
  // table entries they read in L1; or blockIdx.x the row block (one model, or the old order).
  const int b = A.models_first ? blockIdx.x : blockIdx.y;
  const int row_block = A.models_first ? blockIdx.y : blockIdx.x;
  const int row_blocks = A.models_first ? gridDim.y : gridDim.x;
  const int r = row_block * blockDim.x + threadIdx.x;  // table row
  const bool split = A.split.rows > 0;                 // the same for every thread of the launch
  const int rows = split ? A.split.rows : A.nodes.nodes;
  R stiff = R(1);
  int code = hd::kNodeOk;
  hd::NodeArrays<R> N;
  hd::SpringTable<R> T;
  model_arrays(A, b, N, T);
  const long long off = 3ll * A.nodes.nodes * b;
  R h = A.h;
  if (A.count_model) {  // each model its own substeps (uniform per block: blockIdx.y is the model)
    if (A.substep >= A.count_model[b]) {  // model b has taken its substeps: carry its state over
      for (int q = r; q < A.nodes.nodes; q += row_blocks * blockDim.x)
        for (int c = 0; c < 3; ++c) {
          A.xo[off + 3ll * q + c] = A.x[off + 3ll * q + c];
          A.vo[off + 3ll * q + c] = A.v[off + 3ll * q + c];
        }
      return;
    }
    h = A.h_model[b];
  }
  const R* loads = A.loads + 3ll * A.load_rows * b;
  if (split) {
    // Phase 1: whole rows advance their node, chunk rows write their sums; a split node's chunks are in
    // the lead's warp (blockDim is a multiple of 32), so the warp's barrier orders them before phase 2.
    R* parts = A.parts + A.parts_stride * b;
    if (r < rows)
      code = hd::grid_split_gather<Soft, Stiff, U, Packed>(N, T, A.split, r, h, A.vmax2, loads, A.x + off,
                                                           A.v + off, A.xo + off, A.vo + off, parts, stiff);
    __syncwarp();
    if (r < rows) {
      const int c = hd::grid_split_finish(N, A.split, r, h, A.vmax2, loads, A.x + off, A.v + off, A.xo + off,
                                          A.vo + off, parts);
      code = c > code ? c : code;
    }
  } else if (r < rows) {
    code = hd::node_substep<Soft, Stiff, U, Packed>(N, T, r, h, A.vmax2, loads, A.x + off, A.v + off,
                                                    A.xo + off, A.vo + off, stiff);
  }
  if (code != hd::kNodeOk && A.guard) {
    atomicMin(&A.scalars->fail_first, A.substep);
    atomicMax(&A.scalars->fail_code, code);
  }
  if constexpr (Stiff) {
    __shared__ double warp_max[32];
    block_max_into(static_cast<double>(stiff), warp_max, A.stiff_bits + b);
  }
}

// M models per thread (SubstepArgs::models_per_thread, hd::node_substep_models): the block's group of
// models g M .. g M + M - 1 (blockIdx.y, or x with models_first), each table entry loaded once for them.
// A model of the group past its substeps (count_model) carries its state over as in substep_kernel.
template <class R, bool Soft, bool Stiff, int M>
__global__ void substep_models_kernel(SubstepArgs<R> A) {
  if (A.scalars->fail_first < A.substep) return;
  const int group = A.models_first ? blockIdx.x : blockIdx.y;
  const int row_block = A.models_first ? blockIdx.y : blockIdx.x;
  const int row_blocks = A.models_first ? gridDim.y : gridDim.x;
  const int r = row_block * blockDim.x + threadIdx.x;
  const int b0 = group * M;
  const bool split = A.split.rows > 0;
  const int rows = split ? A.split.rows : A.nodes.nodes;
  const int n = A.nodes.nodes;
  // The group's models: `mask` those that run this substep (uniform over the block).
  unsigned mask = 0;
  R h[M], stiff[M];
#pragma unroll
  for (int m = 0; m < M; ++m) {
    stiff[m] = R(1);
    h[m] = A.h;
    const int b = b0 + m;
    if (b >= A.batch) continue;
    if (A.count_model) {
      if (A.substep >= A.count_model[b]) {  // model b has taken its substeps: carry its state over
        const long long off = 3ll * n * b;
        for (int q = r; q < n; q += row_blocks * blockDim.x)
          for (int c = 0; c < 3; ++c) {
            A.xo[off + 3ll * q + c] = A.x[off + 3ll * q + c];
            A.vo[off + 3ll * q + c] = A.v[off + 3ll * q + c];
          }
        continue;
      }
      h[m] = A.h_model[b];
    }
    mask |= 1u << m;
  }
  if (mask == 0) return;
  hd::NodeArrays<R> N;
  hd::SpringTable<R> T;
  model_arrays(A, b0, N, T);  // the table's parameters are shared (entry_stride 0)
  hd::ModelStrides S;
  S.state = 3ll * n;
  S.node = A.node_stride;
  S.slot = A.slot_stride;
  S.loads = 3ll * A.load_rows;
  S.parts = A.parts_stride;
  const long long off = 3ll * n * b0;
  const R* loads = A.loads + 3ll * A.load_rows * b0;
  int code = hd::kNodeOk;
  if (split) {
    R* parts = A.parts + A.parts_stride * b0;
    if (r < rows)
      code = hd::grid_split_gather_models<Soft, Stiff, M>(N, T, A.split, S, mask, r, h, A.vmax2, loads,
                                                          A.x + off, A.v + off, A.xo + off, A.vo + off, parts,
                                                          stiff);
    __syncwarp();
    if (r < rows) {
      const int c = hd::grid_split_finish_models<M>(N, A.split, S, mask, r, h, A.vmax2, loads, A.x + off,
                                                    A.v + off, A.xo + off, A.vo + off, parts);
      code = c > code ? c : code;
    }
  } else if (r < rows) {
    code = hd::node_substep_models<Soft, Stiff, M>(N, T, S, mask, r, h, A.vmax2, loads, A.x + off, A.v + off,
                                                   A.xo + off, A.vo + off, stiff);
  }
  if (code != hd::kNodeOk && A.guard) {
    atomicMin(&A.scalars->fail_first, A.substep);
    atomicMax(&A.scalars->fail_code, code);
  }
  if constexpr (Stiff) {
    __shared__ double warp_max[32];
#pragma unroll
    for (int m = 0; m < M; ++m) {
      if (!((mask >> m) & 1u)) continue;
      __syncthreads();  // warp 0 has read the previous model's warp maxima
      block_max_into(static_cast<double>(stiff[m]), warp_max, A.stiff_bits + b0 + m);
    }
  }
}

// One block per model: `count` substeps with the model's state in shared memory (launch.hpp).
template <class R, bool Soft>
__global__ void __launch_bounds__(kBlockThreads, 2) block_frame_kernel(BlockArgs<R> A) {
  extern __shared__ double shared_raw[];  // double: aligned for R = double and float
  __shared__ double warp_max[32];
  const int n = A.s.nodes.nodes, b = blockIdx.x, t = threadIdx.x, threads = blockDim.x;
  R* xa = reinterpret_cast<R*>(shared_raw);  // positions read by the substep
  R* xb = xa + 3 * n;                        // positions written by it (then swapped)
  R* vs = xb + 3 * n;
  R* parts = vs + 3 * n;  // partial forces of the split rows' chunks
  hd::NodeArrays<R> N;
  hd::SpringTable<R> T;
  model_arrays(A.s, b, N, T);
  const long long off = 3ll * n * b;
  for (int q = t; q < 3 * n; q += threads) {
    xa[q] = A.s.x[off + q];
    vs[q] = A.s.v[off + q];
  }
  __syncthreads();
  // Model b's own substeps (s.count_model) or the launch's; A.count caps them (the re-run after a failure).
  const int own = A.s.count_model ? A.s.count_model[b] : A.count;
  const int count = own < A.count ? own : A.count;
  const R h = A.s.count_model ? A.s.h_model[b] : A.s.h;
  for (int kk = 0; kk < count; ++kk) {
    const R* loads = A.s.loads + A.load_substep_stride * kk + 3ll * A.s.load_rows * b;
    const bool stiff_now = A.stiff_mode == 2 || (A.stiff_mode == 1 && kk == own - 1);
    R stiff = R(1);
    int code = stiff_now ? hd::split_phase1<Soft, true>(N, T, A.split, t, threads, h, A.s.vmax2, loads, xa,
                                                        vs, xb, parts, stiff)
                         : hd::split_phase1<Soft, false>(N, T, A.split, t, threads, h, A.s.vmax2, loads, xa,
                                                         vs, xb, parts, stiff);
    if (A.split.heavy > 0) {  // the split nodes, once their chunks' sums are in
      __syncthreads();
      const int c = hd::split_phase2(N, A.split, t, threads, h, A.s.vmax2, loads, xa, vs, xb, parts);
      code = c > code ? c : code;
    }
    if (stiff_now)
      block_max_into(static_cast<double>(stiff), warp_max,
                     A.s.stiff_bits + static_cast<long long>(kk) * A.s.batch + b);
    // One barrier: the substep's writes are visible to the next, and the block agrees on the guard.
    const bool guard = A.s.guard;
    if (__syncthreads_or(guard && code != hd::kNodeOk)) {
      const bool nonfinite = __syncthreads_or(code == hd::kNodeNonFinite);
      if (t == 0) {
        atomicMin(&A.s.scalars->fail_first, kk);
        atomicMax(&A.s.scalars->fail_code, nonfinite ? hd::kNodeNonFinite : hd::kNodeTooFast);
      }
      return;  // the host discards this launch's output and re-runs the substeps before kk
    }
    R* const swap = xa;
    xa = xb;
    xb = swap;
  }
  for (int q = t; q < 3 * n; q += threads) {
    A.s.xo[off + q] = xa[q];
    A.s.vo[off + q] = vs[q];
  }
}

template <class R, bool Soft, bool Stiff>
cudaError_t launch(const SubstepArgs<R>& A, int block, cudaStream_t stream) {
  const int rows = A.split.rows > 0 ? A.split.rows : A.nodes.nodes;
  const auto row_blocks = static_cast<unsigned>((rows + block - 1) / block);
  const int per_thread = A.models_per_thread == 4 || A.models_per_thread == 2 ? A.models_per_thread : 1;
  const auto models = static_cast<unsigned>((A.batch + per_thread - 1) / per_thread);  // model groups
  const dim3 grid = A.models_first ? dim3(models, row_blocks) : dim3(row_blocks, models);
  if (A.table
          .packed) {  // packed entries (Options::packed_table; the engine refuses it with models per thread)
    substep_kernel<R, Soft, Stiff, 1, true><<<grid, block, 0, stream>>>(A);
    return cudaGetLastError();
  }
  if (per_thread == 4) {  // several models per thread (Options::models_per_thread, validated by the engine)
    substep_models_kernel<R, Soft, Stiff, 4><<<grid, block, 0, stream>>>(A);
    return cudaGetLastError();
  }
  if (per_thread == 2) {
    substep_models_kernel<R, Soft, Stiff, 2><<<grid, block, 0, stream>>>(A);
    return cudaGetLastError();
  }
  // The gather batch (Options::gather_batch, validated by the engine: 1, 2 or 4).
  if (A.gather == 4)
    substep_kernel<R, Soft, Stiff, 4><<<grid, block, 0, stream>>>(A);
  else if (A.gather == 2)
    substep_kernel<R, Soft, Stiff, 2><<<grid, block, 0, stream>>>(A);
  else
    substep_kernel<R, Soft, Stiff, 1><<<grid, block, 0, stream>>>(A);
  return cudaGetLastError();
}

}  // namespace

template <class R>
cudaError_t launch_substep(const SubstepArgs<R>& A, int block, cudaStream_t stream) {
  if (A.soft)
    return A.stiff ? launch<R, true, true>(A, block, stream) : launch<R, true, false>(A, block, stream);
  return A.stiff ? launch<R, false, true>(A, block, stream) : launch<R, false, false>(A, block, stream);
}

template <class R>
cudaError_t prepare_block_frame(std::size_t bytes) {
  const int b = static_cast<int>(bytes);
  cudaError_t e =
      cudaFuncSetAttribute(block_frame_kernel<R, false>, cudaFuncAttributeMaxDynamicSharedMemorySize, b);
  if (e == cudaSuccess)
    e = cudaFuncSetAttribute(block_frame_kernel<R, true>, cudaFuncAttributeMaxDynamicSharedMemorySize, b);
  return e;
}

template <class R>
cudaError_t launch_block_frame(const BlockArgs<R>& A, cudaStream_t stream) {
  const std::size_t bytes = block_shared_bytes<R>(A.s.nodes.nodes, A.parts);
  const dim3 grid(static_cast<unsigned>(A.s.batch));
  if (A.s.soft)
    block_frame_kernel<R, true><<<grid, A.threads, bytes, stream>>>(A);
  else
    block_frame_kernel<R, false><<<grid, A.threads, bytes, stream>>>(A);
  return cudaGetLastError();
}

template cudaError_t launch_substep<double>(const SubstepArgs<double>&, int, cudaStream_t);
template cudaError_t launch_substep<float>(const SubstepArgs<float>&, int, cudaStream_t);
template cudaError_t prepare_block_frame<double>(std::size_t);
template cudaError_t prepare_block_frame<float>(std::size_t);
template cudaError_t launch_block_frame<double>(const BlockArgs<double>&, cudaStream_t);
template cudaError_t launch_block_frame<float>(const BlockArgs<float>&, cudaStream_t);

}  // namespace medspring::gpu::detail
