// Fixtures shared by the volumetric tests (volumetric_test.cpp, volumetric_moduli_test.cpp).
#pragma once

#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "medspring/fem/organ.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/models/volumetric_body.hpp"

namespace medspring::testing {

// An irregular, positively oriented tetrahedron (mm).
inline MatX3 irregular_tet() {
  MatX3 X(4, 3);
  X << 0, 0, 0, 4.2, 0.3, -0.2, 0.7, 3.6, 0.4, 1.1, 0.9, 3.3;
  return X;
}

// A single tetrahedron as a closed surface + mesh (all four nodes on the surface).
inline VolumetricMesh one_tet(const MatX3& X) {
  VolumetricMesh m;
  m.X = X;
  m.T.resize(1, 4);
  m.T << 0, 1, 2, 3;
  m.F.resize(4, 3);
  m.F << 0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2;
  m.surface_nodes = 4;
  return m;
}

// Closed box surface [0, L]^3 with n x n squares per face (two triangles each), outward, shared vertices.
inline SurfaceMesh box_surface(int n, double L) {
  std::map<std::array<long, 3>, Index> id;
  std::vector<Vec3> P;
  std::vector<std::array<Index, 3>> T;
  auto vid = [&](const Vec3& p) {
    const std::array<long, 3> key{std::lround(p(0) * 1e6), std::lround(p(1) * 1e6), std::lround(p(2) * 1e6)};
    auto it = id.find(key);
    if (it != id.end()) return it->second;
    P.push_back(p);
    return id[key] = static_cast<Index>(P.size()) - 1;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          Index q[4];
          for (int c = 0; c < 4; ++c) {
            Vec3 p;
            p(axis) = side * L;
            p(u) = L * (i + (c == 1 || c == 2)) / n;
            p(v) = L * (j + (c >= 2)) / n;
            q[c] = vid(p);
          }
          // (u, v, axis) right-handed: counter-clockwise in (u, v) points along +axis
          if (side == 1) {
            T.push_back({q[0], q[1], q[2]});
            T.push_back({q[0], q[2], q[3]});
          } else {
            T.push_back({q[0], q[2], q[1]});
            T.push_back({q[0], q[3], q[2]});
          }
        }
    }
  SurfaceMesh m;
  m.V.resize(static_cast<Index>(P.size()), 3);
  for (std::size_t i = 0; i < P.size(); ++i) m.V.row(static_cast<Index>(i)) = P[i].transpose();
  m.F.resize(static_cast<Index>(T.size()), 3);
  for (std::size_t f = 0; f < T.size(); ++f)
    for (int k = 0; k < 3; ++k) m.F(static_cast<Index>(f), k) = T[f][static_cast<std::size_t>(k)];
  return m;
}

// x0 squeezed along z by `strain` about the centroid (the supports keep the organ in place: no rigid shift).
inline MatX3 squeezed(const MatX3& x0, double strain) {
  MatX3 x = x0;
  const double cz = x0.col(2).mean();
  x.col(2) = (x0.col(2).array() - cz) * (1.0 - strain) + cz;
  return x;
}

// The supports of the benchmark's kidney (bench/volumetric_bench.cpp): the surface nodes of its bottom 20 %.
inline std::vector<Index> bottom_supports(const SurfaceMesh& s) {
  const double zmin = s.V.col(2).minCoeff(), zmax = s.V.col(2).maxCoeff();
  return fem::support_nodes(s.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
}

// The surface node with the largest z (where the benchmark presses).
inline Index top_node(const SurfaceMesh& s) {
  Index top = 0;
  for (Index i = 0; i < s.V.rows(); ++i)
    if (s.V(i, 2) > s.V(top, 2)) top = i;
  return top;
}
}  // namespace medspring::testing
