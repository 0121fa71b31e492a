// Node orderings for cache locality (issue 15): a reverse Cuthill-McKee order of a mesh's vertices, and
// the permutation of a mesh (and of node lists given in its numbering) into such an order.
//
//   const std::vector<Index> order = locality_order(mesh);   // order[new] = old
//   const SurfaceMesh m = permute_vertices(mesh, order);      // vertex order[k] of mesh is vertex k of m
//
// A spring pass reads the two end nodes of every spring; with the nodes numbered so that neighbours
// have close numbers (small bandwidth) those reads hit the cache. Builders that generate their meshes
// (the balloon surface of the kidney pipeline) emit them in this order; a large user mesh is simulated in
// this order by SurfaceBody and HybridKidney behind a surface <-> DOF map (users keep their numbering).
#pragma once

#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/geometry/topology.hpp"

namespace medspring {

/// Models built from a user's mesh (SurfaceBody, HybridKidney) renumber it only from this many surface
/// nodes on (smaller models fit in the cache anyway), and only when its bandwidth is more than twice that
/// of its locality_order.
inline constexpr Index kLocalityReorderMinNodes = 20000;

/// Reverse Cuthill-McKee order of a graph: order[new] = old. Each connected component is numbered from
/// a pseudo-peripheral node (George-Liu), neighbours by increasing degree (ties: lower index); the
/// whole sequence is then reversed. Deterministic; O(E log d). Isolated nodes are kept (own component).
std::vector<Index> rcm_order(const Adjacency& adj);

/// rcm_order of a mesh's vertex graph (vertices in no face are placed too).
std::vector<Index> locality_order(const SurfaceMesh& mesh);

/// The inverse permutation: inverse[order[k]] = k (old -> new). Throws InvalidInput if `order` is not a
/// permutation of 0..n-1.
std::vector<Index> inverse_permutation(const std::vector<Index>& order);

/// The mesh with its vertices renumbered: new vertex k is old vertex order[k]; faces keep their order
/// and orientation, with their indices mapped. Throws InvalidInput if `order` is not a permutation of
/// the mesh's vertices.
SurfaceMesh permute_vertices(const SurfaceMesh& mesh, const std::vector<Index>& order);

/// Largest |i - j| over the edges of a mesh (its bandwidth: small = neighbours stored close together).
Index mesh_bandwidth(const SurfaceMesh& mesh);

}  // namespace medspring
