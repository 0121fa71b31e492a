// medspring_soak: long-run stability (issue 9). Repeated press / release cycles on the hybrid kidney
// phantom, the SMRM vessel phantom (40 atoms x 30 spokes on an arc) and the 40 x 30 tube, and on any
// model package given (the real kidney and aorta of `medspring export --web`); checks finiteness, rest
// recovery, bounded energy and resident memory.
//
//   medspring_soak [updates=1000000] [integrator=symplectic_euler] [PACKAGE.msm [FORCE_N=0.5]]...
//
// A package is pressed at its surface node farthest along +x, towards the surface centroid. Prints one
// line per model and exits 1 if any check fails.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/core/error.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/smrm_vessel.hpp"
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
  if (updates <= 0) {
    std::fprintf(stderr,
                 "usage: medspring_soak [updates > 0] [symplectic_euler|implicit_euler] [PACKAGE.msm [FORCE_N]]...\n");
    return 2;
  }
  Integrator integ = Integrator::SymplecticEuler;
  try {
    if (argc > 2) integ = parse_integrator(argv[2]);
  } catch (const Error& e) {
    std::fprintf(stderr, "medspring_soak: %s\n", e.what());
    return 2;
  }
  bool ok = run_model("hybrid kidney", std::make_shared<HybridKidney>(hybrid_kidney_phantom()),
                      {.node = 223, .force = Vec3(0, 0, -1.0)}, updates, integ);
  ok = run_model("tube 40x30",
                 std::make_shared<SurfaceBody>(tube(40, 30, 2.5, 3.0), SurfaceBodyParams{}, "tube",
                                               GridLayout{40, 30}),
                 {.node = 20 * 30 + 7, .force = Vec3(0, -0.5, 0)}, updates, integ) &&
       ok;
  ok = run_model("smrm vessel", std::make_shared<SmrmVessel>(smrm_phantom(VesselPath::Arc, CrossSectionShape::Circular)),
                 {.node = 20 * 30, .force = Vec3(0, 0, -0.5), .settle_ms = 200}, updates, integ) &&
       ok;
  for (int a = 3; a < argc; ++a) {
    const std::string file = argv[a];
    double newton = 0.5;
    if (a + 1 < argc && std::string(argv[a + 1]).find(".msm") == std::string::npos) newton = std::atof(argv[++a]);
    try {
      BodyPtr body = make_body(read_model_package(file));
      const MatX3& S = body->rest_surface();
      const Vec3 c = S.colwise().mean().transpose();
      Index node = 0;
      S.col(0).maxCoeff(&node);
      const Vec3 inward = (c - S.row(node).transpose()).normalized();
      // an SMRM centerline settles more slowly than a surface (the real aorta: ~200 ms to 1e-6 mm)
      const double settle = body->kind() == "smrm" ? 300 : 150;
      ok = run_model(file.c_str(), std::move(body), {.node = node, .force = newton * inward, .settle_ms = settle},
                     updates, integ) &&
           ok;
    } catch (const Error& e) {
      std::fprintf(stderr, "medspring_soak: %s\n", e.what());
      return 2;
    }
  }
  return ok ? 0 : 1;
}
