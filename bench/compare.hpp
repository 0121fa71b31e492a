// `medspring bench --compare` / `--scaling`: MedSpring, a plain reference loop and Bullet's btSoftBody
// timed side by side, in one process, on the same tube (docs/performance.md).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "cases.hpp"
#include "medspring/core/types.hpp"
#include "medspring/physics/model.hpp"

namespace medspring::bench {

/// The comparison tube: `rings` x `spokes` nodes spaced 2.5 mm along the axis and about 2.5 mm around
/// (radius max(3, 2.5 spokes / 2 pi) mm), one spring per mesh edge (Strain Duffing law, k 0.05 N/mm),
/// kidney node parameters (0.3 g, beta 0.5/ms, k_r 0.02 N/mm), both end rings anchored, 0.5 N held on
/// one node of the middle ring, frames of 0.5 ms.
struct TubeSize {
  Index rings = 40, spokes = 30;
  long nodes() const { return static_cast<long>(rings) * spokes; }
};

/// "tube_1.2k", "tube_1M", ...
std::string size_name(long nodes);
/// The comparison tube as a MedSpring model (also the GPU benchmark's, gpu_bench.cpp).
Model tube_model(const TubeSize& size);

/// The tube as plain arrays (what the plain loop and Bullet are built from).
struct TubeData {
  std::vector<double> x0;  // interleaved xyz (3N)
  std::vector<double> mass, damping, kr;
  std::vector<std::uint8_t> fixed;
  std::vector<Index> si, sj;
  std::vector<double> L0, k, kp;
  Index load_node = 0;
  double load[3] = {0, 0, -0.5};
  double dt = 0.5;
  long nodes() const { return static_cast<long>(mass.size()); }
  long springs() const { return static_cast<long>(si.size()); }
};

struct CompareResult {
  std::string name;      // e.g. "tube_10k"
  std::string engine;    // medspring | plain | bullet
  int threads = 1;       // threads asked for
  int threads_used = 1;  // threads the engine really ran (MedSpring runs small models on one)
  double substeps = 1;   // force passes per update
  long nodes = 0, springs = 0;
  Timing timing;
  double ns_per_spring = 0;   // median per update / (springs x substeps)
  double bytes_per_node = 0;  // the engine's model + state arrays / nodes
  std::string settings;       // what was run (Bullet: its configuration)
  double build_s = 0;         // seconds to build the engine's model from the tube
};

struct CompareOptions {
  std::vector<TubeSize> sizes;  // default: 1.2k, 10k, 100k, 1M
  std::vector<int> threads{1, 2};
  double budget_s = 2.0;  // per engine and size
  long samples = 2000;
  bool bullet = true;
  std::string order = "built";  // node order of the tube: built (ring by ring) | shuffled | rcm
};

/// True when the benchmark was built with Bullet (libbullet-dev).
bool bullet_available();

/// Runs every engine on every size; `on_result` is called as each result is ready.
std::vector<CompareResult> run_compare(const CompareOptions& options,
                                       const std::function<void(const CompareResult&)>& on_result);

/// Least-squares slope of log(median) against log(nodes) over the results of one engine (and thread
/// count); 0 with fewer than two sizes.
double fitted_exponent(const std::vector<CompareResult>& results, const std::string& engine, int threads);

}  // namespace medspring::bench
