// SMRM vessel tree update (issue 17, docs/vessels.md): the VMR 0159 tree (4 polylines sharing their start
// merged into 7 branches, 3 junctions), 1 thread, strong force (0.5 N) held on a leaf.
//   BM_SmrmTreeUpdate        one 0.5 ms frame as Simulation::update runs it: chain step (with its bending
//                            substeps) + frames and reconstruction of every branch; normals are computed
//                            when read (Simulation::normals), not per frame
//   BM_SmrmTreeUpdateNormals the same + the vertex normals of every branch every frame (the earlier
//                            definition of the update)
//   BM_SmrmTreeNormals       the normal pass alone (what a read costs)
// and the same for the watertight surface (--blend). Needs the data file (skipped with a message without
// it) and the io layer.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

#include "medspring/models/smrm_tree.hpp"
#include "medspring/physics/integrators.hpp"
#ifdef MEDSPRING_BENCH_HAVE_IO
#include "medspring/io/centerline_io.hpp"
#include "medspring/io/data_dir.hpp"
#endif
#ifdef MEDSPRING_BENCH_HAVE_BUILDERS
#include "medspring/builders/vessel_build.hpp"
#include "medspring/medial/reconstruction.hpp"
#endif

namespace {

using namespace medspring;

#ifdef MEDSPRING_BENCH_HAVE_IO
std::unique_ptr<SmrmTree> vmr_tree() {
  const std::filesystem::path file = data_dir() / "vmr-0159-aorta-centerline.vtp";
  if (!std::filesystem::exists(file)) return nullptr;
  return std::make_unique<SmrmTree>(merge_centerlines(read_centerlines(file, LengthUnit::Centimetre)));
}

void BM_SmrmTreeBuild(benchmark::State& st) {
  const std::filesystem::path file = data_dir() / "vmr-0159-aorta-centerline.vtp";
  if (!std::filesystem::exists(file)) {
    st.SkipWithError("vmr-0159-aorta-centerline.vtp not found (MEDSPRING_DATA)");
    return;
  }
  for (auto _ : st) {
    SmrmTree t(merge_centerlines(read_centerlines(file, LengthUnit::Centimetre)));
    benchmark::DoNotOptimize(t.rest_surface().data());
  }
}
BENCHMARK(BM_SmrmTreeBuild)->Unit(benchmark::kMillisecond);

// mode 0: step + surface; 1: + normals every frame; 2: normals only (of the loaded, deformed surface)
void tree_update(benchmark::State& st, int mode) {
  const auto tree = vmr_tree();
  if (!tree) {
    st.SkipWithError("vmr-0159-aorta-centerline.vtp not found (MEDSPRING_DATA)");
    return;
  }
  State s = make_state(tree->model());
  const Index leaf = tree->num_branches() - 1;
  const Index a = tree->branch_atoms(leaf)[tree->branch_atoms(leaf).size() / 2];
  s.f_ext.row(a) << 0.5, 0.0, 0.0;
  const StepSettings ss{.dt = 0.5};
  SmrmTree::Workspace ws = tree->make_workspace();
  MatX3 S = tree->rest_surface();
  std::vector<MatX3> N(static_cast<std::size_t>(tree->num_branches()));
  double frames = 0;
  auto normals = [&] {
    for (Index b = 0; b < tree->num_branches(); ++b) {
      const std::size_t q = static_cast<std::size_t>(b);
      const Index n0 = tree->node_begin(b), n = tree->branch_vessel(b).num_surface_nodes();
      ws.surface[q] = S.middleRows(n0, n);  // the branch's rows (a tree surface is one matrix)
      tree->branch_vessel(b).surface_normals(ws.surface[q], ws.vessel[q], N[q]);
    }
  };
  auto update = [&] {
    frames += 1;
    step(tree->model(), s, ss);
    tree->map_to_surface(s.x, ws, S);
    if (mode == 1) normals();
  };
  for (int i = 0; i < 200; ++i) update();
  for (auto _ : st) {
    if (mode == 2)
      normals();
    else
      update();
    benchmark::DoNotOptimize(S.data());
    benchmark::DoNotOptimize(N[0].data());
  }
  st.counters["atoms"] = static_cast<double>(tree->num_atoms());
  st.counters["surface_nodes"] = static_cast<double>(S.rows());
  st.counters["substeps_per_frame"] = static_cast<double>(s.substeps) / frames;
}
void BM_SmrmTreeUpdate(benchmark::State& st) {
  tree_update(st, 0);
}
void BM_SmrmTreeUpdateNormals(benchmark::State& st) {
  tree_update(st, 1);
}
void BM_SmrmTreeNormals(benchmark::State& st) {
  tree_update(st, 2);
}
BENCHMARK(BM_SmrmTreeUpdate)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SmrmTreeUpdateNormals)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SmrmTreeNormals)->Unit(benchmark::kMicrosecond);

#ifdef MEDSPRING_BENCH_HAVE_BUILDERS
// The same update with the watertight junction surface (union of the closed path tubes, --blend): every
// node rebuilt from its two bracket atoms' frames, and area-weighted normals of the whole mesh.
// mode as tree_update
void blended_update(benchmark::State& st, int mode) {
  const std::filesystem::path file = data_dir() / "vmr-0159-aorta-centerline.vtp";
  if (!std::filesystem::exists(file)) {
    st.SkipWithError("vmr-0159-aorta-centerline.vtp not found (MEDSPRING_DATA)");
    return;
  }
  VesselBuildSettings vs;
  vs.centerline = file;
  vs.centerline_unit = LengthUnit::Centimetre;
  vs.all_branches = true;
  vs.blend = true;
  const VesselBuild v = build_vessel(vs);
  const SmrmTree& tree = *v.tree;
  State s = make_state(tree.model());
  const Index leaf = tree.num_branches() - 1;
  const Index a = tree.branch_atoms(leaf)[tree.branch_atoms(leaf).size() / 2];
  s.f_ext.row(a) << 0.5, 0.0, 0.0;
  const StepSettings ss{.dt = 0.5};
  SmrmTree::Workspace ws = tree.make_workspace();
  MatX3 S = tree.rest_surface(), N;
  const NormalPlan plan = make_normal_plan(static_cast<Index>(S.rows()), tree.faces());
  ReconstructionScratch scratch(2, static_cast<Index>(tree.faces().rows()));
  double frames = 0;
  auto update = [&] {
    frames += 1;
    step(tree.model(), s, ss);
    tree.map_to_surface(s.x, ws, S);
    if (mode == 1) vertex_normals(plan, S, scratch, N);
  };
  for (int i = 0; i < 200; ++i) update();
  for (auto _ : st) {
    if (mode == 2)
      vertex_normals(plan, S, scratch, N);
    else
      update();
    benchmark::DoNotOptimize(S.data());
    benchmark::DoNotOptimize(N.data());
  }
  st.counters["surface_nodes"] = static_cast<double>(S.rows());
  st.counters["substeps_per_frame"] = static_cast<double>(s.substeps) / frames;
}
void BM_SmrmTreeBlendedUpdate(benchmark::State& st) {
  blended_update(st, 0);
}
void BM_SmrmTreeBlendedUpdateNormals(benchmark::State& st) {
  blended_update(st, 1);
}
void BM_SmrmTreeBlendedNormals(benchmark::State& st) {
  blended_update(st, 2);
}
BENCHMARK(BM_SmrmTreeBlendedUpdate)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SmrmTreeBlendedUpdateNormals)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SmrmTreeBlendedNormals)->Unit(benchmark::kMicrosecond);
#endif
#endif

}  // namespace
