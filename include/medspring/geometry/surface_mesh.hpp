// Triangle surface meshes: storage, validation, welding, normals.
#pragma once

#include <string>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

/// A triangle surface mesh in millimetres.
struct SurfaceMesh {
  MatX3 V;   // vertex positions (#V x 3), mm
  MatX3i F;  // triangles (#F x 3), 0-based vertex indices, counter-clockwise seen from outside

  Index num_vertices() const { return static_cast<Index>(V.rows()); }
  Index num_faces() const { return static_cast<Index>(F.rows()); }
};

/// What validate_mesh found. Counts are exact; the *_example fields name the first offender.
struct MeshReport {
  Index vertices = 0, faces = 0, edges = 0;
  Index nonfinite_vertices = 0;    // rows of V with NaN/Inf
  Index bad_indices = 0;           // faces with an index outside [0, #V)
  Index degenerate_faces = 0;      // repeated index or zero area (area < 1e-12 * bbox_diag^2)
  Index duplicate_faces = 0;       // same vertex set as an earlier face
  Index boundary_edges = 0;        // edges with one incident face (open surface)
  Index nonmanifold_edges = 0;     // edges with more than two incident faces
  Index inconsistent_edges = 0;    // interior edges traversed twice in the same direction
  Index isolated_vertices = 0;     // vertices in no face
  Index components = 0;            // connected components (by faces)
  Index euler_characteristic = 0;  // V - E + F (2 for a closed genus-0 surface)
  double bbox_diagonal = 0.0;      // mm
  double signed_volume = 0.0;      // mm^3, > 0 when normals point outward (closed meshes)
  std::string first_problem;       // e.g. "face 17: index 5002 out of range [0, 5002)"

  bool closed() const { return boundary_edges == 0; }
  bool manifold() const { return nonmanifold_edges == 0; }
  /// True when the mesh is usable for simulation: finite, indices valid, no degenerate,
  /// duplicate or non-manifold faces. Open boundaries are allowed (reported).
  bool valid() const {
    return nonfinite_vertices == 0 && bad_indices == 0 && degenerate_faces == 0 && duplicate_faces == 0 &&
           nonmanifold_edges == 0 && vertices > 0 && faces > 0;
  }
  /// One line summary, e.g. "5002 vertices, 10000 faces, closed, manifold, 1 component".
  std::string summary() const;
};

/// Checks a mesh without modifying it.
MeshReport validate_mesh(const SurfaceMesh& mesh);

struct MeshRequirements {
  bool closed = false;   // reject open boundaries
  bool manifold = true;  // reject non-manifold edges
};

/// Throws InvalidInput("<what>: <first problem>") unless the mesh is valid (and closed/manifold if
/// required). Returns the report otherwise.
MeshReport require_valid_mesh(const SurfaceMesh& mesh, const std::string& what,
                              const MeshRequirements& req = {});

/// Merges vertices closer than tol (default: 1e-9 x bounding-box diagonal), drops faces that
/// become degenerate, and removes unreferenced vertices. Returns the number of merged vertices.
/// If old_to_new is given it receives the new index of every old vertex (-1 if removed).
Index weld_vertices(SurfaceMesh& mesh, double tol = -1.0, std::vector<Index>* old_to_new = nullptr);

/// Area-weighted vertex normals (unit; zero for isolated vertices), written into N (#V x 3).
void vertex_normals(const MatX3& V, const MatX3i& F, MatX3& N);
/// Unit face normals (#F x 3).
MatX3 face_normals(const MatX3& V, const MatX3i& F);
/// Signed volume (divergence theorem), mm^3.
double signed_volume(const MatX3& V, const MatX3i& F);
/// Total area, mm^2.
double surface_area(const MatX3& V, const MatX3i& F);
/// Axis-aligned bounds as a 2 x 3 matrix (min row, max row).
Eigen::Matrix<double, 2, 3> bounds(const MatX3& V);

}  // namespace medspring
