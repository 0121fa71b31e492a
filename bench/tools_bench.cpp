// Rigid-tool contact on the hybrid kidney (458 surface nodes + 42 atoms, the phantom of §4.1; the
// real kidney model has the same sizes): a sphere pressed into the broad face so that it touches
// about 20 triangles. Compare, within one run, the update without the tool (contact forces held),
// the update with collision + response, and collision + response alone (docs/tools.md).
#include <benchmark/benchmark.h>

#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/sim/tool_sim.hpp"

namespace {

using namespace medspring;

struct PressedKidney {
  std::shared_ptr<HybridKidney> body = std::make_shared<HybridKidney>(hybrid_kidney_phantom());
  Simulation sim{body, SimulationSettings{.normals = false}};
  ToolSimulation tools{sim};
  Index probe = -1;
  PressedKidney() {
    Index top = 0;
    body->rest_surface().col(2).maxCoeff(&top);
    const Vec3 x = body->rest_surface().row(top).transpose();
    const double R = 16.0;
    probe = tools.add_tool(Tool::sphere(R), Pose{x + Vec3(0, 0, R + 1), Quat::Identity()});
    tools.set_path(probe, {{0.0, Pose{x + Vec3(0, 0, R + 1), Quat::Identity()}},
                           {50.0, Pose{x + Vec3(0, 0, R - 5), Quat::Identity()}}});
    while (sim.time() < 300) tools.update();  // pressed, at rest
  }
};

void BM_KidneyUpdateContactHeld(benchmark::State& st) {
  PressedKidney k;
  for (auto _ : st) k.sim.update();  // the forces of the last contact evaluation, no collision
  st.counters["contacts"] = static_cast<double>(k.tools.contact().state(k.probe).contacts);
}
BENCHMARK(BM_KidneyUpdateContactHeld)->Unit(benchmark::kMicrosecond);

void BM_KidneyUpdateWithSphereTool(benchmark::State& st) {
  PressedKidney k;
  for (auto _ : st) k.tools.update();  // collision + response + update
  st.counters["contacts"] = static_cast<double>(k.tools.contact().state(k.probe).contacts);
}
BENCHMARK(BM_KidneyUpdateWithSphereTool)->Unit(benchmark::kMicrosecond);

void BM_KidneySphereCollisionAndResponse(benchmark::State& st) {
  PressedKidney k;
  ContactModel contact = k.tools.contact();
  const MatX3& S = k.sim.global_surface();
  for (auto _ : st) {
    contact.update(S);
    benchmark::DoNotOptimize(contact.forces().total);
  }
  st.counters["contacts"] = static_cast<double>(contact.state(k.probe).contacts);
}
BENCHMARK(BM_KidneySphereCollisionAndResponse)->Unit(benchmark::kMicrosecond);

}  // namespace
