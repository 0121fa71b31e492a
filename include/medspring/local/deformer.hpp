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
  /// Selects and factors the patch of `contact` (found in the cache with cache_local) without solving:
  /// set-up points (a new load or tool node) call it so that the update loop finds the factor ready.
  /// Throws like compute.
  void prepare(Index contact);

  /// The patch of the last compute (empty before the first).
  const LocalPatch& patch() const;
  const LocalSolver& solver() const;
  const LocalDeformationSettings& settings() const { return settings_; }
  /// Drops the cached factors (e.g. after changing the positions used by Linearized / AxisProjected).
  void invalidate() { cache_.clear(); }

  /// Factored patches kept with cache_local, the least recently used replaced: a contact that moves
  /// among up to this many nodes (a tool's contact centre wandering as the tissue gives way, loads
  /// taking turns) costs one solve and no allocation. A tube's 5 x 5 patch factor is ~50 kB.
  static constexpr std::size_t kCachedPatches = 32;

 private:
  LocalDeformer() { cache_.reserve(kCachedPatches); }
  /// The cache slot holding the factor of `contact`, selected and factored when missing.
  std::size_t select(Index contact);

  struct Entry {
    Index contact = -1;  // -1: not a valid factor
    LocalPatch patch;
    LocalSolver solver;
    std::uint64_t used = 0;  // last use, for least-recently-used replacement
  };
  LocalDeformationSettings settings_;
  bool structured_ = false;
  Index rings_ = 0, spokes_ = 0;
  Adjacency adj_;
  MatX3 X_;
  std::vector<std::uint8_t> fixed_;
  std::vector<Entry> cache_;  // at most kCachedPatches (one without cache_local)
  std::size_t active_ = 0;    // the entry of the last compute
  std::uint64_t clock_ = 0;
};

}  // namespace medspring
