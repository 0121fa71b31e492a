// The deformable centerline of the SMRM vessel as a physics Model (ALGORITHMS.md §5.2, §9).
//
//   Model chain = make_chain_model(C0, {.nonlinear = true});   // 40 atoms, ends fixed
//   State s = make_state(chain);  step(chain, s, {.dt = 0.5});
#pragma once

#include <string>

#include "medspring/core/types.hpp"
#include "medspring/physics/model.hpp"

namespace medspring {

/// Parameters of the centerline chain; defaults are the vessel column of ALGORITHMS.md §9.
struct ChainSettings {
  double k = 0.2;             // chain spring stiffness k_cl between atoms i, i+1, N/mm
  double kr = 0.02;           // return-spring stiffness per atom, N/mm (D-2: linear)
  double mass = 0.5;          // per atom, g
  double beta = 0.5;          // mass-proportional damping d = beta m, 1/ms
  bool nonlinear = true;      // Duffing chain springs (eq. 5, D-4); false: k' = 0
  DuffingSettings duffing{};  // k' rule when nonlinear (D-3, Strain by default)
  bool fix_first = true;      // atom 0 fixed (a vessel segment is attached to the vasculature, §1.5)
  bool fix_last = true;       // atom n-1 fixed
  double kb = 0.0;            // optional discrete bending springs (§5.2, not in the paper), N/mm; 0 = off
};

/// Chain of the rest atoms C0 (#n x 3, mm, n >= 2): springs (i, i+1) with L0 = rest distance,
/// return springs, uniform masses, fixed ends, bending terms when kb > 0. Throws InvalidInput naming
/// the atom for non-finite coordinates or coincident neighbours, and for invalid parameters.
Model make_chain_model(const MatX3& C0, const ChainSettings& settings = {},
                       const std::string& name = "centerline");

/// The same chain with a bending stiffness per atom: bending term i (atoms i-1, i, i+1) gets kb[i]
/// (N/mm; entries 0 and n-1 are unused; a zero entry adds no term). settings.kb is ignored. Throws
/// InvalidInput naming the atom for a negative or non-finite entry or a size other than n.
Model make_chain_model(const MatX3& C0, const ChainSettings& settings, const std::string& name,
                       const VecX& kb);

}  // namespace medspring
