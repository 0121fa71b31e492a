// Shared meshes and helpers for the local-deformation tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/local/patch.hpp"

namespace medspring::testing {

inline Adjacency mesh_adjacency(const SurfaceMesh& m) {
  return vertex_adjacency(m.num_vertices(), unique_edges(m.F));
}

/// Local index of window offset (di, dj) in a 5 x 5 (half_width 2) window around an interior contact.
inline Index window_index(Index di, Index dj) {
  return (di + 2) * 5 + (dj + 2);
}

/// A flat G x G grid in the z = 0 plane with the tube-grid triangulation (diagonal (i,j)-(i+1,j+1)),
/// node i*G + j at (h i + 0.1 sin j, h j + 0.1 cos i, 0): slightly irregular so spring directions vary.
inline SurfaceMesh flat_grid(Index G, double h = 1.0) {
  SurfaceMesh m;
  m.V.resize(G * G, 3);
  for (Index i = 0; i < G; ++i)
    for (Index j = 0; j < G; ++j)
      m.V.row(i * G + j) << h * i + 0.1 * std::sin(double(j)), h * j + 0.1 * std::cos(double(i)), 0.0;
  m.F.resize(2 * (G - 1) * (G - 1), 3);
  Index f = 0;
  for (Index i = 0; i + 1 < G; ++i)
    for (Index j = 0; j + 1 < G; ++j) {
      m.F.row(f++) << i * G + j, i * G + j + 1, (i + 1) * G + j + 1;
      m.F.row(f++) << i * G + j, (i + 1) * G + j + 1, (i + 1) * G + j;
    }
  return m;
}

/// Border flags (1 on the outer rows and columns) of a G x G grid.
inline std::vector<std::uint8_t> grid_border(Index G) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(G * G), 0);
  for (Index i = 0; i < G; ++i)
    for (Index j = 0; j < G; ++j) b[i * G + j] = (i == 0 || j == 0 || i == G - 1 || j == G - 1);
  return b;
}

/// Positions of the rings x spokes tube grid laid flat in the z = 0 plane (node (i, j) at (i, j, 0)):
/// a patch "with all the points on a plane" (Fig. 8B).
inline MatX3 flat_tube_positions(Index rings, Index spokes) {
  MatX3 X(rings * spokes, 3);
  for (Index i = 0; i < rings; ++i)
    for (Index j = 0; j < spokes; ++j) X.row(i * spokes + j) << double(i), double(j), 0.0;
  return X;
}

}  // namespace medspring::testing
