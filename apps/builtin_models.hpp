// The bundled procedural models by name, shared by `medspring haptics` and `medspring export`.
#pragma once

#include <memory>
#include <string>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"

namespace medspring::cli {

/// A bundled model and its default contact node (the press node of the demos).
struct BuiltinModel {
  BodyPtr body;
  Index contact = 0;
};

inline bool is_builtin_model(const std::string& name) {
  return name == "kidney_phantom" || name == "tube" || name == "vessel_phantom";
}

/// kidney_phantom: hybrid kidney of §4.1 (458 + 42); tube: surface mass-spring 40 x 30 tube;
/// vessel_phantom: SMRM straight-x vessel of §8.0 (40 atoms x 30 spokes). `nonlinear` selects the
/// Duffing springs (D-4) or all linear.
inline BuiltinModel builtin_model(const std::string& name, bool nonlinear = true) {
  if (name == "kidney_phantom") {
    HybridSettings hs;
    hs.nonlinear = nonlinear;
    return {std::make_shared<HybridKidney>(hybrid_kidney_phantom(hs)), 223};
  }
  if (name == "tube") {
    SurfaceBodyParams p;
    if (!nonlinear) p.duffing.mode = DuffingMode::Linear;
    return {std::make_shared<SurfaceBody>(tube(40, 30, 2.5, 3.0), p, "tube", GridLayout{40, 30}),
            20 * 30 + 7};
  }
  if (name == "vessel_phantom") {
    SmrmSettings s;
    s.chain.nonlinear = nonlinear;
    return {std::make_shared<SmrmVessel>(smrm_phantom(VesselPath::StraightX, CrossSectionShape::Circular, s)),
            20 * 30 + 7};
  }
  throw InvalidInput("unknown model '" + name + "' (expected kidney_phantom, tube or vessel_phantom)");
}

}  // namespace medspring::cli
