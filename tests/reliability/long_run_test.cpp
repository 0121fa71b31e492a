// Long runs (issue 9): repeated press / release cycles stay finite, return to rest after every release,
// keep the same energy peak every cycle and do not grow in resident memory. The full 10^6-update soak
// is tools/soak.cpp (docs/reliability.md); this test runs ~100 000 updates (label `long`).
#include <gtest/gtest.h>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "soak_run.hpp"

namespace medspring {
namespace {

enum class Which { Kidney, Tube, Vessel };

struct LongCase {
  const char* name;
  Which which;
  Integrator integrator;
  int cycles;
};
void PrintTo(const LongCase& c, std::ostream* os) {
  *os << c.name;
}

class LongRun : public ::testing::TestWithParam<LongCase> {};

TEST_P(LongRun, PressReleaseCyclesRecoverRestWithBoundedEnergyAndMemory) {
  const LongCase& lc = GetParam();
  SimulationSettings st;
  st.step.integrator = lc.integrator;
  BodyPtr body;
  soak::Options o;  // the demo's forces; 100 ms press (20 ms ramp), 150 ms settling (~70 ms suffice)
  switch (lc.which) {
    case Which::Kidney:
      body = std::make_shared<HybridKidney>(hybrid_kidney_phantom());
      o = {.node = 223, .force = Vec3(0, 0, -1.0)};
      break;
    case Which::Tube:
      body = std::make_shared<SurfaceBody>(tube(40, 30, 2.5, 3.0), SurfaceBodyParams{}, "tube", GridLayout{40, 30});
      o = {.node = 20 * 30 + 7, .force = Vec3(0, -0.5, 0)};
      break;
    case Which::Vessel:  // SMRM: 40 atoms x 30 spokes; the surface force is transferred to the atoms
      body = std::make_shared<SmrmVessel>(smrm_phantom(VesselPath::Arc, CrossSectionShape::Circular));
      o = {.node = 20 * 30, .force = Vec3(0, 0, -0.5), .settle_ms = 200};  // settles in ~155 ms
      break;
  }
  Simulation sim(body, st);
  double first_energy = 0;
  long rss10 = 0;
  for (int c = 0; c < lc.cycles; ++c) {
    const soak::Cycle r = soak::run_cycle(sim, o);
    ASSERT_TRUE(r.finite) << "cycle " << c;
    EXPECT_GT(r.peak_mm, 0.5) << "cycle " << c;         // the press acts every cycle
    EXPECT_LE(r.rest_error_mm, 1e-6) << "cycle " << c;  // rest recovered after the release
    EXPECT_EQ(r.warnings, 0u) << "cycle " << c;
    if (c == 0) first_energy = r.peak_energy;
    EXPECT_NEAR(r.peak_energy / first_energy, 1.0, 1e-6) << "cycle " << c;  // the same cycle each time
    if (c == 9) rss10 = r.rss_kib;
  }
  EXPECT_GT(rss10, 0);
  EXPECT_LE(soak::resident_kib(), rss10) << "resident memory grew after cycle 10";
}

INSTANTIATE_TEST_SUITE_P(Models, LongRun,
                         ::testing::Values(LongCase{"KidneySymplectic", Which::Kidney, Integrator::SymplecticEuler, 80},
                                           LongCase{"TubeSymplectic", Which::Tube, Integrator::SymplecticEuler, 80},
                                           LongCase{"VesselSymplectic", Which::Vessel, Integrator::SymplecticEuler, 80},
                                           LongCase{"KidneyImplicit", Which::Kidney, Integrator::ImplicitEuler, 14},
                                           LongCase{"TubeImplicit", Which::Tube, Integrator::ImplicitEuler, 14},
                                           LongCase{"VesselImplicit", Which::Vessel, Integrator::ImplicitEuler, 14}),
                         [](const auto& i) { return std::string(i.param.name); });

}  // namespace
}  // namespace medspring
