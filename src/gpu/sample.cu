// The trace reduction (sample.hpp): blocks (x: chunks of the surface, y: the model) take the largest
// surface displacement of their nodes (hd::surface_displacement, the code the CPU-side test runs), reduce
// it over the warp and the block, and combine it into the model's value with one atomicMax on the bit
// pattern (the max is exact: the order does not change it); the first block of each model writes its
// traced points' displacements (hd::traced_displacement).
#include "sample.hpp"

namespace medspring::gpu::detail {

namespace {

template <class R>
__global__ void __launch_bounds__(kTraceThreads)
    trace_kernel(hd::TraceTable T, const R* x, long long model_stride, const double* origin, double* out) {
  const int b = blockIdx.y;
  const R* xb = x + model_stride * b;
  const double* o = origin + 3ll * b;
  double* ob = out + static_cast<long long>(T.width()) * b;
  double m = 0.0;
  for (int s = blockIdx.x * blockDim.x + threadIdx.x; s < T.surface; s += gridDim.x * blockDim.x)
    m = hd::trace_max(m, hd::surface_displacement(T, b, xb, o, s));
  for (int off = 16; off > 0; off >>= 1) m = hd::trace_max(m, __shfl_xor_sync(0xffffffffu, m, off));
  __shared__ double warp_max[kTraceThreads / 32];
  const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
  if (lane == 0) warp_max[warp] = m;
  __syncthreads();
  if (threadIdx.x == 0) {
    for (int w = 1; w < static_cast<int>(blockDim.x >> 5); ++w) m = hd::trace_max(m, warp_max[w]);
    atomicMax(reinterpret_cast<unsigned long long*>(ob),
              static_cast<unsigned long long>(__double_as_longlong(m)));
  }
  if (blockIdx.x == 0)
    for (int p = threadIdx.x; p < T.points; p += blockDim.x)
      ob[1 + p] = hd::traced_displacement(T, b, xb, o, p);
}

}  // namespace

template <class R>
cudaError_t launch_trace_sample(const hd::TraceTable& T, const R* x, long long model_stride,
                                const double* origin, double* out, cudaStream_t stream) {
  if (T.batch <= 0) return cudaSuccess;
  // About 8 surface nodes per thread, at most 256 blocks per model.
  const long long per_block = 8ll * kTraceThreads;
  const long long chunks = (static_cast<long long>(T.surface) + per_block - 1) / per_block;
  const dim3 grid(static_cast<unsigned>(chunks < 1 ? 1 : (chunks > 256 ? 256 : chunks)),
                  static_cast<unsigned>(T.batch));
  trace_kernel<R><<<grid, kTraceThreads, 0, stream>>>(T, x, model_stride, origin, out);
  return cudaGetLastError();
}

template cudaError_t launch_trace_sample<double>(const hd::TraceTable&, const double*, long long,
                                                 const double*, double*, cudaStream_t);
template cudaError_t launch_trace_sample<float>(const hd::TraceTable&, const float*, long long, const double*,
                                                double*, cudaStream_t);

}  // namespace medspring::gpu::detail
