// The volumetric spring organ from a closed surface (issue 23, docs/volumetric.md): TetGen meshes the
// inside with the surface kept as it is (-pqY), aiming at a node count, and the linear tetrahedra become a
// VolumetricBody (models/volumetric_body.hpp) whose first nodes are the surface's vertices.
#pragma once

#include <string>

#include "medspring/fem/tet_mesh.hpp"
#include "medspring/models/volumetric_body.hpp"

namespace medspring::fem {

// How the interior is sized: MeshSizing (models/volumetric_body.hpp, a scene parameter too).
using ::medspring::MeshSizing;
using ::medspring::parse_mesh_sizing;

struct VolumetricMeshSettings {
  Index target_nodes = 2000;  // total nodes aimed at (surface + interior); at least the surface's
  double radius_edge = 1.6;   // TetGen quality bound
  int attempts = 5;           // TetGen runs to approach target_nodes (volume bound rescaled each time)
  // midpoint subdivisions of the surface before meshing (0..3; subdivide_midpoint, organ.hpp): the same
  // polyhedron with 4^k times the faces, its first #V vertices the given ones, so a load spread over a
  // small disk (a tool tip, the accuracy tables' contact disk) falls on many nodes instead of a handful
  // (docs/accuracy-nonlinear.md, "The load site"). target_nodes counts the refined surface's vertices.
  int surface_subdivisions = 0;
  MeshSizing sizing = MeshSizing::Volume;
  double grading = 0.3;  // sizing surface: size growth per mm of depth (mm/mm, >= 0)
};

/// Tetrahedralises the closed, outward surface keeping its vertices and faces (TetGen -pqY) with the
/// volume bound (sizing volume) or the scale of the surface-sized field (sizing surface, at least 1) that
/// brings the node count nearest target_nodes (within the attempts). The surface
/// vertices are nodes [0, #V); with surface_subdivisions k > 0 the model's surface is the subdivided one
/// (VolumetricMesh::F, surface_nodes), whose first #V vertices are still the given ones. Throws InvalidInput
/// for an open/non-manifold/inward surface or a target below the surface's vertex count, SolverError when
/// TetGen fails.
VolumetricMesh volumetric_mesh(const SurfaceMesh& surface, const VolumetricMeshSettings& settings = {});

}  // namespace medspring::fem
