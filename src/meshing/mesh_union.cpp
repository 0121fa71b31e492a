// CGAL corefinement union and self-intersection count (include/medspring/meshing/mesh_union.hpp).
#include "medspring/meshing/mesh_union.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <iterator>
#include <utility>
#include <vector>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using VD = Mesh::Vertex_index;
using FD = Mesh::Face_index;

Mesh to_cgal(const SurfaceMesh& s, const std::string& what) {
  Mesh m;
  for (Index i = 0; i < s.num_vertices(); ++i) m.add_vertex(Point(s.V(i, 0), s.V(i, 1), s.V(i, 2)));
  for (Index f = 0; f < s.num_faces(); ++f) {
    const FD fd =
        m.add_face(VD(static_cast<Mesh::size_type>(s.F(f, 0))), VD(static_cast<Mesh::size_type>(s.F(f, 1))),
                   VD(static_cast<Mesh::size_type>(s.F(f, 2))));
    require(fd != Mesh::null_face(), what, ": face ", f,
            " cannot be added to a manifold, consistently oriented surface (non-manifold or flipped)");
  }
  return m;
}

SurfaceMesh from_cgal(const Mesh& m) {
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
      require(c < 3, "mesh union: a face of the result is not a triangle");
      s.F(k, c++) = id[v];
    }
    ++k;
  }
  return s;
}

}  // namespace

SurfaceMesh union_of_closed_meshes(const std::vector<SurfaceMesh>& parts, const std::string& what) {
  require(!parts.empty(), what, ": union of no surfaces");
  Mesh acc;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const std::string w = cat(what, ": part ", k);
    SurfaceMesh p = parts[k];
    const MeshReport r = require_valid_mesh(p, w, {.closed = true});
    require(r.inconsistent_edges == 0, w, ": inconsistently oriented (", r.inconsistent_edges, " edges)");
    if (signed_volume(p.V, p.F) < 0.0) p.F.col(1).swap(p.F.col(2));
    Mesh m = to_cgal(p, w);
    require(!PMP::does_self_intersect(m), w, ": intersects itself (a union needs simple closed surfaces)");
    if (k == 0) {
      acc = std::move(m);
      continue;
    }
    Mesh out;
    const bool ok = PMP::corefine_and_compute_union(acc, m, out);
    require(ok, what, ": the union with part ", k, " is not a closed manifold surface (CGAL corefinement)");
    acc = std::move(out);
  }
  SurfaceMesh s = from_cgal(acc);
  if (signed_volume(s.V, s.F) < 0.0) s.F.col(1).swap(s.F.col(2));
  return s;
}

Index self_intersections(const SurfaceMesh& mesh, const std::string& what) {
  require_valid_mesh(mesh, what);
  const Mesh m = to_cgal(mesh, what);
  std::vector<std::pair<FD, FD>> pairs;
  PMP::self_intersections(m, std::back_inserter(pairs));
  return static_cast<Index>(pairs.size());
}

}  // namespace medspring
