// Host-side interface of the substep kernel (kernels.cu): plain structs and a launch function, so that
// engine.cpp (host compiler, Eigen) and kernels.cu (nvcc, no Eigen) share no heavy header.
#pragma once

#include <cuda_runtime_api.h>

#include "medspring/physics/kernels.hpp"

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
  hd::NodeArrays<R> nodes;   // model 0; node arrays of model b at + b * node_stride (x0: 3x)
  hd::SpringTable<R> table;  // model 0; parameter arrays of model b at + b * entry_stride
  long long node_stride = 0, entry_stride = 0;
  int batch = 1;
  const R* loads = nullptr;  // this substep's load rows: model b at + b * 3 * load_rows
  int load_rows = 0;
  const R* x = nullptr;  // (B x 3n) read
  const R* v = nullptr;
  R* xo = nullptr;  // (B x 3n) written
  R* vo = nullptr;
  R h = 0, vmax2 = 0;
  int substep = 0;                           // index within the batch of substeps
  bool soft = false;                         // some spring is soft (clamped law)
  bool stiff = false;                        // evaluate the stiffening into stiff_bits
  bool guard = true;                         // flag |v| > v_max / non-finite into scalars
  unsigned long long* stiff_bits = nullptr;  // double bit pattern, atomicMax (values >= 0)
  FrameScalars* scalars = nullptr;
};

template <class R>
cudaError_t launch_substep(const SubstepArgs<R>& args, int block, cudaStream_t stream);

}  // namespace medspring::gpu::detail
