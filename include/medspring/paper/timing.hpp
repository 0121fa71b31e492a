// The timing of the paper's Tables I and II (ALGORITHMS.md §7.3, D-18): the cases, and the protocol that
// times them. One update = loads -> step (sub-steps as the stability rule asks) -> map to the surface
// (SMRM: frames + reconstruction of 1200 nodes) -> local overlay if enabled -> vertex normals, through
// Simulation::update(). The force is held constant at the strong value (vessel 0.5 N, kidney 1.0 N) so
// that the cubic terms act. `medspring bench` runs the same cases (bench/table_cases.hpp).
//
//   std::vector<TimedCase> t = time_cases(timing_cases(), {.warmup = 200, .rounds = 5, .per_round = 400});
//   t[0].median_us
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring::paper {

/// One case of Tables I and II.
struct TimingCase {
  std::string name;   // "table_ms_tube_1200_nonlinear_local_cache", ...
  std::string model;  // "MS" (TubeHybridBody, the hybrid mass-spring on the vessel), "SMRM", "kidney MS"
  bool nonlinear = true;
  std::string local;  // "off", "no_cache" (paper-like: select, assemble, factor, solve every update),
                      // "cache" (factor kept per contact node)
  Index nodes = 0, springs = 0;
  /// Builds the case's simulation (force held) and returns one update of it.
  std::function<std::function<void()>()> setup;
};

/// Facts about the model of a case, measured by building it and running a few updates.
struct TimingCaseInfo {
  long masses = 0, springs = 0, surface_nodes = 0;
  double dt_safe_rest_ms = 0.0;      // stable step at rest (§2.2)
  double substeps_per_update = 0.0;  // sub-steps taken per update under the held force
};

/// The cases: MS and SMRM on the same 40 x 30 vessel and the kidney hybrid (458 + 42), each linear,
/// nonlinear, nonlinear with local deformation without and with the cached factor.
std::vector<TimingCase> timing_cases();

/// Builds the case's model, runs 200 updates and reports its size and sub-stepping.
TimingCaseInfo timing_case_info(const TimingCase& c);

/// The protocol of D-18: every case warmed up, then its timed updates taken in interleaved rounds (a
/// change of the machine's load hits every case alike).
struct TimingProtocol {
  long warmup = 200, rounds = 5, per_round = 400;
};

struct TimedCase {
  TimingCase c;
  TimingCaseInfo info;
  std::vector<double> us;             // every timed update, µs
  std::vector<double> round_medians;  // median of each round, µs
  double median = 0, mean = 0, p90 = 0;
  double spread = 0;  // (max - min) / median of the round medians: the run-to-run noise
};

/// Times `cases` by `protocol`; `progress` (may be empty) gets the fraction done.
std::vector<TimedCase> time_cases(const std::vector<TimingCase>& cases, const TimingProtocol& protocol,
                                  const std::function<void(double)>& progress = {});

/// The case of a model, law and local mode; InvalidInput when there is none.
const TimedCase& find_case(const std::vector<TimedCase>& cases, const std::string& model, bool nonlinear,
                           const std::string& local);

/// The paper's Tables I and II, seconds per update.
struct PaperTimes {
  double linear, nonlinear, local;
};
inline constexpr PaperTimes kPaperMassSpring{0.018, 0.022, 0.032};
inline constexpr PaperTimes kPaperSmrm{0.013, 0.016, 0.027};

}  // namespace medspring::paper
