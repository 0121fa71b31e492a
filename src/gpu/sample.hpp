// Host-side interface of the trace reduction kernel (sample.cu, docs/gpu.md "Study runs on the GPU"):
// per model the frame's trace values of hd::trace_sample (physics/trace_kernels.hpp) from the device
// positions, so that a scene batch reads B x (1 + points) numbers per frame instead of every position.
#pragma once

#include <cuda_runtime_api.h>

#include "device.hpp"
#include "medspring/physics/trace_kernels.hpp"

namespace medspring::gpu::detail {

/// The reduction's device arrays (the table of Engine::set_trace_probes), its output and its readback.
struct TraceBuffers {
  hd::TraceTable table;  // device pointers into the arrays below
  DeviceArray<int> surface_dof, point_dof;
  DeviceArray<double> surface_rest, point_rest, origin, out;  // origin: 3 per model, as Backend::origin
  PinnedArray<double> host;                                   // B x table.width()
  cudaEvent_t done = nullptr;
  bool requested = false;
  TraceBuffers() = default;
  TraceBuffers(const TraceBuffers&) = delete;
  TraceBuffers& operator=(const TraceBuffers&) = delete;
  ~TraceBuffers() {
    if (done) cudaEventDestroy(done);
  }
};

inline constexpr int kTraceThreads = 128;

/// Model b's values (table.width() doubles at out + b * width) from its positions at x + b * model_stride
/// (stored relative to origin + 3 b). `out` must be zero (the surface max is combined with atomicMax on
/// the bit pattern of non-negative doubles, in which a NaN is larger than any number).
template <class R>
cudaError_t launch_trace_sample(const hd::TraceTable& table, const R* x, long long model_stride,
                                const double* origin, double* out, cudaStream_t stream);

}  // namespace medspring::gpu::detail
