// The fused substep kernel: one thread per node gathers its return spring, load and springs
// (hd::node_substep, the same code the CPU-side test runs) and advances the node. No atomics on forces;
// the stiffening max and the guard's flags are reduced per block.
#include <climits>

#include "launch.hpp"

namespace medspring::gpu::detail {

namespace {

__device__ inline void max_bits(unsigned long long* target, double v) {
  // Non-negative doubles order like their bit patterns.
  atomicMax(target, static_cast<unsigned long long>(__double_as_longlong(v)));
}

template <class R, bool Soft, bool Stiff>
__global__ void substep_kernel(SubstepArgs<R> A) {
  if (A.scalars->fail_first < A.substep) return;  // an earlier substep failed: buffers left as they were
  const int b = blockIdx.y;
  const int a = blockIdx.x * blockDim.x + threadIdx.x;
  R stiff = R(1);
  if (a < A.nodes.nodes) {
    hd::NodeArrays<R> N = A.nodes;
    const long long ns = A.node_stride * b;
    N.x0 += 3 * ns;
    N.mass += ns;
    N.damping += ns;
    N.kr += ns;
    N.fixed += ns;
    N.load_slot += ns;
    hd::SpringTable<R> T = A.table;
    const long long es = A.entry_stride * b;
    T.L0 += es;
    T.k += es;
    T.kp += es;
    T.ik += es;
    const long long off = 3ll * A.nodes.nodes * b;
    const int code = hd::node_substep<Soft, Stiff>(N, T, a, A.h, A.vmax2, A.loads + 3ll * A.load_rows * b,
                                                   A.x + off, A.v + off, A.xo + off, A.vo + off, stiff);
    if (code != hd::kNodeOk && A.guard) {
      atomicMin(&A.scalars->fail_first, A.substep);
      atomicMax(&A.scalars->fail_code, code);
    }
  }
  if constexpr (Stiff) {
    double s = static_cast<double>(stiff);
    for (int o = 16; o > 0; o >>= 1) s = fmax(s, __shfl_xor_sync(0xffffffffu, s, o));
    __shared__ double warp_max[32];
    const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
    if (lane == 0) warp_max[warp] = s;
    __syncthreads();
    if (warp == 0) {
      s = lane < static_cast<int>((blockDim.x + 31) >> 5) ? warp_max[lane] : 0.0;
      for (int o = 16; o > 0; o >>= 1) s = fmax(s, __shfl_xor_sync(0xffffffffu, s, o));
      if (lane == 0) max_bits(A.stiff_bits, s);
    }
  }
}

template <class R, bool Soft, bool Stiff>
cudaError_t launch(const SubstepArgs<R>& A, int block, cudaStream_t stream) {
  const dim3 grid(static_cast<unsigned>((A.nodes.nodes + block - 1) / block), static_cast<unsigned>(A.batch));
  substep_kernel<R, Soft, Stiff><<<grid, block, 0, stream>>>(A);
  return cudaGetLastError();
}

}  // namespace

template <class R>
cudaError_t launch_substep(const SubstepArgs<R>& A, int block, cudaStream_t stream) {
  if (A.soft)
    return A.stiff ? launch<R, true, true>(A, block, stream) : launch<R, true, false>(A, block, stream);
  return A.stiff ? launch<R, false, true>(A, block, stream) : launch<R, false, false>(A, block, stream);
}

template cudaError_t launch_substep<double>(const SubstepArgs<double>&, int, cudaStream_t);
template cudaError_t launch_substep<float>(const SubstepArgs<float>&, int, cudaStream_t);

}  // namespace medspring::gpu::detail
