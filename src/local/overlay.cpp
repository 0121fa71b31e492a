#include "medspring/local/overlay.hpp"

#include <cmath>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

void require_patch_rows(const LocalPatch& patch, const MatX3& U, const char* what) {
  require(U.rows() == patch.size(), what, ": displacement has ", U.rows(), " rows, the patch has ",
          patch.size(), " nodes");
}

// Checked before anything is written, so a bad call leaves the surface untouched.
void require_patch_in_surface(const LocalPatch& patch, const MatX3& surface, const char* what) {
  const Index n = static_cast<Index>(surface.rows());
  for (Index a = 0; a < patch.size(); ++a)
    require(patch.nodes[a] >= 0 && patch.nodes[a] < n, what, ": patch node ", a, " (global ", patch.nodes[a],
            ") is outside the surface of ", n, " nodes");
}

}  // namespace

void apply_local_overlay(const LocalPatch& patch, const MatX3& U, MatX3& surface) {
  require_patch_rows(patch, U, "local overlay");
  require_patch_in_surface(patch, surface, "local overlay");
  for (Index a = 0; a < patch.size(); ++a)
    surface.row(patch.nodes[a]) += U.row(a);  // §6.5: x_disp = x_global + U (D-17: display only)
}

double limit_local_displacement(const LocalPatch& patch, MatX3& U, double rho_c, const LocalGuard& guard) {
  require_patch_rows(patch, U, "local guard");
  require_positive(rho_c, "local guard: rho_c");
  if (!guard.enabled) return 1.0;
  require_positive(guard.fraction, "local guard: fraction");
  require_index(patch.contact_local, patch.size(), "local guard: contact_local");
  const double u_c = U.row(patch.contact_local).norm(), limit = guard.fraction * rho_c;
  if (!(u_c > limit)) return 1.0;
  const double scale = limit / u_c;  // §6.5 guard: scale U uniformly
  U *= scale;
  return scale;
}

LocalSmoother::LocalSmoother(double tau_U) : tau_U_(tau_U) {
  require_nonnegative(tau_U, "local smoothing: tau_U");
}

double LocalSmoother::blend(double dt) const {
  require_nonnegative(dt, "local smoothing: dt");
  return tau_U_ == 0.0 ? 1.0 : 1.0 - std::exp(-dt / tau_U_);
}

void LocalSmoother::apply(const LocalPatch& patch, const MatX3& U, double dt, MatX3& surface) {
  require_patch_rows(patch, U, "local smoothing");
  require_patch_in_surface(patch, surface, "local smoothing");
  const double alpha = blend(dt);
  if (D_.rows() != surface.rows()) D_ = MatX3::Zero(surface.rows(), 3);
  D_ *= 1.0 - alpha;  // first-order lag towards the target (§6.5 tau_U)
  for (Index a = 0; a < patch.size(); ++a) D_.row(patch.nodes[a]) += alpha * U.row(a);
  surface += D_;
}

void LocalSmoother::apply_released(double dt, MatX3& surface) {
  const double alpha = blend(dt);
  if (D_.rows() != surface.rows()) D_ = MatX3::Zero(surface.rows(), 3);
  D_ *= 1.0 - alpha;
  surface += D_;
}

}  // namespace medspring
