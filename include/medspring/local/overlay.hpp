// Combining the local displacement with the global deformation (ALGORITHMS.md §6.5, D-17): the patch
// displacement U is added to the displayed positions only, never fed back into the dynamic state.
#pragma once

#include "medspring/core/types.hpp"
#include "medspring/local/patch.hpp"

namespace medspring {

/// x_a^disp += U_a for every patch node a; other rows unchanged (§6.5). U: #P x 3 (mm) in the patch's
/// local order; surface: #N x 3 displayed positions (mm). Throws InvalidInput when U has the wrong
/// number of rows or a patch node is outside the surface.
void apply_local_overlay(const LocalPatch& patch, const MatX3& U, MatX3& surface);

/// The dent guard of §6.5.
struct LocalGuard {
  bool enabled = true;    // §6.5 (disabled in the verification tests of §8)
  double fraction = 0.9;  // limit ||U_c|| <= fraction x rho_c
};

/// If ||U_c|| > fraction x rho_c (rho_c: spoke length of the contact node, mm; the dent would pass the
/// centerline), scales U uniformly so that ||U_c|| = fraction x rho_c. Returns the factor applied
/// (1 when the guard is off or not triggered). Never throws for a finite rho_c > 0; throws InvalidInput
/// otherwise, or when U has the wrong number of rows.
double limit_local_displacement(const LocalPatch& patch, MatX3& U, double rho_c,
                                const LocalGuard& guard = {});

/// Optional first-order smoothing of the local displacement with time constant tau_U (§6.5), held as a
/// displacement field over the whole surface so that a change of contact node or a release (U = 0)
/// fades out smoothly. tau_U = 0 (default) passes U through unchanged.
class LocalSmoother {
 public:
  explicit LocalSmoother(double tau_U = 0.0);  // ms; >= 0

  /// Advances the smoothed field D by dt (ms) towards the target (U on the patch nodes, 0 elsewhere):
  /// D += (1 - exp(-dt / tau_U)) (target - D), then adds D to surface (#N x 3). D is sized to surface
  /// on the first call (allocation then only). Throws InvalidInput for dt < 0 or mismatched sizes.
  void apply(const LocalPatch& patch, const MatX3& U, double dt, MatX3& surface);
  /// The same with no load (target 0 everywhere): the release of §6.5.
  void apply_released(double dt, MatX3& surface);
  /// The smoothed displacement field D (#N x 3, mm; empty before the first apply).
  const MatX3& displacement() const { return D_; }
  void reset() { D_.setZero(); }
  double time_constant() const { return tau_U_; }  // tau_U, ms

 private:
  double blend(double dt) const;
  double tau_U_ = 0.0;
  MatX3 D_;
};

}  // namespace medspring
