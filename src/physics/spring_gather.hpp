// The gather pass of the serial symplectic step (docs/physics.md, "One update"): the spring forces of a
// substep are computed once per spring into a slot buffer (vectorised, no scatter), then every node
// gathers its slots in increasing spring index, adds its return spring and load and is advanced at once.
// The node sums have the same terms in the same order as the scatter pass (forces.cpp): a spring's force
// on its end j is the negated force on its end i, as `f_j -= f` there. Equal to rounding (FMA
// contraction may differ between the vectorised and the scalar loop). With the float volume pass
// (Model::volume_f32) the slots are float (spring_f32.hpp) and each node sums them in four partial sums:
// equal to the double pass to float rounding (docs/volumetric-speed.md "Float springs").
#pragma once

#include <cstdint>

#include "medspring/physics/model.hpp"
#include "medspring/physics/state.hpp"
#include "spring_kernel.hpp"

namespace medspring::detail {

/// Largest model (springs) with the float volume pass and float springs (Model::volume_f32) that gets a
/// SpringGather: its float slots take 32 bytes a spring, half the double ones, so twice
/// kSpringGatherMaxSprings (docs/volumetric-speed.md "Float slots for larger models").
inline constexpr Index kSpringGatherMaxSpringsF32 = 2 * kSpringGatherMaxSprings;

/// Fills model.gather (finalize calls it last, set_volume_single_precision again); leaves it empty where the
/// pass does not apply.
void build_spring_gather(Model& m);

/// The float limit above (for the benchmark's A/B: models built after the call). Returns the former one.
Index set_spring_gather_max_f32(Index springs);

/// The gather pass applies to m (and st's buffer is sized for it, or is sized now: once per state).
bool gather_ready(const Model& m, State& st);

/// One guarded symplectic substep (§2.1, §2.5) through the gather pass, coefficients st.step_coef
/// refreshed for h by the caller. With `stiffening`, st.stiffening = max(1, max_s kappa_s / k_s).
/// Returns 0 (ok), 1 (a velocity over v_max) or 2 (non-finite), the nodes already advanced restored
/// (as symplectic_substep does). st.f holds the node forces afterwards, as after internal_forces (after
/// a failed substep only those of the nodes up to the failing one: f is scratch then).
/// A model with volume terms (issue 23): their pass (volume_forces, with `local` as in internal_forces)
/// writes st.f before the node pass adds the rest, and the stiffening is that of springs and terms.
int gather_substep(const Model& m, State& st, double h, double vmax2, bool guard, bool stiffening,
                   const LocalStiffening* local = nullptr);

/// The forces t e (e = x_j - x_i, t the tension over the length) of the springs [s0, s0 + nb) on their
/// ends i, as rows (x, y, z, 0) of F (nb x 4 doubles), with the gather pass's vectorised arithmetic (its
/// 4-springs-at-a-time AVX-512 pass where built, a spring shorter than kMinSpringLength gets 0; no soft
/// springs). With `stiffening`, the largest kappa/k is folded into stiff_bits (the bit pattern of a
/// non-negative double, start at 0).
void spring_chunk_forces(const Model& m, Index s0, Index nb, const double* x, double* F, bool stiffening,
                         std::int64_t& stiff_bits);

/// With the float volume pass (Model::volume_f32) the springs of every sub-step are in float too
/// (spring_f32.hpp; on by default); off: in double, as without it. For the benchmark's and the tests' A/B.
/// Returns the former setting.
bool set_gather_springs_f32(bool on);

/// gather_substep takes the float sub-step (the float volume pass and float springs) for m with `local`.
bool float_substep_applies(const Model& m, const LocalStiffening* local);

/// The float sub-step's node pass (threaded_volume.hpp): each node's force (the volume terms' part, the sum
/// in double of its rows of the float force mirrors mirrors[0 .. count), in that order; its load, return
/// spring and float slots) into st.f, and the symplectic update of a free node. Returns 0, or 1 / 2 after
/// restoring the nodes it advanced.
int node_pass_f32(const Model& m, State& st, double h, double vmax2, bool guard, const float* const* mirrors,
                  int count);

}  // namespace medspring::detail
