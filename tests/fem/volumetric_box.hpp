// A box meshed by fem::box_mesh (Kuhn split) as a VolumetricMesh (corners only, surface nodes first), shared
// by the volumetric tests (volumetric_test.cpp, thin_tet_model_test.cpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include "medspring/fem/tet_mesh.hpp"
#include "medspring/models/volumetric_body.hpp"

namespace medspring::testing {

// Box xs x ys x zs (fem::box_mesh, Kuhn split) as a VolumetricMesh, surface nodes first.
inline VolumetricMesh box(const std::vector<double>& xs, const std::vector<double>& ys,
                          const std::vector<double>& zs) {
  const fem::TetMesh q = fem::box_mesh(xs, ys, zs);
  const Index nn = q.T.leftCols(4).maxCoeff() + 1;
  const double lo[3] = {xs.front(), ys.front(), zs.front()}, hi[3] = {xs.back(), ys.back(), zs.back()};
  auto on_surface = [&](Index i) {
    for (int k = 0; k < 3; ++k)
      if (std::abs(q.X(i, k) - lo[k]) < 1e-9 || std::abs(q.X(i, k) - hi[k]) < 1e-9) return true;
    return false;
  };
  std::vector<Index> order, newid(static_cast<std::size_t>(nn), -1);
  for (Index i = 0; i < nn; ++i)
    if (on_surface(i)) order.push_back(i);
  const Index ns = static_cast<Index>(order.size());
  for (Index i = 0; i < nn; ++i)
    if (!on_surface(i)) order.push_back(i);
  VolumetricMesh m;
  m.X.resize(nn, 3);
  for (Index k = 0; k < nn; ++k) {
    newid[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = k;
    m.X.row(k) = q.X.row(order[static_cast<std::size_t>(k)]);
  }
  m.T.resize(q.num_elements(), 4);
  for (Index e = 0; e < q.num_elements(); ++e)
    for (int k = 0; k < 4; ++k) m.T(e, k) = newid[static_cast<std::size_t>(q.T(e, k))];
  const fem::MatX6i B = fem::boundary_faces(q);
  m.F.resize(B.rows(), 3);
  for (Index f = 0; f < B.rows(); ++f)
    for (int k = 0; k < 3; ++k) m.F(f, k) = newid[static_cast<std::size_t>(B(f, k))];
  m.surface_nodes = ns;
  return m;
}

}  // namespace medspring::testing
