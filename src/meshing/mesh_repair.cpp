// Closed-manifold checks (no CGAL here: close_small_holes lives in cgal_meshing.cpp).
#include "medspring/meshing/mesh_repair.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <unordered_map>
#include <utility>
#include <vector>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

std::uint64_t edge_key(Index a, Index b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

Index find_root(std::vector<Index>& parent, Index a) {
  while (parent[a] != a) {
    parent[a] = parent[parent[a]];
    a = parent[a];
  }
  return a;
}

bool unite(std::vector<Index>& parent, Index a, Index b) {
  a = find_root(parent, a);
  b = find_root(parent, b);
  if (a == b) return false;
  parent[std::max(a, b)] = std::min(a, b);
  return true;
}

/// "1 edge", "3 edges".
std::string count_of(Index n, const char* one, const char* many) {
  return cat(n, " ", n == 1 ? one : many);
}

}  // namespace

ClosedManifoldReport check_closed_manifold(const SurfaceMesh& mesh) {
  ClosedManifoldReport r;
  r.mesh = validate_mesh(mesh);
  if (r.mesh.bad_indices > 0 || r.mesh.vertices == 0) return r;
  const Index nv = mesh.num_vertices();
  const Index nf = mesh.num_faces();

  // Edge -> incident faces.
  std::unordered_map<std::uint64_t, std::vector<Index>> edge_faces;
  edge_faces.reserve(static_cast<std::size_t>(nf) * 2);
  for (Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) edge_faces[edge_key(mesh.F(f, k), mesh.F(f, (k + 1) % 3))].push_back(f);

  // Holes: connected components of the boundary-edge graph.
  std::vector<Index> parent(static_cast<std::size_t>(nv));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> on_boundary(static_cast<std::size_t>(nv), 0);
  for (const auto& [key, faces] : edge_faces) {
    if (faces.size() != 1) continue;
    const auto a = static_cast<Index>(key >> 32), b = static_cast<Index>(key & 0xffffffffu);
    on_boundary[a] = on_boundary[b] = 1;
    unite(parent, a, b);
  }
  for (Index v = 0; v < nv; ++v)
    if (on_boundary[v] && find_root(parent, v) == v) ++r.holes;

  // Non-manifold vertices: the faces around v must form one fan (connected through edges at v).
  std::vector<std::vector<Index>> vertex_faces(static_cast<std::size_t>(nv));
  for (Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) vertex_faces[mesh.F(f, k)].push_back(f);
  std::vector<Index> fan_parent;
  for (Index v = 0; v < nv; ++v) {
    const auto& vf = vertex_faces[v];
    if (vf.size() < 2) continue;
    fan_parent.resize(vf.size());
    std::iota(fan_parent.begin(), fan_parent.end(), 0);
    Index groups = static_cast<Index>(vf.size());
    for (std::size_t i = 0; i < vf.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        const Index w = mesh.F(vf[i], k);
        if (w == v) continue;
        const auto it = edge_faces.find(edge_key(v, w));
        for (const Index g : it->second) {
          const auto j = std::find(vf.begin(), vf.end(), g) - vf.begin();
          if (unite(fan_parent, static_cast<Index>(i), static_cast<Index>(j))) --groups;
        }
      }
    }
    if (groups > 1) ++r.nonmanifold_vertices;
  }
  return r;
}

ClosedManifoldReport require_closed_manifold(const SurfaceMesh& mesh, const std::string& what) {
  ClosedManifoldReport r = check_closed_manifold(mesh);
  const MeshReport& m = r.mesh;
  const bool basic_ok = m.vertices > 0 && m.faces > 0 && m.nonfinite_vertices == 0 && m.bad_indices == 0 &&
                        m.degenerate_faces == 0 && m.duplicate_faces == 0;
  require(basic_ok, what, ": invalid surface mesh: ", m.first_problem);
  require(
      m.nonmanifold_edges == 0, what,
      ": surface is not manifold: ", count_of(m.nonmanifold_edges, "edge is", "edges are"),
      " shared by more than two triangles; repair the mesh (e.g. remove duplicate or overlapping triangles) "
      "before meshing");
  require(r.nonmanifold_vertices == 0, what,
          ": surface is not manifold: ", count_of(r.nonmanifold_vertices, "vertex joins", "vertices join"),
          " separate triangle fans (bow-tie vertices); repair the mesh before meshing");
  require(m.closed(), what,
          ": surface is open: ", count_of(m.boundary_edges, "boundary edge", "boundary edges"), " in ",
          count_of(r.holes, "hole", "holes"),
          "; close holes of up to N edges with close_small_holes (CLI option --close-holes N)");
  require(m.inconsistent_edges == 0, what,
          ": surface is not consistently oriented: ", count_of(m.inconsistent_edges, "edge is", "edges are"),
          " traversed twice in the same direction");
  return r;
}

}  // namespace medspring
