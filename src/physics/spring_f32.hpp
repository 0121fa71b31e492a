// The springs of the gather pass in single precision (issue 23, docs/volumetric-speed.md "Float springs"):
// with the float volume pass (Model::volume_f32), each sub-step's spring slots are computed in float from the
// volume pass's displacement mirror and summed in float by the node pass (spring_gather.cpp), 16 bytes a
// slot instead of 32. Internal to the physics layer; slot_forces (spring_gather.cpp, double) is the
// reference.
#pragma once

#include "medspring/physics/model.hpp"
#include "volume_f32.hpp"

namespace medspring::detail {

/// Builds S from the model's springs and rest positions (set_volume_single_precision calls it).
void build_springs_f32(const Model& m, SpringsF32& S);

/// The displacement mirror of the float volume pass (volume_f32.hpp): u's rows (4 floats a node) set to
/// (x - x0, 0) in float. For a spring pass that runs before the volume pass (the frame's last sub-step).
void fill_displacements_f32(const VolumeTermsF32& F, const double* x, float* u);

/// Every slot's force in float into F ((2 #S + 1) rows of 4 floats: slot s = spring s at its end i, #S + s
/// at its end j, 2 #S zero), from the displacement mirror u, as (t e, 0) and its exact negation: t the
/// tension over the length, e = E + (u_j - u_i), L - L0 = (2 E.D + D.D) / (L + |E|) + c with D = u_j - u_i
/// (no cancellation: exactly c at rest). A spring shorter than kMinSpringLength gets 0. Returns max(1, max
/// kappa/k) with `stiffening`, else 1. Eight springs a vector where MEDSPRING_F32_LANES is compiled (or
/// `x8` is off: one at a time, for the tests' A/B), the rest one at a time.
double spring_slots_f32(const SpringsF32& S, const float* u, float* F, bool stiffening, bool x8 = true);

}  // namespace medspring::detail
