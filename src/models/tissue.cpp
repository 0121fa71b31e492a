// Tissue materials -> calibrated spring parameters (models/tissue.hpp).
#include "medspring/models/tissue.hpp"

#include <cmath>
#include <sstream>

#include "medspring/core/error.hpp"

namespace medspring {
namespace {

constexpr double kE0 = 10.0;  // kPa, the calibrations' reference material
constexpr double kNu0 = 0.45;

// Multipliers of the defaults (k_surf 0.05, k_spoke 0.05, k_cl 0.1, k_r 0.02 N/mm; surface k 0.05,
// k_r 0.02) fitted by `medspring accuracy` / `medspring calibrate` at E0, nu0, contact radius 8 mm,
// trained on 2 sites at 0.5 N (docs/accuracy.md, run of issue 16; the accuracy.json of that run).
struct Fit {
  double m[4];
};
constexpr Fit kHybridPhantom[2] = {
    {{0.23831820326597328, 0.1771824352978786, 96.77972735120174, 1.1051373509779578}},
    {{0.23685454676252113, 0.17572236805171002, 91.43799678195838, 1.105375645626106}}};
constexpr Fit kHybridReal[2] = {
    {{0.35491958411340885, 0.9139547579908905, 9998.66759995472, 1.0833235643651737}},
    {{0.3542404092316476, 0.911615984909211, 9997.504988816749, 1.0815727244923123}}};
constexpr Fit kSurfacePhantom[2] = {{{861.3479440750025, 1.0058838368481564, 0, 0}},
                                    {{946.417613417323, 0.6716271664556865, 0, 0}}};
constexpr Fit kSurfaceReal[2] = {{{443.54955462106375, 1.5931609978322898, 0, 0}},
                                 {{443.58895802596504, 1.5930361828222563, 0, 0}}};

std::string num(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

}  // namespace

std::vector<std::string> tissue_preset_names() {
  return {"kidney", "aorta"};
}

TissueMaterial tissue_preset(const std::string& name) {
  // Sources: docs/accuracy.md, "Tissue presets" (Ruan et al. 2023; Hemmasizadeh et al. 2012).
  if (name == "kidney") return {10.0, 0.45, "kidney"};
  if (name == "aorta") return {65.0, 0.45, "aorta"};
  throw InvalidInput("unknown tissue preset '" + name + "' (expected one of: kidney, aorta)");
}

void check_tissue(const TissueMaterial& t, const std::string& where) {
  if (!(std::isfinite(t.E_kPa) && t.E_kPa > 0))
    throw InvalidInput(where + ".E_kPa: must be > 0 and finite (got " + num(t.E_kPa) + ")");
  if (!(std::isfinite(t.nu) && t.nu > -1.0 && t.nu < 0.5))
    throw InvalidInput(where + ".nu: must be in (-1, 0.5) (got " + num(t.nu) +
                       (t.nu >= 0.5 ? "; 0.5 is incompressible, which the reference cannot solve)" : ")"));
}

double tissue_scale(const TissueMaterial& t) {
  check_tissue(t, "material");
  const double mu = t.E_kPa / (2.0 * (1.0 + t.nu)), mu0 = kE0 / (2.0 * (1.0 + kNu0));
  return mu / mu0;
}

void apply_tissue(const TissueMaterial& t, TissueOrgan organ, HybridSettings& s) {
  const double f = tissue_scale(t);
  const Fit& fit = (organ == TissueOrgan::Phantom ? kHybridPhantom : kHybridReal)[s.nonlinear ? 1 : 0];
  s.k_surf = 0.05 * fit.m[0] * f;
  s.k_spoke = 0.05 * fit.m[1] * f;
  s.k_cl = 0.1 * fit.m[2] * f;
  s.surface_node.return_k = 0.02 * fit.m[3] * f;
  s.atom_node.return_k = 0.02 * fit.m[3] * f;
}

void apply_tissue(const TissueMaterial& t, TissueOrgan organ, SurfaceBodyParams& p) {
  const double f = tissue_scale(t);
  const bool duffing = p.duffing.mode != DuffingMode::Linear;
  const Fit& fit = (organ == TissueOrgan::Phantom ? kSurfacePhantom : kSurfaceReal)[duffing ? 1 : 0];
  p.k = 0.05 * fit.m[0] * f;
  p.node.return_k = 0.02 * fit.m[1] * f;
}

void apply_tissue(const TissueMaterial& t, SmrmSettings& s) {
  check_tissue(t, "material");
  s.wall.E = t.E_kPa * 1e-3;  // kPa -> MPa = N/mm^2
}

}  // namespace medspring
