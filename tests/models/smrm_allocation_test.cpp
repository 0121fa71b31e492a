// "No allocation inside the update loop" (DESIGN.md) for the SMRM update: chain step, frames,
// reconstruction and normals. Counts every malloc/calloc/realloc/aligned allocation of the process by
// interposing glibc's allocator in this test executable (glibc only, not under a sanitizer, which
// interposes the allocator itself).
#include <gtest/gtest.h>

#include "medspring/models/smrm_vessel.hpp"
#include "medspring/physics/integrators.hpp"

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MEDSPRING_TEST_NO_INTERPOSE 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define MEDSPRING_TEST_NO_INTERPOSE 1
#endif

#if defined(__GLIBC__) && !defined(MEDSPRING_TEST_NO_INTERPOSE)
#include <atomic>
#include <cerrno>
#include <cstddef>

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
}

namespace {
std::atomic<long> g_allocations{0};
}

extern "C" {
void* malloc(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(n);
}
void* calloc(std::size_t a, std::size_t b) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(a, b);
}
void* realloc(void* p, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, n);
}
void* aligned_alloc(std::size_t a, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(a, n);
}
int posix_memalign(void** p, std::size_t a, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  *p = __libc_memalign(a, n);
  return *p ? 0 : ENOMEM;
}
}

namespace medspring {
namespace {

long allocations() {
  return g_allocations.load(std::memory_order_relaxed);
}

TEST(SmrmAllocation, TheCounterSeesEigenAndStandardAllocations) {  // the check below can fail
  const long before = allocations();
  MatX3 big(1000, 3);
  std::vector<double> v(100);
  EXPECT_GE(allocations() - before, 2);
}

TEST(SmrmAllocation, UpdateDoesNotAllocate) {
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
#endif
