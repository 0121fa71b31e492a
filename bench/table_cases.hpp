// The timing cases of the paper's Tables I and II (ALGORITHMS.md §7.3, D-18) as benchmark cases: the
// paper module's cases (include/medspring/paper/timing.hpp), run by `medspring bench` (through
// all_cases) and timed by `medspring paper`. One update = loads -> step (substeps as the stability rule
// asks; 1 at these sizes) -> map to the surface (SMRM: frames + reconstruction of 1200 nodes) -> local
// overlay if enabled -> vertex normals, through Simulation::update(). The force is held constant at the
// strong value (vessel 0.5 N, kidney 1.0 N) so that the cubic terms are active.
#pragma once

#include <string>
#include <vector>

#include "cases.hpp"
#include "medspring/paper/timing.hpp"

namespace medspring::bench {

/// What a table case is: which model, linear or not, and how local deformation runs.
struct TableCase {
  BenchCase bench;    // name contains the model ("tube_1200" / "smrm_1200" / "kidney"), "local"
  std::string model;  // "MS" (hybrid mass-spring on the vessel), "SMRM", "kidney MS"
  bool nonlinear = true;
  std::string local;         // "off", "no_cache" (paper-like: select, assemble, factor, solve every update),
                             // "cache" (factor kept per contact node)
  paper::TimingCase timing;  // the case as the paper module defines it
};

/// Facts about the model of a table case, measured by building it and running a few updates.
using TableCaseInfo = paper::TimingCaseInfo;

/// The cases of Tables I and II: MS and SMRM on the same 40 x 30 vessel (linear, nonlinear, nonlinear
/// with local deformation without and with the cached factor), and the kidney hybrid (458 + 42).
std::vector<TableCase> table_cases();

/// Builds the case's model, runs 200 updates and reports its size and sub-stepping.
TableCaseInfo table_case_info(const TableCase& c);

}  // namespace medspring::bench
