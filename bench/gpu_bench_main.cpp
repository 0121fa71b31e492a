// medspring_gpu_bench: `medspring bench --gpu` for builds without the CLI (engine-only, GPU machines).
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "gpu_bench.hpp"

int main(int argc, char** argv) {
  try {
    const std::vector<std::string> args(argv + 1, argv + argc);
    return medspring::bench::run_gpu_bench(medspring::bench::parse_gpu_bench_args(args));
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
