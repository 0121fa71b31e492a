// Benchmark cases shared by the Google Benchmark suite and `medspring bench` (one definition each).
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace medspring::bench {

/// One timed operation. setup() builds the model and state (untimed) and returns the update closure.
struct BenchCase {
  std::string name;   // e.g. "tube_1200_explicit_nonlinear"
  std::string group;  // "core", "kidney", "smrm", "local", "scaling"
  long nodes = 0;     // physics + surface nodes updated per call
  long springs = 0;   // springs evaluated per call (0 if not applicable)
  std::function<std::function<void()>()> setup;
};

struct CaseOptions {
  bool large = true;  // include the 1M-node tube (about 1 s to build, 100 MB)
};

/// All engine cases (core, scaling and the model kinds that are built in).
std::vector<BenchCase> all_cases(const CaseOptions& options = {});

struct Timing {
  double median_us = 0, p99_us = 0, mean_us = 0, min_us = 0;
  long samples = 0;
};

/// Runs `warmup` untimed updates, then times `samples` updates one by one (steady clock).
/// Large cases are timed with fewer samples so that one case takes about `budget_s` seconds at most.
Timing time_case(const BenchCase& c, long warmup = 200, long samples = 2000, double budget_s = 2.0);

}  // namespace medspring::bench
