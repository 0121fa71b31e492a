// Local deformation per update (ALGORITHMS.md §6.5): patch selection around the contact node plus the
// precomputed patch solve, with the factor cached per contact node (cache_local).
//
//   LocalDeformer local = LocalDeformer::tube(40, 30);  // vessel: 5 x 5 window, Isotropic, k_loc = 0.05
//   MatX3 U;
//   local.compute(contact, F, U);                        // every update while F != 0
//   apply_local_overlay(local.patch(), U, surface);      // overlay.hpp
#pragma once

#include <cstdint>
#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/local/patch.hpp"
#include "medspring/local/solver.hpp"

namespace medspring {

/// Settings of the per-update local deformation. Defaults: ALGORITHMS.md §6 and §9.
struct LocalDeformationSettings {
  PatchOptions patch;       // k_loc (N/mm), tube window half-width, BFS node count
  LocalSettings solver;     // stiffness mode (Isotropic), boundary method (Elimination), k_r, thresholds
  bool cache_local = true;  // §6.5: keep the factor while the contact node stays the same; false = select,
                            // assemble, factor and solve on every call (the paper's path, for timing)
};

/// Selects the patch around a contact node and solves eq. (6), caching the factor per contact node.
class LocalDeformer {
 public:
  /// Structured tube grid of rings x spokes (vessel, §6.1 window). X: #N x 3 positions (mm) used for
  /// the spring directions, needed only for Linearized / AxisProjected (may be empty otherwise);
  /// fixed: model-fixed flags (#N, or empty). Throws InvalidInput for bad sizes or settings.
  static LocalDeformer tube(Index rings, Index spokes, const LocalDeformationSettings& settings = {},
                            MatX3 X = {}, std::vector<std::uint8_t> fixed = {});
  /// General mesh (kidney, §6.1 BFS patch of settings.patch.count nodes). X0: #N x 3 rest positions, mm.
  static LocalDeformer mesh(Adjacency adj, MatX3 X0, const LocalDeformationSettings& settings = {},
                            std::vector<std::uint8_t> fixed = {});

  /// Displacement U (#P x 3, mm) of the patch around `contact` for the force F (N) on it. With
  /// cache_local the selection and factorisation run only when the contact changes, and a repeated
  /// contact costs one solve with no allocation (U already sized). Throws (InvalidInput, SolverError)
  /// only when a new patch is selected and factored: contact outside the mesh, singular patch, ...
  LocalSolveInfo compute(Index contact, const Vec3& F, MatX3& U);

  /// The patch of the last compute (empty before the first).
  const LocalPatch& patch() const { return patch_; }
  const LocalSolver& solver() const { return solver_; }
  const LocalDeformationSettings& settings() const { return settings_; }
  /// Drops the cached factor (e.g. after changing the positions used by Linearized / AxisProjected).
  void invalidate() { cached_ = false; }

 private:
  LocalDeformer() = default;
  void select(Index contact);

  LocalDeformationSettings settings_;
  bool structured_ = false;
  Index rings_ = 0, spokes_ = 0;
  Adjacency adj_;
  MatX3 X_;
  std::vector<std::uint8_t> fixed_;
  LocalPatch patch_;
  LocalSolver solver_;
  Index cached_contact_ = -1;
  bool cached_ = false;  // the solver holds the factor of cached_contact_ (cache_local)
};

}  // namespace medspring
