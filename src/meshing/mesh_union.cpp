// CGAL corefinement union and self-intersection count (include/medspring/meshing/mesh_union.hpp).
#include "medspring/meshing/mesh_union.hpp"

#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>

#include <algorithm>
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
