// Tissue materials (docs/accuracy.md, "Scenes and Python: material"): a Young's modulus and Poisson
// ratio resolved to the spring parameters that `medspring calibrate` fitted against the CalculiX
// reference for that model kind.
//
//   TissueMaterial t = tissue_preset("kidney");            // 10 kPa, 0.45 (sources in docs/accuracy.md)
//   check_tissue(t, "model.material");                     // E <= 0, nu >= 0.5: InvalidInput naming the path
//   apply_tissue(t, TissueOrgan::Phantom, hybrid_settings);  // calibrated k_surf, k_spoke, k_cl, k_r
//
// The calibrations are shipped in this library (the table in tissue.cpp; reproduced by the commands in
// docs/accuracy.md) at the reference material E0 = 10 kPa, nu0 = 0.45. Another E at nu0 is exact: a
// compressible Neo-Hookean solid and a spring model whose every stiffness (k, k' = k eta / L0^2, k_r)
// scales by s give, under the force s F, the displacement they give under F; so the stiffnesses fitted
// at E0 scale by E / E0. Another nu scales them by the shear modulus ratio mu / mu0 (an approximation:
// a nearly incompressible body's response is dominated by mu; the error is not measured).
#pragma once

#include <string>
#include <vector>

#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/physics/model.hpp"

namespace medspring {

struct TissueMaterial {
  double E_kPa = 10.0;  // Young's modulus, kPa
  double nu = 0.45;     // Poisson ratio, (-1, 0.5)
  std::string preset;   // the preset it came from ("" when given by value)
};

/// "kidney" (10 kPa, 0.45) or "aorta" (65 kPa, 0.45); anything else throws InvalidInput listing them.
TissueMaterial tissue_preset(const std::string& name);
std::vector<std::string> tissue_preset_names();

/// Throws InvalidInput "<where>.E_kPa: must be > 0 ..." / "<where>.nu: must be in (-1, 0.5) ...".
void check_tissue(const TissueMaterial& t, const std::string& where);

/// Which calibration of a kidney-like body: the 458-node phantom or the real kidney of the bundled
/// scenes (remeshed, docs/accuracy.md). A body of another mesh gets the one nearest its kind.
enum class TissueOrgan { Phantom, RealKidney };

/// Stiffness scale of the material against the calibration's reference (E0 = 10 kPa, nu0 = 0.45).
double tissue_scale(const TissueMaterial& t);

/// Sets the calibrated stiffnesses (k_surf, k_spoke, k_cl, both k_r) for the material; s.nonlinear picks
/// the Duffing or the linear calibration. Masses, damping and the rest are untouched. Checks t.
void apply_tissue(const TissueMaterial& t, TissueOrgan organ, HybridSettings& s);
/// The same for the plain surface model (k, k_r); p.duffing.mode Linear picks the linear calibration.
void apply_tissue(const TissueMaterial& t, TissueOrgan organ, SurfaceBodyParams& p);
/// SMRM vessel: the wall's Young's modulus (wall.E, MPa) that gives the centerline's bending stiffness
/// (issue 17, BendingMode::Wall). The wall's thickness ratio is the vessel's, not the material's.
void apply_tissue(const TissueMaterial& t, SmrmSettings& s);

}  // namespace medspring
