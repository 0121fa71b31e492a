// `medspring bench --gpu` and `medspring_gpu_bench` (the engine-only build has no CLI): the tube on the
// GPU in fp64 and fp32, batch throughput, effective bandwidth against the card's measured copy
// bandwidth, the CPU engine and the same step in PyTorch in the same run (docs/gpu.md).
#pragma once

#include <string>
#include <vector>

namespace medspring::bench {

struct GpuBenchOptions {
  std::vector<long> sizes{1200, 120000, 1000000, 16000000};  // tube nodes (rings x spokes chosen per size)
  int batch = 2048;              // hybrid kidney phantoms in the batch case (0: skip)
  long cpu_max_nodes = 1000000;  // the CPU engine runs up to this size
  bool torch = true;             // the PyTorch step when `import torch` works and sees the GPU
  std::string out;               // folder for gpu_bench.json and gpu_bench.png ("" = none)
  int device = 0;
  std::string kidney;           // a hybrid kidney model package (.msm) for the batch case ("" = the phantom)
  bool compact = false;         // also time each tube with compact parameters (gpu::Options::compact_params)
  std::vector<int> gathers{1};  // gather batches (gpu::Options::gather_batch) timed with compact parameters
  // Models per thread (gpu::Options::models_per_thread, 2 or 4) of the extra kidney batch variants
  // "grid-m2", "grid-m4" (with --compact "grid-compact-m2", ...); empty: none.
  std::vector<int> models_per_thread;
  // Also time each tube and the kidney batch with the packed table (gpu::Options::packed_table): rows
  // fp64p, fp32p, grid-packed.
  bool packed = false;
};

/// Runs the benchmark and prints the table. Throws gpu::GpuError (no device, ...) or InvalidInput.
/// Returns 0. Without the CUDA backend in the build: prints why and returns 2 (no silent fallback).
int run_gpu_bench(const GpuBenchOptions& options);

/// Parses "--sizes 1200,120000 --batch 2048 --kidney FILE.msm --cpu-max 1000000 --no-torch --compact
/// --gather 1,2,4 --models-per-thread 2,4 --packed --out DIR --device 0"
/// (argv-style, the program name excluded). Throws InvalidInput naming the bad argument.
GpuBenchOptions parse_gpu_bench_args(const std::vector<std::string>& args);

}  // namespace medspring::bench
