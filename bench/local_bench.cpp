// Local deformation (eq. 6, ALGORITHMS.md §6): cost of one update with the cached factor
// (cache_local = true) and with selection + assembly + factorisation + solve on every call
// (cache_local = false, the paper's path), on the vessel's 5 x 5 window and the kidney's 25-node BFS
// patch. Targets (this machine): cached isotropic solve <= 2 us, refactoring path <= 15 us. The distributed
// load's overlay (DistributedOverlay, the volumetric kind's run-time form of the calibrated disk overlay):
// the same loaded set (solve + overlay) and a loaded set that changes every update (select + factor + solve
// + overlay), on disks of 4 to 30 mm around the kidney phantom's node 223.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/local/deformer.hpp"
#include "medspring/local/distributed_overlay.hpp"
#include "medspring/local/overlay.hpp"
#include "medspring/local/patch.hpp"
#include "medspring/local/solver.hpp"

namespace {

using namespace medspring;

constexpr Index kRings = 40, kSpokes = 30;
constexpr Index kVesselContact = 20 * kSpokes + 7;
constexpr Index kKidneyContact = 223;

// Varies the force a little between iterations so the work cannot be hoisted.
Vec3 force(std::int64_t t) {
  return {0.0, 0.01 * static_cast<double>(t & 7), -0.05};
}

// Cached isotropic solve on the 5 x 5 window: U_a = g_a F.
void BM_LocalCachedSolve_Window5x5(benchmark::State& state) {
  LocalSolver solver;
  solver.precompute(structured_window_patch(kRings, kSpokes, kVesselContact));
  MatX3 U(25, 3);
  std::int64_t t = 0;
  for (auto _ : state) {
    solver.solve(force(t++), U);
    benchmark::DoNotOptimize(U.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_LocalCachedSolve_Window5x5);

// Cached solve plus the overlay onto the 1200-node vessel surface (one full local-deformation update).
void BM_LocalCachedSolveOverlay_Window5x5(benchmark::State& state) {
  const SurfaceMesh vessel = tube(kRings, kSpokes);
  LocalDeformer local = LocalDeformer::tube(kRings, kSpokes);
  MatX3 U, surface = vessel.V;
  std::int64_t t = 0;
  for (auto _ : state) {
    local.compute(kVesselContact, force(t++), U);
    apply_local_overlay(local.patch(), U, surface);
    benchmark::DoNotOptimize(surface.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_LocalCachedSolveOverlay_Window5x5);

// cache_local = false: select the window, assemble, factor and solve on every call.
void run_uncached_tube(benchmark::State& state, LocalStiffness mode) {
  LocalDeformationSettings s;
  s.cache_local = false;
  s.solver.stiffness = mode;
  LocalDeformer local = LocalDeformer::tube(kRings, kSpokes, s, tube(kRings, kSpokes).V);
  MatX3 U;
  std::int64_t t = 0;
  for (auto _ : state) {
    local.compute(kVesselContact, force(t++), U);
    benchmark::DoNotOptimize(U.data());
    benchmark::ClobberMemory();
  }
}
void BM_LocalRefactor_Window5x5(benchmark::State& state) {
  run_uncached_tube(state, LocalStiffness::Isotropic);
}
BENCHMARK(BM_LocalRefactor_Window5x5);
void BM_LocalRefactor_Window5x5_Linearized(benchmark::State& state) {
  run_uncached_tube(state, LocalStiffness::Linearized);
}
BENCHMARK(BM_LocalRefactor_Window5x5_Linearized);
void BM_LocalRefactor_Window5x5_PaperLiteral(benchmark::State& state) {
  run_uncached_tube(state, LocalStiffness::PaperLiteral);
}
BENCHMARK(BM_LocalRefactor_Window5x5_PaperLiteral);

// Cached solve in the dense 3 n_f system of the Linearized mode (factor reused, one solve per update).
void BM_LocalCachedSolve_Window5x5_Linearized(benchmark::State& state) {
  LocalSolver solver;
  solver.precompute(structured_window_patch(kRings, kSpokes, kVesselContact), tube(kRings, kSpokes).V,
                    {.stiffness = LocalStiffness::Linearized});
  MatX3 U(25, 3);
  std::int64_t t = 0;
  for (auto _ : state) {
    solver.solve(force(t++), U);
    benchmark::DoNotOptimize(U.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_LocalCachedSolve_Window5x5_Linearized);

// Kidney phantom (458 nodes), 25-node BFS patch.
void run_kidney(benchmark::State& state, bool cache_local) {
  const SurfaceMesh kidney = kidney_phantom();
  LocalDeformationSettings s;
  s.cache_local = cache_local;
  LocalDeformer local =
      LocalDeformer::mesh(vertex_adjacency(kidney.num_vertices(), unique_edges(kidney.F)), kidney.V, s);
  MatX3 U;
  std::int64_t t = 0;
  for (auto _ : state) {
    local.compute(kKidneyContact, force(t++), U);
    benchmark::DoNotOptimize(U.data());
    benchmark::ClobberMemory();
  }
}
void BM_LocalCachedSolve_KidneyBfs25(benchmark::State& state) {
  run_kidney(state, true);
}
BENCHMARK(BM_LocalCachedSolve_KidneyBfs25);
void BM_LocalRefactor_KidneyBfs25(benchmark::State& state) {
  run_kidney(state, false);
}
BENCHMARK(BM_LocalRefactor_KidneyBfs25);

// The loaded nodes of a disk of radius r (mm) around node c, with a force per node summing to 0.5 N.
struct Disk {
  std::vector<Index> nodes;
  MatX3 F;
};
Disk disk(const SurfaceMesh& m, Index c, double r) {
  Disk d;
  d.F = MatX3::Zero(m.num_vertices(), 3);
  for (Index i = 0; i < m.num_vertices(); ++i)
    if ((m.V.row(i) - m.V.row(c)).norm() < r) d.nodes.push_back(i);
  for (Index i : d.nodes) d.F.row(i) << 0.0, 0.0, -0.5 / static_cast<double>(d.nodes.size());
  return d;
}

// changing = false: one loaded set (the factor reused: solve + overlay per update); true: two sets of the
// same radius around neighbouring nodes taking turns, so every update selects and factors its patch.
void run_distributed(benchmark::State& state, bool changing) {
  const SurfaceMesh kidney = kidney_phantom();
  const double r = static_cast<double>(state.range(0));
  const Disk a = disk(kidney, kKidneyContact, r), b = disk(kidney, kKidneyContact + 1, r);
  DistributedOverlay d(vertex_adjacency(kidney.num_vertices(), unique_edges(kidney.F)), 0.05);
  d.reserve(std::max(d.patch_size_of(a.nodes), d.patch_size_of(b.nodes)));
  MatX3 surface = kidney.V;
  std::int64_t t = 0;
  for (auto _ : state) {
    const Disk& s = changing && (t++ & 1) ? b : a;
    d.prepare(s.nodes);
    d.solve(s.F);
    const auto U = d.displacement();
    for (Index p = 0; p < d.size(); ++p) surface.row(d.nodes()[p]) += U.row(p);
    benchmark::DoNotOptimize(surface.data());
    benchmark::ClobberMemory();
  }
  d.prepare(a.nodes);
  state.counters["loaded"] = static_cast<double>(a.nodes.size());
  state.counters["patch"] = static_cast<double>(d.size());
  state.counters["free"] = static_cast<double>(d.num_free());
}
void BM_LocalDistributed_SameLoadedSet(benchmark::State& state) {
  run_distributed(state, false);
}
BENCHMARK(BM_LocalDistributed_SameLoadedSet)->Arg(4)->Arg(8)->Arg(12)->Arg(20)->Arg(30);
void BM_LocalDistributed_NewLoadedSet(benchmark::State& state) {
  run_distributed(state, true);
}
BENCHMARK(BM_LocalDistributed_NewLoadedSet)->Arg(4)->Arg(8)->Arg(12)->Arg(20)->Arg(30);

}  // namespace
