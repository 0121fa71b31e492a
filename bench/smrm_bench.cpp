// SMRM vessel update (ALGORITHMS.md §7.3, D-18): one chain step (1 substep of 0.5 ms, strong force
// held) + frames + reconstruction of the 1200 surface nodes + vertex normals; and its parts.
#include <benchmark/benchmark.h>

#include "medspring/models/smrm_vessel.hpp"
#include "medspring/physics/integrators.hpp"

namespace {

using namespace medspring;

// The paper's vessel (straight-x phantom, 40 atoms x 30 spokes) with the strong force (0.5 N) held on
// atom 20 and 200 warm-up updates, so that the cubic terms are active.
struct SmrmBenchCase {
  SmrmVessel vessel;
  State state;
  StepSettings step_settings{.dt = 0.5};
  SmrmVessel::Workspace ws;
  MatX3 S, N;

  explicit SmrmBenchCase(bool nonlinear)
      : vessel(smrm_phantom(VesselPath::StraightX, CrossSectionShape::Circular, settings(nonlinear))),
        state(make_state(vessel.model())),
        ws(vessel.make_workspace()),
        S(vessel.rest_surface()),
        N(S.rows(), 3) {
    vessel.transfer_force(20 * 30 + 15, 0.5 * Vec3::UnitY(), state.f_ext);
    for (int i = 0; i < 200; ++i) update();
  }
  static SmrmSettings settings(bool nonlinear) {
    SmrmSettings s;
    s.chain.nonlinear = nonlinear;
    return s;
  }
  void update() {
    step(vessel.model(), state, step_settings);
    vessel.map_to_surface(state.x, ws, S);
    vessel.surface_normals(S, ws, N);
  }
};

void BM_SmrmUpdate(benchmark::State& st, bool nonlinear) {
  SmrmBenchCase c(nonlinear);
  for (auto _ : st) {
    c.update();
    benchmark::DoNotOptimize(c.N.data());
  }
  st.counters["surface_nodes"] = static_cast<double>(c.S.rows());
}
BENCHMARK_CAPTURE(BM_SmrmUpdate, linear, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_SmrmUpdate, nonlinear, true)->Unit(benchmark::kMicrosecond);

void BM_SmrmChainStep(benchmark::State& st) {
  SmrmBenchCase c(true);
  for (auto _ : st) {
    step(c.vessel.model(), c.state, c.step_settings);
    benchmark::DoNotOptimize(c.state.x.data());
  }
}
BENCHMARK(BM_SmrmChainStep)->Unit(benchmark::kMicrosecond);

void BM_SmrmFrames(benchmark::State& st) {
  SmrmBenchCase c(true);
  for (auto _ : st) {
    benchmark::DoNotOptimize(compute_frames(c.state.x, c.vessel.frame_reference(), c.ws.frames));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_SmrmFrames)->Unit(benchmark::kMicrosecond);

void BM_SmrmReconstruct(benchmark::State& st) {
  SmrmBenchCase c(true);
  for (auto _ : st) {
    reconstruct(c.vessel.binding(), c.state.x, c.ws.frames, c.ws.scratch, c.S);
    benchmark::DoNotOptimize(c.S.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_SmrmReconstruct)->Unit(benchmark::kMicrosecond);

void BM_SmrmNormals(benchmark::State& st) {
  SmrmBenchCase c(true);
  for (auto _ : st) {
    c.vessel.surface_normals(c.S, c.ws, c.N);
    benchmark::DoNotOptimize(c.N.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_SmrmNormals)->Unit(benchmark::kMicrosecond);

}  // namespace
