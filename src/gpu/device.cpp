// The GPU path's device queries and errors: require_device, require_supported, the copy bandwidth probe
// (docs/gpu.md).
#include "device.hpp"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <vector>

#include "launch.hpp"
#include "medspring/core/check.hpp"
#include "medspring/gpu/engine.hpp"

namespace medspring::gpu {

namespace detail {

void check(cudaError_t e, const char* what) {
  if (e == cudaSuccess) return;
  cudaGetLastError();  // clear a sticky launch error for the next call
  if (e == cudaErrorMemoryAllocation)
    throw GpuError(cat("GPU: out of device memory while ", what,
                       "; use a smaller model or batch, --precision fp32 (half the bytes), or ",
                       kCpuAlternative));
  if (e == cudaErrorInsufficientDriver)
    throw GpuError(cat("GPU: the NVIDIA driver is older than the CUDA runtime this build uses (", what,
                       "); update the driver, or use ", kCpuAlternative));
  if (e == cudaErrorNoDevice)
    throw GpuError(cat("GPU: no CUDA device found (", what, "); use ", kCpuAlternative));
  throw GpuError(cat("GPU: ", what, " failed: ", cudaGetErrorName(e), " (", cudaGetErrorString(e), ")"));
}

}  // namespace detail

using detail::check;
using detail::DeviceArray;
using detail::kCpuAlternative;

Precision parse_precision(const std::string& text) {
  if (text == "fp64" || text == "double" || text == "float64") return Precision::Double;
  if (text == "fp32" || text == "float" || text == "float32") return Precision::Float;
  throw InvalidInput(cat("precision: unknown value '", text, "' (expected fp64 or fp32)"));
}

std::string to_string(Precision p) {
  return p == Precision::Double ? "fp64" : "fp32";
}

bool built() {
  return true;
}

DeviceInfo require_device(int index) {
  int driver = 0, runtime = 0;
  cudaDriverGetVersion(&driver);
  cudaRuntimeGetVersion(&runtime);
  if (driver == 0)
    throw GpuError(cat("GPU: no NVIDIA driver found (libcuda not loadable); use ", kCpuAlternative));
  if (driver < runtime)
    throw GpuError(cat("GPU: the NVIDIA driver supports CUDA ", driver / 1000, ".", (driver % 1000) / 10,
                       " but this build needs ", runtime / 1000, ".", (runtime % 1000) / 10,
                       "; update the driver, or use ", kCpuAlternative));
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e == cudaErrorNoDevice || (e == cudaSuccess && count == 0)) {
    cudaGetLastError();
    throw GpuError(cat("GPU: no CUDA device found; use ", kCpuAlternative));
  }
  check(e, "counting CUDA devices");
  if (index < 0 || index >= count)
    throw GpuError(cat("GPU: device ", index, " does not exist (", count, " device(s): 0..", count - 1, ")"));
  cudaDeviceProp prop{};
  check(cudaGetDeviceProperties(&prop, index), "reading the device properties");
  if (prop.major < 9)
    throw GpuError(cat("GPU: device ", index, " (", prop.name, ") has compute capability ", prop.major, ".",
                       prop.minor,
                       "; the kernels are built for 9.0 (Hopper: H100/H200) — rebuild with "
                       "-DCMAKE_CUDA_ARCHITECTURES=",
                       prop.major, prop.minor, ", or use ", kCpuAlternative));
  DeviceInfo d;
  d.index = index;
  d.name = prop.name;
  d.major = prop.major;
  d.minor = prop.minor;
  d.multiprocessors = prop.multiProcessorCount;
  d.memory_bytes = prop.totalGlobalMem;
  d.shared_per_block = prop.sharedMemPerBlockOptin;
  d.driver_version = driver;
  d.runtime_version = runtime;
  return d;
}

void require_supported(const std::string& kind, bool local_overlay, bool tools) {
  if (kind == "smrm" || kind == "tree" || kind == "vessel")
    throw GpuError(
        cat("GPU: model kind '", kind,
            "' (SMRM vessel: frames and medial reconstruction) is not ported to the GPU path; run it "
            "with ",
            kCpuAlternative));
  if (kind != "surface" && kind != "hybrid")
    throw GpuError(cat("GPU: model kind '", kind,
                       "' is not supported on the GPU path (surface and hybrid are); use ", kCpuAlternative));
  if (local_overlay)
    throw GpuError(
        cat("GPU: the local deformation overlay is not ported to the GPU path; use ", kCpuAlternative));
  if (tools)
    throw GpuError(cat("GPU: tools (contact) are not ported to the GPU path; use ", kCpuAlternative));
}

Options::Kernel kernel_for(const Options& options, int batch, Index nodes, const DeviceInfo& device) {
  // The block kernel's static shared memory (the stiffening reduction) beside the state.
  const std::size_t need =
      (options.precision == Precision::Double ? detail::block_shared_bytes<double>(nodes)
                                              : detail::block_shared_bytes<float>(nodes)) +
      32 * sizeof(double);
  const bool fits = need <= device.shared_per_block;
  if (options.kernel == Options::Kernel::Grid) return Options::Kernel::Grid;
  if (options.kernel == Options::Kernel::PerBlock) {
    if (!fits)
      throw GpuError(cat("GPU: one block per model needs ", need, " bytes of shared memory for a model of ",
                         nodes, " nodes (", to_string(options.precision), "); the device (", device.name,
                         ") allows ", device.shared_per_block, " per block: use the grid kernel (Auto)"));
    return Options::Kernel::PerBlock;
  }
  // Auto is the grid kernel. Measured on an H200 (docs/gpu.md, 2026-11-26), the real kidney (500 nodes):
  // 8,448 models, 404 µs per substep on the grid kernel and 857 µs on one block per model in fp64
  // (242 / 280 µs in fp32); one model, a 35.7 µs frame on the grid kernel and 59.0 µs on one block (fp32
  // 33.8 / 50.2 µs). One block per model stays available on request (Options::Kernel::PerBlock).
  (void)batch;
  return Options::Kernel::Grid;
}

double measured_copy_bandwidth(std::size_t bytes, int repeats, int device) {
  require_device(device);
  check(cudaSetDevice(device), "selecting the device");
  DeviceArray<unsigned char> a, b;
  a.allocate(bytes, "allocating the bandwidth probe");
  b.allocate(bytes, "allocating the bandwidth probe");
  check(cudaMemset(a.p, 1, bytes), "filling the bandwidth probe");
  cudaEvent_t e0, e1;
  check(cudaEventCreate(&e0), "creating events");
  check(cudaEventCreate(&e1), "creating events");
  std::vector<float> ms;
  for (int r = 0; r < repeats + 2; ++r) {
    cudaEventRecord(e0);
    cudaMemcpyAsync(b.p, a.p, bytes, cudaMemcpyDeviceToDevice);
    cudaEventRecord(e1);
    check(cudaEventSynchronize(e1), "timing a device copy");
    float t = 0;
    cudaEventElapsedTime(&t, e0, e1);
    if (r >= 2) ms.push_back(t);  // two warm-up copies
  }
  cudaEventDestroy(e0);
  cudaEventDestroy(e1);
  std::sort(ms.begin(), ms.end());
  const double med = ms[ms.size() / 2];
  return 2.0 * static_cast<double>(bytes) / (med * 1e-3) / 1e9;
}

// ------------------------------------------------------------------------------------------------

}  // namespace medspring::gpu
