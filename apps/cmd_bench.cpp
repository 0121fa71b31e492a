#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cases.hpp"
#include "commands.hpp"
#include "compare.hpp"

namespace medspring::cli {

// Real-anatomy cases built by the builders layer (cmd_build.cpp); empty without it or without the data.
std::vector<bench::BenchCase> builder_bench_cases(const std::string& filter);
// The volumetric kidney (cmd_bench_volumetric.cpp); empty without the fem layer (TetGen).
std::vector<bench::BenchCase> volumetric_bench_cases(const std::string& filter);

// bench_compare.cpp: --compare and --scaling.
int cmd_bench_compare(const Args& args);
// cmd_bench_gpu.cpp: --gpu.
int cmd_bench_gpu(const Args& args);

int cmd_bench(const Args& args) {
  if (args.flag("gpu")) return cmd_bench_gpu(args);
  if (args.flag("compare") || args.flag("scaling")) return cmd_bench_compare(args);
  args.require_known({"json", "quick", "filter", "samples"});
  const bool quick = args.flag("quick");
  const std::string filter = args.get_or("filter", "");
  const long samples = args.integer("samples", quick ? 200 : 2000);
  const bool json = args.flag("json");
  nlohmann::json results = nlohmann::json::array();
  if (!json)
    std::printf("%-50s %10s %10s %10s %8s %9s %8s\n", "case", "median_us", "p99_us", "mean_us", "nodes",
                "springs", "ns/spring");
  std::vector<bench::BenchCase> cases = bench::all_cases({.large = !quick});
  for (auto& c : builder_bench_cases(filter)) cases.push_back(std::move(c));
  for (auto& c : volumetric_bench_cases(filter)) cases.push_back(std::move(c));
  for (const auto& c : cases) {
    if (!filter.empty() && c.name.find(filter) == std::string::npos) continue;
    const bench::Timing t = bench::time_case(c, quick ? 50 : 200, samples, quick ? 0.5 : 2.0);
    const double ns_spring = c.springs > 0 ? 1000.0 * t.median_us / static_cast<double>(c.springs) : 0.0;
    if (json) {
      results.push_back({{"name", c.name},
                         {"group", c.group},
                         {"median_us", t.median_us},
                         {"p99_us", t.p99_us},
                         {"mean_us", t.mean_us},
                         {"min_us", t.min_us},
                         {"samples", t.samples},
                         {"nodes", c.nodes},
                         {"springs", c.springs},
                         {"ns_per_spring", ns_spring}});
    } else {
      std::printf("%-50s %10.2f %10.2f %10.2f %8ld %9ld %8.2f\n", c.name.c_str(), t.median_us, t.p99_us,
                  t.mean_us, c.nodes, c.springs, ns_spring);
      std::fflush(stdout);
    }
  }
  if (json) std::cout << nlohmann::json{{"results", results}}.dump(2) << "\n";
  return 0;
}

}  // namespace medspring::cli
