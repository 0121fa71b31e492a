// The volumetric spring organ from a closed surface (issue 23, docs/volumetric.md): TetGen meshes the
// inside with the surface kept as it is (-pqY), aiming at a node count, and the linear tetrahedra become a
// VolumetricBody (models/volumetric_body.hpp) whose first nodes are the surface's vertices.
#pragma once

#include "medspring/fem/tet_mesh.hpp"
#include "medspring/models/volumetric_body.hpp"

namespace medspring::fem {

struct VolumetricMeshSettings {
  Index target_nodes = 2000;  // total nodes aimed at (surface + interior); at least the surface's
  double radius_edge = 1.6;   // TetGen quality bound
  int attempts = 5;           // TetGen runs to approach target_nodes (volume bound rescaled each time)
};

/// Tetrahedralises the closed, outward surface keeping its vertices and faces (TetGen -pqY) with the
/// volume bound that brings the node count nearest target_nodes (within the attempts). The surface
/// vertices are nodes [0, #V). Throws InvalidInput for an open/non-manifold/inward surface or a target
/// below the surface's vertex count, SolverError when TetGen fails.
VolumetricMesh volumetric_mesh(const SurfaceMesh& surface, const VolumetricMeshSettings& settings = {});

}  // namespace medspring::fem
