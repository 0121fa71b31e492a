// `medspring bench --gpu` (bench/gpu_bench.cpp, docs/gpu.md).
#include "commands.hpp"
#include "gpu_bench.hpp"

namespace medspring::cli {

int cmd_bench_gpu(const Args& args) {
  args.require_known({"gpu", "sizes", "batch", "kidney", "cpu-max", "no-torch", "compact", "gather",
                      "models-per-thread", "packed", "out", "device"});
  std::vector<std::string> a;
  for (const char* name :
       {"sizes", "batch", "kidney", "cpu-max", "gather", "models-per-thread", "out", "device"})
    if (const auto v = args.get(name)) {
      a.push_back(std::string("--") + name);
      a.push_back(*v);
    }
  if (args.flag("no-torch")) a.emplace_back("--no-torch");
  if (args.flag("compact")) a.emplace_back("--compact");
  if (args.flag("packed")) a.emplace_back("--packed");
  return bench::run_gpu_bench(bench::parse_gpu_bench_args(a));
}

}  // namespace medspring::cli
