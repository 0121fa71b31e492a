// medspring_soak: long-run stability (issue 9). Repeated press / release cycles on the hybrid kidney
// phantom and the 40 x 30 tube; checks finiteness, rest recovery, bounded energy and resident memory.
//
//   medspring_soak [updates=1000000] [integrator=symplectic_euler]
//
// Prints one line per model and exits 1 if any check fails.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/surface_body.hpp"
#include "soak_run.hpp"

using namespace medspring;

namespace {

bool run_model(const char* name, BodyPtr body, const soak::Options& o, long updates, Integrator integrator) {
  SimulationSettings st;
  st.step.integrator = integrator;
  Simulation sim(std::move(body), st);
  const long per_cycle = std::lround((o.press_ms + o.settle_ms) / st.step.dt);
  const long cycles = std::max(11L, (updates + per_cycle - 1) / per_cycle);
  const long rss_start = soak::resident_kib();
  long rss10 = 0, done = 0;
  double seconds = 0, worst_rest = 0, e_min = 1e300, e_max = 0, peak_min = 1e300;
  bool finite = true;
  std::uint64_t warnings = 0;
  for (long c = 0; c < cycles; ++c) {
    const soak::Cycle r = soak::run_cycle(sim, o);
    done += r.updates;
    seconds += r.update_seconds;
    worst_rest = std::max(worst_rest, r.rest_error_mm);
    e_min = std::min(e_min, r.peak_energy);
    e_max = std::max(e_max, r.peak_energy);
    peak_min = std::min(peak_min, r.peak_mm);
    finite = finite && r.finite;
    warnings += r.warnings;
    if (c == 9) rss10 = r.rss_kib;
  }
  const long rss_end = soak::resident_kib();
  const bool ok =
      finite && worst_rest <= 1e-6 && e_max <= e_min * (1 + 1e-6) && rss_end <= rss10 && warnings == 0;
  std::printf(
      "%-14s %s: %ld cycles, %ld updates, %.0f updates/s (%.2f us/update); min peak %.3f mm; worst rest "
      "error %.2e mm; peak energy %.6g..%.6g mJ; warnings %llu; RSS start %ld KiB, cycle 10 %ld KiB, end %ld "
      "KiB -> %s\n",
      name, to_string(integrator).c_str(), cycles, done, static_cast<double>(done) / seconds,
      1e6 * seconds / static_cast<double>(done), peak_min, worst_rest, e_min, e_max,
      static_cast<unsigned long long>(warnings), rss_start, rss10, rss_end, ok ? "OK" : "FAILED");
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  const long updates = argc > 1 ? std::atol(argv[1]) : 1000000;
  const Integrator integ = argc > 2 ? parse_integrator(argv[2]) : Integrator::SymplecticEuler;
  if (updates <= 0) {
    std::fprintf(stderr, "usage: medspring_soak [updates > 0] [symplectic_euler|implicit_euler]\n");
    return 2;
  }
  bool ok = run_model("hybrid kidney", std::make_shared<HybridKidney>(hybrid_kidney_phantom()),
                      {.node = 223, .force = Vec3(0, 0, -1.0)}, updates, integ);
  ok = run_model("tube 40x30",
                 std::make_shared<SurfaceBody>(tube(40, 30, 2.5, 3.0), SurfaceBodyParams{}, "tube",
                                               GridLayout{40, 30}),
                 {.node = 20 * 30 + 7, .force = Vec3(0, -0.5, 0)}, updates, integ) &&
       ok;
  return ok ? 0 : 1;
}
