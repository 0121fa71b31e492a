// Checks that a surface can be meshed (closed, manifold) and the explicit repair for open meshes.
#pragma once

#include <string>

#include "medspring/geometry/surface_mesh.hpp"

namespace medspring {

/// Topology counts that decide whether a surface is usable as an organ boundary.
struct ClosedManifoldReport {
  MeshReport mesh;                 // validate_mesh
  Index holes = 0;                 // boundary loops
  Index nonmanifold_vertices = 0;  // vertices whose triangle fan splits in two or more
  bool ok() const {
    return mesh.valid() && mesh.closed() && nonmanifold_vertices == 0 && mesh.inconsistent_edges == 0;
  }
};

/// Counts boundary loops, non-manifold edges and vertices, without modifying the mesh.
ClosedManifoldReport check_closed_manifold(const SurfaceMesh& mesh);

/// Throws InvalidInput unless the mesh is valid, closed, edge- and vertex-manifold and consistently
/// oriented. The one-line message starts with `what`, counts the offending edges/vertices and says
/// what to do, e.g. "kidney.obj: surface is open: 14 boundary edges in 2 holes; close holes of up to
/// N edges with close_small_holes (CLI option --close-holes N)". Returns the report otherwise.
ClosedManifoldReport require_closed_manifold(const SurfaceMesh& mesh, const std::string& what);

struct HoleFillReport {
  Index holes_found = 0;    // boundary loops before filling
  Index holes_filled = 0;   // loops of at most max_hole_edges edges, triangulated, refined and faired
  Index holes_skipped = 0;  // larger loops, left open
  Index faces_added = 0, vertices_added = 0;
};

/// Closes every hole (boundary loop) with at most max_hole_edges edges: CGAL
/// triangulate_refine_and_fair_hole (minimum-area triangulation, refined to the local edge length,
/// faired to the surrounding curvature). Larger holes are left open and counted. The mesh must be
/// valid and edge-manifold (InvalidInput otherwise); max_hole_edges must be >= 3.
HoleFillReport close_small_holes(SurfaceMesh& mesh, Index max_hole_edges = 64);

}  // namespace medspring
