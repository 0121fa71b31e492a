// Volumetric meshes for the FEM reference (docs/accuracy.md): quadratic tetrahedra (CalculiX C3D10),
// from a structured box or from a closed organ surface (TetGen run as a subprocess).
//
// Units: mm. Node order of a C3D10 element (CalculiX / Abaqus): corners 0-3 with a positive volume
// ((x1-x0) x (x2-x0)) . (x3-x0) > 0, then the mid-edge nodes 01 12 20 03 13 23.
#pragma once

#include <string>
#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/geometry/surface_mesh.hpp"

namespace medspring::fem {

using MatX4i = Eigen::Matrix<Index, Eigen::Dynamic, 4, Eigen::RowMajor>;
using MatX10i = Eigen::Matrix<Index, Eigen::Dynamic, 10, Eigen::RowMajor>;
using MatX6i = Eigen::Matrix<Index, Eigen::Dynamic, 6, Eigen::RowMajor>;

/// A quadratic tetrahedral mesh (mm).
struct TetMesh {
  MatX3 X;    // node positions (#N x 3), mm
  MatX10i T;  // elements (#E x 10), 0-based, C3D10 order
  Index num_nodes() const { return static_cast<Index>(X.rows()); }
  Index num_elements() const { return static_cast<Index>(T.rows()); }
};

/// Quadratic mesh from linear tetrahedra: corners kept (reoriented to a positive volume), one node per
/// unique edge at its midpoint. Throws InvalidInput for an index out of range or a flat element.
TetMesh make_quadratic(const MatX3& X, const MatX4i& T4);

/// Structured box [xs.front, xs.back] x [ys...] x [zs...]: every cell of the grid split into 6
/// tetrahedra (Kuhn split, conforming), then made quadratic. The coordinate lists must be strictly
/// increasing with >= 2 entries each (graded grids allowed).
TetMesh box_mesh(const std::vector<double>& xs, const std::vector<double>& ys, const std::vector<double>& zs);

/// n + 1 coordinates from a to b, uniform (grading 1) or geometric with cell ratio `grading` between
/// consecutive cells (grading > 1: cells grow from a towards b).
std::vector<double> graded(double a, double b, int n, double grading = 1.0);

/// Settings of surface meshing with TetGen.
struct TetgenSettings {
  double max_volume = 0.0;   // mm^3, 0 = no volume constraint (-a)
  double radius_edge = 1.6;  // quality bound (-q); 0 = none (fewest elements)
  /// -Y: no Steiner points on the surface (its vertices stay the first nodes); the volumetric kind.
  bool preserve_surface = false;
  std::string executable = "";  // default: $MEDSPRING_TETGEN, then `tetgen` on PATH
  // -m: TetGen's mesh sizing function (manual §4.2.4, files .mtr and .b.node/.b.ele/.b.mtr, §5.2.8). Empty
  // = none. vertex_sizes (one per surface vertex, mm > 0) bound the circumradius of the tetrahedra at that
  // vertex and keep quality-driven Steiner points out of a ball of that radius around it; with a background
  // mesh (background_X / background_T, linear tetrahedra covering the organ, background_sizes per node)
  // the sizes of the points TetGen inserts are interpolated from it, else from the tetrahedron they split.
  std::vector<double> vertex_sizes{};
  MatX3 background_X{};
  MatX4i background_T{};
  std::vector<double> background_sizes{};
};

/// Tetrahedralises the inside of a closed, manifold, outward-oriented surface with TetGen (`tetgen -pq`,
/// Debian package `tetgen`) in a temporary folder, then makes the mesh quadratic. An open, non-manifold
/// or inward-oriented surface is refused (InvalidInput naming the defect) before anything runs; a
/// missing tetgen or a failed run is an Error with the tool's last output lines.
TetMesh tet_mesh_from_surface(const SurfaceMesh& surface, const TetgenSettings& settings = {});

/// The boundary of a tetrahedral mesh: faces used by one element, as 6-node triangles (corners a b c,
/// then the mid-edge nodes ab bc ca), oriented outwards.
MatX6i boundary_faces(const TetMesh& mesh);

/// Total volume (mm^3) of the mesh, from the corner nodes (exact for straight-sided elements).
double mesh_volume(const TetMesh& mesh);

/// Sorted list of the nodes on the boundary (corner and mid-edge).
std::vector<Index> boundary_nodes(const TetMesh& mesh);

/// The largest strains of a displacement field (issue 23, large strain; docs/accuracy.md): per element the
/// deformation gradient of its corner nodes (the element's mean for a curved C3D10 field, exact for an
/// affine one), its principal stretches (eigenvalues of sqrt(F^T F)), and over the mesh the smallest and
/// the largest. Rigid motions give 0 at any size.
struct PeakStrain {
  double compressive = 0;  // 1 - the smallest principal stretch (0.3 = 30 % shortening)
  double tensile = 0;      // the largest principal stretch - 1
  Index compressive_element = -1, tensile_element = -1;
};
/// InvalidInput for a displacement whose shape is not #N x 3 or that is not finite.
PeakStrain peak_strain(const TetMesh& mesh, const MatX3& u);

}  // namespace medspring::fem
