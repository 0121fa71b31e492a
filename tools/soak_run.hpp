// Repeated press / release cycles on a Simulation (issue 9, long runs): shared by tools/soak.cpp and
// tests/reliability/long_run_test.cpp. Not part of the library (reads /proc/self/statm on Linux).
#pragma once

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "medspring/physics/forces.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring::soak {

/// Resident set size of this process, KiB (0 where /proc/self/statm cannot be read).
inline long resident_kib() {
  long pages_total = 0, pages_resident = 0;
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0;
  const int got = std::fscanf(f, "%ld %ld", &pages_total, &pages_resident);
  std::fclose(f);
  return got == 2 ? pages_resident * (sysconf(_SC_PAGESIZE) / 1024) : 0;
}

struct Options {
  Index node = 0;             // loaded surface node
  Vec3 force = Vec3::Zero();  // N
  double ramp_ms = 20;        // ramp duration
  double press_ms = 100;      // from the cycle start to the release
  double settle_ms = 150;     // after the release, before the rest check (70 ms measured suffice)
};

/// What one cycle measured.
struct Cycle {
  double peak_mm = 0;        // max node displacement from rest during the cycle
  double rest_error_mm = 0;  // max node displacement at the cycle end (after settling)
  double peak_energy = 0;    // max total energy (mJ) sampled every update
  bool finite = true;        // x and v finite at every update
  std::uint64_t warnings = 0;
  long rss_kib = 0;           // resident size at the cycle end
  long updates = 0;           // updates in the cycle
  double update_seconds = 0;  // wall time inside Simulation::update (checks excluded)
};

/// Runs one press / release cycle starting at the current time. Updates: (press + settle) / dt.
inline Cycle run_cycle(Simulation& sim, const Options& o) {
  const double t0 = sim.time();
  sim.set_loads(
      {{.node = o.node, .force = o.force, .t_on = t0, .t_ramp = o.ramp_ms, .t_release = t0 + o.press_ms}});
  const Model& m = sim.model();
  const long frames = std::lround((o.press_ms + o.settle_ms) / sim.settings().step.dt);
  const std::uint64_t w0 = sim.state().warnings.total();
  Cycle c;
  for (long k = 0; k < frames; ++k) {
    const auto a = std::chrono::steady_clock::now();
    sim.update();
    c.update_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
    const State& s = sim.state();
    if (!s.x.allFinite() || !s.v.allFinite()) c.finite = false;
    c.peak_mm = std::max(c.peak_mm, (s.x - m.x0).rowwise().norm().maxCoeff());
    c.peak_energy = std::max(c.peak_energy, total_energy(m, s.x, s.v));
  }
  c.updates = frames;
  c.rest_error_mm = (sim.state().x - m.x0).rowwise().norm().maxCoeff();
  c.warnings = sim.state().warnings.total() - w0;
  c.rss_kib = resident_kib();
  return c;
}

}  // namespace medspring::soak
