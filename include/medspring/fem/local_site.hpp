// The local overlay of eq. (6) as a calibrated site family of the volumetric kind
// (docs/accuracy-calibration.md, "The local overlay as a site family"): the disk load's own nodal forces
// solved on the loaded patch, added to the static response with a fitted compliance a (a = 0: no overlay;
// k_loc = k_ref / a).
//
//   const MatX3 v = fem::disk_local_overlay(*body, load, body->local_stiffness());  // #S x 3, mm
//   const MatX3 u = fem::spring_displacement(*body, load) + a * v;
#pragma once

#include <functional>
#include <vector>

#include "medspring/fem/organ.hpp"

namespace medspring::fem {

/// The local deformation (§6, eq. 6) of a disk load on the body's surface: the consistent nodal forces of
/// disk_load_linear on the body's surface triangles, solved (Isotropic, every patch spring k_loc N/mm) on
/// the patch of the loaded nodes plus `rings` rings of neighbours (loaded_nodes_patch: the outer ring
/// fixed), zero elsewhere. #S x 3 (mm), the rows of body.rest_surface(). Throws InvalidInput for k_loc <= 0
/// or a disk that loads no surface node, SolverError for a singular patch.
MatX3 disk_local_overlay(const Body& body, const ContactLoad& load, double k_loc, int rings = 1);

/// The least-squares coefficients of u and v in the calibration cost (calibration_cost's terms: the mean
/// squared surface error and the squared site error, relative to each load's largest FEM displacement)
/// of alpha u_i + a v_i against the FEM over the training loads, with a >= 0. fit_scale = false holds
/// alpha = 1 and fits a alone. u, v: one field per training load, as the response's rows.
struct OverlayCoefficients {
  double alpha = 1;  // scale of u (1 / the stiffness scale of the volumetric kind's small-strain response)
  double a = 0;      // the overlay compliance (>= 0)
  double cost = 0;   // the cost at (alpha, a)
};
OverlayCoefficients fit_overlay_coefficients(const std::vector<MatX3>& u, const std::vector<MatX3>& v,
                                             const std::vector<CalibrationCase>& training, bool fit_scale);

/// The volumetric kind's calibration with the overlay family: multipliers (springs, volume terms, c, a).
/// Small strain: a golden-section search over the volume / spring ratio r in [1e-2, 1e2] (`evaluations`
/// batch responses at (1, r)), with the scale and a in closed form at each r (fit_overlay_coefficients), as
/// calibrate_scale_and_ratio does without a. With `full` (the full response at (springs, volume, c), no
/// overlay): calibrate_volumetric_nonlinear refines (springs, volume, c) with the overlay held at the
/// small-strain a, then a is refitted in closed form on the refined response. overlay(load): the overlay
/// field at compliance 1 (e.g. disk_local_overlay at k_ref). Without `full`, c's multiplier is 1.
struct OverlayFit {
  VecX m;                                  // springs, volume terms, c multiplier, overlay compliance a
  VecX m_small_strain;                     // the small-strain stage's (springs, volume terms)
  double a_small_strain = 0;               // a of the small-strain stage
  double small_strain_cost = 0, cost = 0;  // the small-strain stage's cost; the final calibration_cost
  int evaluations = 0;                     // nonlinear refine evaluations (0 without `full`)
};
OverlayFit calibrate_volumetric_overlay(const BatchResponse& small_strain, const Response* full,
                                        const std::function<MatX3(const ContactLoad&)>& overlay,
                                        const std::vector<CalibrationCase>& training, int evaluations = 18);

}  // namespace medspring::fem
