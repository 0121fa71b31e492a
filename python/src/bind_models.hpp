// Shared between the model bindings (bind_models.cpp, bind_vessels.cpp).
#pragma once

#include "bind_common.hpp"
#include "medspring/models/body.hpp"
#include "medspring/physics/state.hpp"

namespace medspring::python {

/// Throws InvalidInput when `s` does not have the body's node count.
void check_body_state(const Body& body, const State& s);

/// SmrmVessel, vessel trees and the vessel experiment (bind_vessels.cpp).
void bind_vessels(py::module_& m);

}  // namespace medspring::python
