// Private to the meshing layer: the CGAL surface mesh type and its conversions from and to the engine's
// SurfaceMesh, written once for cgal_support.hpp (remeshing, distances, the balloon) and mesh_union.cpp.
// Light on purpose: only Surface_mesh and the kernel, so mesh_union.cpp stays a small translation unit.
#pragma once

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <string>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/geometry/surface_mesh.hpp"

namespace medspring::cgal_detail {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using VD = Mesh::Vertex_index;
using FD = Mesh::Face_index;

inline Point to_point(const MatX3& V, Index i) {
  return {V(i, 0), V(i, 1), V(i, 2)};
}

/// A Surface_mesh from an engine mesh (which must be valid and manifold; InvalidInput otherwise).
inline Mesh to_cgal(const SurfaceMesh& s, const std::string& what) {
  Mesh m;
  m.reserve(static_cast<Mesh::size_type>(s.num_vertices()),
            static_cast<Mesh::size_type>(3 * s.num_faces() / 2 + 8),
            static_cast<Mesh::size_type>(s.num_faces()));
  for (Index i = 0; i < s.num_vertices(); ++i) m.add_vertex(to_point(s.V, i));
  for (Index f = 0; f < s.num_faces(); ++f) {
    const FD fd =
        m.add_face(VD(static_cast<Mesh::size_type>(s.F(f, 0))), VD(static_cast<Mesh::size_type>(s.F(f, 1))),
                   VD(static_cast<Mesh::size_type>(s.F(f, 2))));
    require(fd != Mesh::null_face(), what, ": face ", f,
            " cannot be added to a manifold, consistently oriented surface (non-manifold or flipped)");
  }
  return m;
}

/// The engine mesh of a Surface_mesh (removed elements skipped, vertices numbered in index order).
/// Throws InvalidInput naming `what` for a face that is not a triangle.
inline SurfaceMesh from_cgal(const Mesh& m, const std::string& what = "CGAL mesh") {
  SurfaceMesh s;
  std::vector<Index> id(m.num_vertices(), -1);
  s.V.resize(static_cast<Index>(m.number_of_vertices()), 3);
  Index n = 0;
  for (const VD v : m.vertices()) {
    const Point& p = m.point(v);
    s.V.row(n) << p.x(), p.y(), p.z();
    id[v] = n++;
  }
  s.F.resize(static_cast<Index>(m.number_of_faces()), 3);
  Index k = 0;
  for (const FD f : m.faces()) {
    int c = 0;
    for (const VD v : CGAL::vertices_around_face(m.halfedge(f), m)) {
      require(c < 3, what, ": a face of the result is not a triangle");
      s.F(k, c++) = id[v];
    }
    ++k;
  }
  return s;
}

}  // namespace medspring::cgal_detail
