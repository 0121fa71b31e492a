// The local deformation of eq. (6) under a distributed load (ALGORITHMS.md §6): the patch is the loaded nodes
// plus rings of their neighbours, and K U = F takes every loaded node's own force instead of the whole force
// on the contact node (LocalDeformer::compute). Used by the accuracy pipeline's site family for the
// volumetric kind (docs/accuracy-calibration.md, "The local overlay as a site family").
//
//   const LocalPatch p = loaded_nodes_patch(adj, {3, 4, 7}, 4, 0.05);  // loaded nodes + one ring, fixed
//   MatX3 U;
//   solve_local_distributed(p, F_patch, U);                            // F_patch: #P x 3, N
#pragma once

#include <cstdint>
#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/local/patch.hpp"
#include "medspring/local/solver.hpp"

namespace medspring {

/// The patch of a distributed load: the loaded nodes (`loaded`, global indices, any order, no duplicates)
/// followed by the nodes within `rings` edge hops of them, in (hop distance, index) order; `contact` must be
/// a loaded node. As make_local_patch, every spring has stiffness k_loc (N/mm) and a node with a neighbour
/// outside the patch is fixed (D-15), so for rings >= 1 the outer ring is the patch's boundary and the
/// loaded nodes are free unless model-fixed (`fixed`, #N flags or empty). Throws InvalidInput for an empty
/// or out-of-range `loaded`, a contact not in it, rings < 0, and the errors of make_local_patch.
LocalPatch loaded_nodes_patch(const Adjacency& adj, const std::vector<Index>& loaded, Index contact,
                              double k_loc, const std::vector<std::uint8_t>& fixed = {}, int rings = 1);

/// The displacement U (#P x 3, mm, the patch's order) of K U = F (§6.2, eq. 6) with a force on every patch
/// node: F is #P x 3 (N). The fixed nodes keep U = 0 and their forces are dropped (returned: the force
/// dropped, so that the caller can check that the whole load reached free nodes). K is
/// local_stiffness_matrix (Isotropic, Linearized or AxisProjected; PaperLiteral is refused: it is not
/// symmetric), solved over the free nodes by dense LDLT. A trivial patch (no free node) gives U = 0.
/// Throws InvalidInput for a force of the wrong size or non-finite, SolverError when the free block is
/// singular (a pivot <= settings.pivot_tolerance x max|K|).
Vec3 solve_local_distributed(const LocalPatch& patch, const MatX3& F, MatX3& U, const MatX3& X = MatX3(),
                             const LocalSettings& settings = {});

}  // namespace medspring
