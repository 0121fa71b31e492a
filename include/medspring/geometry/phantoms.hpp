// Procedural phantoms of ALGORITHMS.md §1.1 and §8.0.
#pragma once

#include "medspring/geometry/surface_mesh.hpp"

namespace medspring {

/// Triangles of the structured tube grid of n rings x M spokes (node i*M + j), ALGORITHMS.md §1.1:
/// [(i,j),(i,j+1),(i+1,j+1)] and [(i,j),(i+1,j+1),(i+1,j)]. 2 M (n-1) triangles.
MatX3i tube_grid_faces(Index rings, Index spokes);

/// A straight circular tube along +x: `rings` rings spaced `spacing` mm, `spokes` nodes per ring on
/// radius `radius` mm, spoke j at angle 2 pi j / M counter-clockwise about +x starting from +y... The
/// structured vessel surface of the paper is tube(40, 30, 2.5, 3.0): 1200 nodes, 3540 springs.
/// Open at both ends (the end rings are the boundary).
SurfaceMesh tube(Index rings = 40, Index spokes = 30, double spacing = 2.5, double radius = 3.0);

/// The 458-node latitude-longitude kidney phantom (ALGORITHMS.md §1.1): ellipsoid (55, 28, 18) mm
/// bent with radius 90 mm; 1368 edges, 912 triangles, closed, outward-oriented.
SurfaceMesh kidney_phantom();

/// Parameters of the kidney phantom, exposed for the hybrid model's phantom atoms (§4.1).
struct KidneyPhantomShape {
  double a = 55.0, b = 28.0, c = 18.0;  // ellipsoid semi-axes, mm
  double bend_radius = 90.0;            // mm
};
/// The bend map B(q) of §1.1 (concave side towards +y).
Vec3 kidney_bend(const Vec3& q, double bend_radius = 90.0);

/// A closed icosphere of the given radius (mm) after `subdivisions` Loop-style midpoint subdivisions
/// (10 * 4^s + 2 vertices), outward-oriented.
SurfaceMesh icosphere(int subdivisions = 2, double radius = 10.0);

}  // namespace medspring
