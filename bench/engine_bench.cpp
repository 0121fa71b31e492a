// Google Benchmark front end: every case of cases.cpp, registered at start-up.
#include <benchmark/benchmark.h>

#include "cases.hpp"

namespace {

const bool registered = [] {
  for (const auto& c : medspring::bench::all_cases()) {
    benchmark::RegisterBenchmark(c.name.c_str(), [c](benchmark::State& st) {
      const auto update = c.setup();
      for (int i = 0; i < 50; ++i) update();  // warm-up
      for (auto _ : st) update();
      st.counters["nodes"] = static_cast<double>(c.nodes);
      if (c.springs > 0)
        st.counters["ns_per_spring"] =
            benchmark::Counter(static_cast<double>(c.springs),
                               benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
    })->Unit(benchmark::kMicrosecond);
  }
  return true;
}();

}  // namespace
