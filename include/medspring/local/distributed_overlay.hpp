// The local overlay of a distributed load at run time (ALGORITHMS.md §6, docs/local-deformation.md): the
// patch of the loaded nodes plus one ring of neighbours (the ring fixed, D-15), K U = F with every loaded
// node's own force, Isotropic (K = L (x) I3, so L_ff U = F solves the three axes at once). The same problem
// as solve_local_distributed on loaded_nodes_patch(adj, loaded, ., k_loc, fixed, 1) - the calibrated disk
// overlay of the volumetric kind (fem/local_site.hpp) - set up without allocating: the workspace holds a
// patch capacity and grows (allocates) only when a larger patch than any before arrives.
//
//   DistributedOverlay d(adj, k_loc, fixed);            // workspace for 128 patch nodes
//   d.reserve(d.patch_size_of(loaded));                  // a set-up point: the patch expected
//   if (d.prepare(loaded)) d.solve(F);                   // per update: factored only when `loaded` changed
//   for (Index a = 0; a < d.size(); ++a) surface.row(d.nodes()[a]) += d.displacement().row(a);
#pragma once

#include <cstdint>
#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/geometry/topology.hpp"

namespace medspring {

class DistributedOverlay {
 public:
  DistributedOverlay() = default;
  /// adj: the surface's adjacency (#S nodes); k_loc: every patch spring's stiffness (N/mm, > 0); fixed:
  /// model-fixed flags (#S, nonzero = fixed; empty = none); capacity: the patch nodes the workspace holds at
  /// first. Throws InvalidInput for k_loc <= 0 or not finite, flags of the wrong size, capacity < 1.
  DistributedOverlay(Adjacency adj, double k_loc, std::vector<std::uint8_t> fixed = {}, Index capacity = 128);

  /// The number of nodes of the patch of `loaded` (the loaded nodes and their neighbours), without
  /// allocating. Throws InvalidInput for a node out of range.
  Index patch_size_of(const std::vector<Index>& loaded);
  /// Sizes the workspace for patches of up to `nodes` nodes: when that is above the capacity, allocates
  /// for max(nodes, 2 x capacity) (a set-up point); nothing otherwise.
  void reserve(Index nodes);
  Index capacity() const { return capacity_; }
  /// Times prepare had to grow the workspace (a patch above the capacity; each time an allocation).
  Index growths() const { return growths_; }

  /// Selects the patch of `loaded` (surface nodes, any order; duplicates counted once; empty = no patch) and
  /// factors L_ff (dense Cholesky over the free nodes), unless `loaded` equals the last call's (then it only
  /// returns the last result). The order: the loaded nodes as given, then the ring in index order (as
  /// loaded_nodes_patch). Returns false - every displacement then zero - when no node is free or the free
  /// block is singular (a pivot <= 1e-12 x the largest diagonal: free nodes not connected to a fixed one).
  /// Allocates only when the patch is above the capacity (growths()). Throws InvalidInput for a node out
  /// of range.
  bool prepare(const std::vector<Index>& loaded);
  /// The displacement of every patch node (displacement(), mm) for the forces F (#S x 3, N, global rows:
  /// the rows of the patch's free nodes are read, those of fixed nodes dropped) on the last prepared patch.
  /// Never allocates; zero after a prepare that returned false.
  void solve(const MatX3& F);

  /// Patch nodes P of the last prepare and their global indices (#P).
  Index size() const { return P_; }
  const std::vector<Index>& nodes() const { return nodes_; }
  /// 1 = fixed patch node (#P, the patch's order).
  const std::vector<std::uint8_t>& fixed() const { return fixed_; }
  Index num_free() const { return nf_; }
  /// U (#P x 3, mm) of the last solve, in the patch's order.
  Eigen::Ref<const MatX3> displacement() const { return U_.topRows(P_); }
  double k_loc() const { return k_loc_; }

 private:
  bool factor();

  Adjacency adj_;
  double k_loc_ = 0;
  std::vector<std::uint8_t> model_fixed_;  // #S or empty
  Index capacity_ = 0, growths_ = 0;
  std::vector<Index> mark_;   // #S: local index of a patch node during selection, -1 otherwise
  std::vector<Index> last_;   // the loaded nodes of the last prepare
  std::vector<Index> nodes_;  // #P global indices (capacity_)
  std::vector<std::uint8_t> fixed_;
  std::vector<Index> free_;  // #F local indices of the free nodes, ascending
  std::vector<double> L_;    // #F x #F, row-major: L_ff, then its Cholesky factor (lower triangle)
  std::vector<double> rhs_;  // #F x 3 scratch of solve
  MatX3 U_;                  // capacity_ x 3, the first P_ rows used
  Index P_ = 0, nf_ = 0;
  bool ok_ = false, prepared_ = false;
};

}  // namespace medspring
