// The step of Integrator::LinearStatic (issue 23, physics/linear_response.hpp), called by step() and
// prepare_step().
#pragma once

#include <vector>

#include "medspring/physics/integrators.hpp"

namespace medspring::detail {

/// Builds the state's LinearResponse for m unless it has one built for m, and sizes its scratch.
void prepare_linear_static(const Model& m, State& st);

/// One frame of the quasi-static linear response (see step()).
StepStatus linear_static_step(const Model& m, State& st, const StepSettings& s,
                              const std::vector<PointLoad>* loads, const SubstepForce* per_substep);

}  // namespace medspring::detail
