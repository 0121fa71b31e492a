// Device memory and CUDA error handling shared by the GPU engine's files (private to src/gpu).
#pragma once

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace medspring::gpu::detail {

inline constexpr const char* kCpuAlternative = "the CPU engine (leave out --gpu / --device cuda)";

/// Throws GpuError naming `what` for a failed CUDA call (out of memory, driver, no device: with the CPU
/// alternative).
void check(cudaError_t e, const char* what);

template <class T>
struct DeviceArray {
  T* p = nullptr;
  std::size_t n = 0;
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() {
    if (p) cudaFree(p);
  }
  void allocate(std::size_t count, const char* what) {
    if (p) cudaFree(p);
    p = nullptr;
    n = count;
    check(cudaMalloc(reinterpret_cast<void**>(&p), std::max<std::size_t>(count, 1) * sizeof(T)), what);
  }
  void upload(const T* h, std::size_t count, std::size_t offset, const char* what) {
    check(cudaMemcpy(p + offset, h, count * sizeof(T), cudaMemcpyHostToDevice), what);
  }
  /// Allocates h.size() elements and copies h into them.
  void assign(const std::vector<T>& h, const char* allocating, const char* uploading) {
    allocate(h.size(), allocating);
    upload(h.data(), h.size(), 0, uploading);
  }
};

template <class T>
struct PinnedArray {
  T* p = nullptr;
  std::size_t n = 0;
  PinnedArray() = default;
  PinnedArray(const PinnedArray&) = delete;
  PinnedArray& operator=(const PinnedArray&) = delete;
  ~PinnedArray() {
    if (p) cudaFreeHost(p);
  }
  void allocate(std::size_t count, const char* what) {
    if (p) cudaFreeHost(p);
    p = nullptr;
    n = count;
    check(cudaMallocHost(reinterpret_cast<void**>(&p), std::max<std::size_t>(count, 1) * sizeof(T)), what);
  }
};

}  // namespace medspring::gpu::detail
