// Patch selection for the local deformation of eq. (6): ALGORITHMS.md §6.1 and D-15.
//
//   const LocalPatch p = structured_window_patch(40, 30, GridNode{20, 7});   // 5 x 5 window, 9 free
//   const LocalPatch q = bfs_local_patch(adj, X0, 223, {.k_loc = 0.05});     // 25-node BFS patch
#pragma once

#include <cstdint>
#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/geometry/topology.hpp"

namespace medspring {

/// A node of the structured tube grid (§1.1): ring i in [0, rings), spoke j in [0, spokes) (cyclic);
/// its global index is i * spokes + j.
struct GridNode {
  Index ring = 0;
  Index spoke = 0;
};

/// The nodes, springs and boundary of one local patch (§6.1).
struct LocalPatch {
  std::vector<Index> nodes;         // #P global node indices, in selection order (see the selectors)
  std::vector<std::uint8_t> fixed;  // #P, 1 = fixed patch node (D-15), 0 = free
  std::vector<Index> free_nodes;    // #F local indices of the free nodes, ascending
  MatX2i springs;                   // #S x 2 local end indices (a, b), ordered so nodes[a] < nodes[b]
  VecX k;                           // #S stiffness k_loc of each patch spring, N/mm
  Index contact = -1;               // global index of the contact node c
  Index contact_local = -1;         // local index of c (nodes[contact_local] == contact)

  Index size() const { return static_cast<Index>(nodes.size()); }
  Index num_free() const { return static_cast<Index>(free_nodes.size()); }
  Index num_springs() const { return static_cast<Index>(springs.rows()); }
  /// True when U = 0 for every force: the contact node is fixed or no node is free (§6.1).
  bool trivial() const { return free_nodes.empty() || contact_local < 0 || fixed[contact_local] != 0; }
};

/// Options of the patch selectors. Defaults: ALGORITHMS.md §6.1 and §9.
struct PatchOptions {
  double k_loc = 0.05;   // N/mm, stiffness of every patch spring (§6.2: vessel 0.05, kidney k_surf)
  Index half_width = 2;  // structured window: |i' - i_c| <= half_width, |delta spoke| <= half_width (5 x 5)
  Index count = 25;      // BFS patch: N_local, the number of patch nodes
};

/// Builds a patch from an explicit node list (any order; duplicates rejected) on a mesh with adjacency
/// `adj` (#N nodes): the patch springs are the mesh edges with both ends in the patch, each with
/// stiffness k_loc; a node is fixed when it has a mesh neighbour outside the patch or is model-fixed
/// (D-15). `fixed`: optional model-fixed flags (#N, nonzero = fixed; empty = none).
/// Throws InvalidInput for a node or contact outside the mesh, a contact not in `nodes`, a duplicate
/// node, k_loc <= 0 or a `fixed` array of the wrong size.
LocalPatch make_local_patch(const Adjacency& adj, const std::vector<Index>& nodes, Index contact,
                            double k_loc, const std::vector<std::uint8_t>& fixed = {});

/// The structured-tube window of §6.1 around the contact node on the tube grid of rings x spokes
/// (tube_grid_faces): rings i' with |i' - i_c| <= half_width clamped to [0, rings - 1], spokes
/// j_c + delta mod spokes with |delta| <= half_width. Nodes are ordered by (ring offset, spoke
/// offset), so for an interior contact and half_width = 2 the contact is local node 12 and the node at
/// window offset (di, dj) is local node (di + 2) * 5 + (dj + 2). Computed from index arithmetic (no
/// mesh adjacency needed). Throws InvalidInput for a contact outside the grid, half_width < 0, a
/// window wider than the ring (spokes < 2 half_width + 1) or the other errors of make_local_patch.
LocalPatch structured_window_patch(Index rings, Index spokes, GridNode contact,
                                   const PatchOptions& options = {},
                                   const std::vector<std::uint8_t>& fixed = {});
/// The same with the contact given by its global node index i * spokes + j.
LocalPatch structured_window_patch(Index rings, Index spokes, Index contact, const PatchOptions& options = {},
                                   const std::vector<std::uint8_t>& fixed = {});

/// The general-mesh patch of §6.1 (kidney): the first options.count nodes in BFS order from the
/// contact, ordered by (ring distance, rest Euclidean distance to c, index) (bfs_patch), so the
/// contact is local node 0. X0: #N x 3 rest positions, mm. Throws InvalidInput for a contact outside
/// the mesh, a patch larger than the mesh (or than the contact's connected component), and the other
/// errors of make_local_patch.
LocalPatch bfs_local_patch(const Adjacency& adj, const MatX3& X0, Index contact,
                           const PatchOptions& options = {}, const std::vector<std::uint8_t>& fixed = {});

}  // namespace medspring
