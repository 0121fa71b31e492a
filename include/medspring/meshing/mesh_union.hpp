// Boolean union of closed triangle surfaces (CGAL corefinement) and the self-intersection check, for the
// watertight junction surface of a vessel tree (issue 17, docs/vessels.md). CGAL stays in
// src/meshing/mesh_union.cpp (its own translation unit: corefinement is heavy to compile).
//
//   SurfaceMesh u = union_of_closed_meshes({tube_a, tube_b, ball}, "vessel tree");
//   self_intersections(u) == 0;
#pragma once

#include <string>
#include <vector>

#include "medspring/geometry/surface_mesh.hpp"

namespace medspring {

/// The boundary of the union of the solids bounded by `parts`: every part must be valid, closed,
/// manifold, consistently oriented (either orientation; flipped to outward) and free of
/// self-intersections. The result is closed, manifold and outward-oriented (signed volume > 0).
/// Throws InvalidInput naming `what` and the part at fault, or the step of the union that failed.
SurfaceMesh union_of_closed_meshes(const std::vector<SurfaceMesh>& parts, const std::string& what);

/// Pairs of triangles of the mesh that intersect (other than at a shared edge or vertex); 0 = none.
/// The mesh must be valid and manifold (InvalidInput otherwise).
Index self_intersections(const SurfaceMesh& mesh, const std::string& what = "surface");

/// The faces in at least one intersecting pair (ascending, each once); empty = none.
std::vector<Index> self_intersecting_faces(const SurfaceMesh& mesh, const std::string& what = "surface");

}  // namespace medspring
