// The volumetric spring kidney (issue 23, docs/volumetric.md): one simulation update (a 0.5 ms frame with
// the sub-steps its stable step needs) and one force evaluation, at about 2,000 nodes (the kidney phantom's
// 458-node surface meshed inside by TetGen -pqY), supports on the posterior 20 % and a 0.5 N load.
// Needs the fem layer (TetGen); without it nothing is registered.
#include <benchmark/benchmark.h>

#ifdef MEDSPRING_BENCH_HAVE_FEM
#include <memory>

#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/sim/simulation.hpp"

namespace {

using namespace medspring;

std::shared_ptr<const VolumetricBody> kidney(Index nodes) {
  const SurfaceMesh s = kidney_phantom();
  const VolumetricMesh vm = fem::volumetric_mesh(s, {.target_nodes = nodes});
  const double zmin = s.V.col(2).minCoeff(), zmax = s.V.col(2).maxCoeff();
  VolumetricSettings st;  // 10 kPa, nu = 0.45
  st.fixed = fem::support_nodes(s.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
  return std::make_shared<VolumetricBody>(vm, st, "volumetric kidney");
}

void BM_VolumetricKidneyUpdate(benchmark::State& st) {
  const auto body = kidney(static_cast<Index>(st.range(0)));
  SimulationSettings ss;
  ss.normals = false;
  ss.local.enabled = false;
  Simulation sim(body, ss);
  Index top = 0;
  for (Index i = 0; i < body->num_surface_nodes(); ++i)
    if (body->rest_surface()(i, 2) > body->rest_surface()(top, 2)) top = i;
  sim.set_loads({{.node = top, .force = Vec3(0, 0, -0.5), .t_ramp = 0}});
  sim.advance(50);
  const auto s0 = sim.state().substeps;
  const auto f0 = sim.state().frames;
  for (auto _ : st) sim.update();
  st.counters["nodes"] = static_cast<double>(body->model().num_nodes());
  st.counters["springs"] = static_cast<double>(body->model().num_springs());
  st.counters["tets"] = static_cast<double>(body->model().volume.size());
  st.counters["substeps_per_update"] =
      static_cast<double>(sim.state().substeps - s0) / static_cast<double>(sim.state().frames - f0);
}
BENCHMARK(BM_VolumetricKidneyUpdate)->Arg(1000)->Arg(2000)->Unit(benchmark::kMicrosecond);

void BM_VolumetricKidneyForces(benchmark::State& st) {
  const auto body = kidney(2000);
  const Model& m = body->model();
  MatX3 x = m.x0, f(m.num_nodes(), 3), fe = MatX3::Zero(m.num_nodes(), 3);
  x.col(2) *= 0.98;
  for (auto _ : st) {
    internal_forces(m, x, fe, f);
    benchmark::DoNotOptimize(f.data());
  }
  st.counters["nodes"] = static_cast<double>(m.num_nodes());
}
BENCHMARK(BM_VolumetricKidneyForces)->Unit(benchmark::kMicrosecond);

}  // namespace
#endif
