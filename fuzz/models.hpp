// The small models the checkpoint and model-package targets (and the seed generator) use, so that a
// fuzzed checkpoint can carry the fingerprint of a model the target has.
#pragma once

#include <memory>
#include <vector>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"

namespace medspring::fuzz {

/// A 6-ring x 8-spoke surface tube (48 nodes), the hybrid kidney phantom (458 + 42) and a vessel
/// phantom of 8 atoms x 6 spokes.
inline std::vector<BodyPtr> fuzz_bodies() {
  std::vector<BodyPtr> b;
  b.push_back(std::make_shared<SurfaceBody>(tube(6, 8, 2.5, 3.0), SurfaceBodyParams{}, "tube", GridLayout{6, 8}));
  b.push_back(std::make_shared<HybridKidney>(hybrid_kidney_phantom()));
  SmrmSettings s;
  s.atoms = 8;
  s.spokes = 6;
  b.push_back(std::make_shared<SmrmVessel>(smrm_phantom(VesselPath::Arc, CrossSectionShape::Elliptical, s)));
  return b;
}

}  // namespace medspring::fuzz
