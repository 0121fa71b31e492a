// CGAL corefinement union and self-intersection count (include/medspring/meshing/mesh_union.hpp).
#include "medspring/meshing/mesh_union.hpp"

#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <numbers>
#include <utility>
#include <vector>

#include "cgal_mesh.hpp"
#include "medspring/core/check.hpp"

namespace medspring {

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using cgal_detail::FD;
using cgal_detail::from_cgal;
using cgal_detail::Mesh;
using cgal_detail::to_cgal;

// The mesh in a canonical numbering: vertices in lexicographic (x, y, z) order, each face rotated to start
// at its smallest vertex (orientation kept), faces in lexicographic order. The corefinement's output order
// can change from one call to the next for the same inputs (seen on the Y phantoms and the VMR tree), which
// would make a scene's load on a node index press a different point from run to run; the geometry does
// not change, so this order is reproducible.
void canonical_order(SurfaceMesh& s) {
  const Index n = s.num_vertices(), nf = s.num_faces();
  std::vector<Index> order(static_cast<std::size_t>(n));
  for (Index a = 0; a < n; ++a) order[static_cast<std::size_t>(a)] = a;
  std::sort(order.begin(), order.end(), [&](Index a, Index b) {
    for (int c = 0; c < 3; ++c)
      if (s.V(a, c) != s.V(b, c)) return s.V(a, c) < s.V(b, c);
    return a < b;
  });
  std::vector<Index> rank(static_cast<std::size_t>(n));
  decltype(s.V) V(n, 3);
  for (Index r = 0; r < n; ++r) {
    rank[static_cast<std::size_t>(order[static_cast<std::size_t>(r)])] = r;
    V.row(r) = s.V.row(order[static_cast<std::size_t>(r)]);
  }
  std::vector<std::array<Index, 3>> faces(static_cast<std::size_t>(nf));
  for (Index f = 0; f < nf; ++f) {
    std::array<Index, 3> t{rank[static_cast<std::size_t>(s.F(f, 0))],
                           rank[static_cast<std::size_t>(s.F(f, 1))],
                           rank[static_cast<std::size_t>(s.F(f, 2))]};
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};  // rotate: orientation kept
    faces[static_cast<std::size_t>(f)] = t;
  }
  std::sort(faces.begin(), faces.end());
  s.V = std::move(V);
  for (Index f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c)
      s.F(f, c) =
          static_cast<MatX3i::Scalar>(faces[static_cast<std::size_t>(f)][static_cast<std::size_t>(c)]);
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
  SurfaceMesh s = from_cgal(acc, what + ": union");
  // Where a vertex of one part lies exactly on another part's edge (a planar, mirror-symmetric tree),
  // the corefinement leaves zero-area triangles: collapse or flip them away (caps over 179.99 degrees,
  // needles over 1e6 : 1), only when there are any (other unions stay as they were).
  const MeshReport rep = validate_mesh(s);
  if (rep.degenerate_faces > 0) {
    PMP::experimental::remove_almost_degenerate_faces(acc, std::cos(179.99 * std::numbers::pi / 180.0), 1e6,
                                                      1e-3 * rep.bbox_diagonal);
    acc.collect_garbage();
    s = from_cgal(acc, what + ": union");
    const MeshReport again = validate_mesh(s);
    require(again.degenerate_faces == 0, what, ": the union has ", again.degenerate_faces,
            " zero-area triangles left after removing ", rep.degenerate_faces, " (", again.first_problem,
            ")");
  }
  if (signed_volume(s.V, s.F) < 0.0) s.F.col(1).swap(s.F.col(2));
  canonical_order(s);
  return s;
}

Index self_intersections(const SurfaceMesh& mesh, const std::string& what) {
  require_valid_mesh(mesh, what);
  const Mesh m = to_cgal(mesh, what);
  std::vector<std::pair<FD, FD>> pairs;
  PMP::self_intersections(m, std::back_inserter(pairs));
  return static_cast<Index>(pairs.size());
}

std::vector<Index> self_intersecting_faces(const SurfaceMesh& mesh, const std::string& what) {
  require_valid_mesh(mesh, what);
  const Mesh m = to_cgal(mesh, what);
  std::vector<std::pair<FD, FD>> pairs;
  PMP::self_intersections(m, std::back_inserter(pairs));
  std::vector<Index> faces;
  for (const auto& [a, b] : pairs) {
    faces.push_back(static_cast<Index>(a.idx()));
    faces.push_back(static_cast<Index>(b.idx()));
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  return faces;
}

}  // namespace medspring
