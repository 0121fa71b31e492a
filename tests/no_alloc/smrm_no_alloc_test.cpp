// "No allocation inside the update loop" (DESIGN.md) for the SMRM update: chain step, frames,
// reconstruction and normals, counted by the shared counter of tests/support/alloc_counter.hpp.
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/physics/integrators.hpp"

namespace medspring {
namespace {

long allocations() {
  return testing::heap_allocations();
}

TEST(SmrmAllocation, TheCounterSeesEigenAndStandardAllocations) {  // the check below can fail
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  const long before = allocations();
  MatX3 big(1000, 3);
  std::vector<double> v(100);
  EXPECT_GE(allocations() - before, 2);
}

TEST(SmrmAllocation, UpdateDoesNotAllocate) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  for (bool structured : {true, false}) {
    SCOPED_TRACE(structured ? "structured tube" : "generic binding");
    SmrmSettings settings;
    settings.frames.anchor = structured ? FrameAnchor::TwoEnd : FrameAnchor::BestFit;
    SmrmVessel v = smrm_phantom(VesselPath::Helix, CrossSectionShape::NonPlanar, settings);
    if (!structured) {  // the same surface, bound generically (§5.9) with its triangles
      SurfaceMesh mesh{v.rest_surface(), v.faces()};
      SmrmParts p;
      p.name = "generic";
      p.atoms = v.rest_atoms();
      p.binding = bind_to_polyline(mesh.V, make_frame_reference(p.atoms, settings.frames));
      p.rest_surface = mesh.V;
      p.faces = mesh.F;
      v = SmrmVessel(std::move(p), settings);
    }
    State s = make_state(v.model());
    v.transfer_force(20 * 30 + 15, Vec3(0.3, -0.4, 0.2), s.f_ext);
    const StepSettings step_settings{.dt = 0.5};
    SmrmVessel::Workspace ws = v.make_workspace();
    MatX3 S(v.num_surface_nodes(), 3), N(v.num_surface_nodes(), 3);
    auto update = [&] {
      step(v.model(), s, step_settings);
      v.map_to_surface(s.x, ws, S);
      v.surface_normals(S, ws, N);
    };
    update();  // first call: nothing left to size
    const long before = allocations();
    for (int k = 0; k < 50; ++k) update();
    EXPECT_EQ(allocations() - before, 0);
    EXPECT_GT((S - v.rest_surface()).cwiseAbs().maxCoeff(), 0.1);  // it did move
  }
}

}  // namespace
}  // namespace medspring
