#include "medspring/geometry/surface_mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>

#include "medspring/core/check.hpp"
#include "medspring/geometry/topology.hpp"

namespace medspring {

namespace {

Index find_root(std::vector<Index>& parent, Index a) {
  while (parent[a] != a) {
    parent[a] = parent[parent[a]];
    a = parent[a];
  }
  return a;
}

}  // namespace

Eigen::Matrix<double, 2, 3> bounds(const MatX3& V) {
  Eigen::Matrix<double, 2, 3> b;
  if (V.rows() == 0) {
    b.setZero();
    return b;
  }
  b.row(0) = V.colwise().minCoeff();
  b.row(1) = V.colwise().maxCoeff();
  return b;
}

std::string MeshReport::summary() const {
  std::string s = cat(vertices, " vertices, ", faces, " faces, ", edges, " edges, ",
                      closed() ? "closed" : cat(boundary_edges, " boundary edges (open)"), ", ",
                      manifold() ? "manifold" : cat(nonmanifold_edges, " non-manifold edges"), ", ",
                      components, components == 1 ? " component" : " components");
  if (closed() && manifold()) s += cat(", Euler characteristic ", euler_characteristic);
  if (degenerate_faces) s += cat(", ", degenerate_faces, " degenerate faces");
  if (duplicate_faces) s += cat(", ", duplicate_faces, " duplicate faces");
  if (inconsistent_edges) s += cat(", ", inconsistent_edges, " inconsistently oriented edges");
  if (isolated_vertices) s += cat(", ", isolated_vertices, " isolated vertices");
  return s;
}

MeshReport validate_mesh(const SurfaceMesh& mesh) {
  MeshReport r;
  const Index nv = mesh.num_vertices();
  const Index nf = mesh.num_faces();
  r.vertices = nv;
  r.faces = nf;
  auto note = [&](const std::string& s) {
    if (r.first_problem.empty()) r.first_problem = s;
  };
  if (nv == 0) note("mesh has no vertices");
  if (nf == 0) note("mesh has no faces");
  for (Index i = 0; i < nv; ++i) {
    if (!mesh.V.row(i).allFinite()) {
      if (r.nonfinite_vertices == 0)
        note(cat("vertex ", i, ": coordinates must be finite (got ", mesh.V(i, 0), ", ", mesh.V(i, 1), ", ",
                 mesh.V(i, 2), ")"));
      ++r.nonfinite_vertices;
    }
  }
  if (r.nonfinite_vertices == 0 && nv > 0) {
    const auto b = bounds(mesh.V);
    r.bbox_diagonal = (b.row(1) - b.row(0)).norm();
  }
  const double area_tol = 1e-12 * r.bbox_diagonal * r.bbox_diagonal;
  std::vector<char> used(static_cast<std::size_t>(nv), 0);
  // Every face side as one sortable key: (lo << 33) | (hi << 1) | (lo -> hi is the face's direction).
  // Sorting the keys groups the sides of each edge (no hash map: 1M-node meshes validate in a second).
  std::vector<std::uint64_t> sides;
  sides.reserve(static_cast<std::size_t>(nf) * 3);
  std::vector<std::pair<std::array<Index, 3>, Index>> sorted_faces;  // (sorted corners, face)
  sorted_faces.reserve(static_cast<std::size_t>(nf));
  std::vector<Index> good_faces;
  for (Index f = 0; f < nf; ++f) {
    const Index a = mesh.F(f, 0), b = mesh.F(f, 1), c = mesh.F(f, 2);
    if (a < 0 || b < 0 || c < 0 || a >= nv || b >= nv || c >= nv) {
      if (r.bad_indices == 0)
        note(cat("face ", f, ": index out of range [0, ", nv, ") in (", a, ", ", b, ", ", c, ")"));
      ++r.bad_indices;
      continue;
    }
    used[a] = used[b] = used[c] = 1;
    bool degenerate = a == b || b == c || a == c;
    if (!degenerate && r.nonfinite_vertices == 0) {
      const Vec3 e1 = mesh.V.row(b) - mesh.V.row(a), e2 = mesh.V.row(c) - mesh.V.row(a);
      degenerate = 0.5 * e1.cross(e2).norm() <= area_tol;
    }
    if (degenerate) {
      if (r.degenerate_faces == 0) note(cat("face ", f, ": degenerate triangle (", a, ", ", b, ", ", c, ")"));
      ++r.degenerate_faces;
    }
    std::array<Index, 3> sc{a, b, c};
    std::sort(sc.begin(), sc.end());
    sorted_faces.emplace_back(sc, static_cast<Index>(good_faces.size()));
    good_faces.push_back(f);
    const Index tri[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      const Index u = tri[k], w = tri[(k + 1) % 3];
      if (u == w) continue;
      const auto lo = static_cast<std::uint64_t>(std::min(u, w)),
                 hi = static_cast<std::uint64_t>(std::max(u, w));
      sides.push_back((lo << 33) | (hi << 1) | (u < w ? 1u : 0u));
    }
  }
  // duplicates: faces with the same corners, reported in (corners, face order) order
  {
    std::sort(sorted_faces.begin(), sorted_faces.end());
    for (std::size_t k = 1; k < sorted_faces.size(); ++k) {
      if (sorted_faces[k].first == sorted_faces[k - 1].first) {
        if (r.duplicate_faces == 0)
          note(cat("face ", good_faces[static_cast<std::size_t>(sorted_faces[k].second)],
                   ": duplicate of face ", good_faces[static_cast<std::size_t>(sorted_faces[k - 1].second)]));
        ++r.duplicate_faces;
      }
    }
  }
  std::sort(sides.begin(), sides.end());
  for (std::size_t q = 0; q < sides.size();) {
    const std::uint64_t key = sides[q] >> 1;
    Index faces = 0, forward = 0;
    for (; q < sides.size() && (sides[q] >> 1) == key; ++q) {
      ++faces;
      forward += static_cast<Index>(sides[q] & 1u);
    }
    ++r.edges;
    const Index lo = static_cast<Index>(key >> 32), hi = static_cast<Index>(key & 0xffffffffu);
    if (faces == 1) ++r.boundary_edges;
    if (faces > 2) {
      if (r.nonmanifold_edges == 0)
        note(cat("edge (", lo, ", ", hi, "): non-manifold, shared by ", faces, " faces"));
      ++r.nonmanifold_edges;
    }
    if (faces == 2 && forward != 1) ++r.inconsistent_edges;
  }
  for (Index i = 0; i < nv; ++i) r.isolated_vertices += used[i] ? 0 : 1;
  // components over faces via union-find on vertices
  std::vector<Index> parent(static_cast<std::size_t>(nv));
  std::iota(parent.begin(), parent.end(), 0);
  for (Index f : good_faces) {
    const Index a = find_root(parent, mesh.F(f, 0));
    const Index b = find_root(parent, mesh.F(f, 1));
    const Index c = find_root(parent, mesh.F(f, 2));
    parent[b] = a;
    parent[find_root(parent, c)] = a;
  }
  for (Index i = 0; i < nv; ++i)
    if (used[i] && find_root(parent, i) == i) ++r.components;
  r.euler_characteristic = (nv - r.isolated_vertices) - r.edges + static_cast<Index>(good_faces.size());
  if (r.nonfinite_vertices == 0 && r.bad_indices == 0) r.signed_volume = signed_volume(mesh.V, mesh.F);
  return r;
}

MeshReport require_valid_mesh(const SurfaceMesh& mesh, const std::string& what, const MeshRequirements& req) {
  MeshReport r = validate_mesh(mesh);
  bool ok = r.nonfinite_vertices == 0 && r.bad_indices == 0 && r.degenerate_faces == 0 &&
            r.duplicate_faces == 0 && r.vertices > 0 && r.faces > 0;
  if (req.manifold && r.nonmanifold_edges > 0) ok = false;
  if (!ok) throw InvalidInput(cat(what, ": ", r.first_problem));
  if (req.closed && r.boundary_edges > 0)
    throw InvalidInput(
        cat(what, ": mesh is open (", r.boundary_edges, " boundary edges); a closed surface is required"));
  return r;
}

Index weld_vertices(SurfaceMesh& mesh, double tol, std::vector<Index>* old_to_new) {
  const Index nv = mesh.num_vertices();
  require(first_nonfinite_row(mesh.V) < 0, "weld_vertices: vertex ", first_nonfinite_row(mesh.V),
          " is not finite");
  if (tol < 0) {
    const auto b = bounds(mesh.V);
    tol = 1e-9 * (b.row(1) - b.row(0)).norm();
  }
  // sort by x, sweep within tol (deterministic: the lowest index of a cluster represents it)
  std::vector<Index> order(static_cast<std::size_t>(nv));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](Index a, Index b) {
    return mesh.V(a, 0) < mesh.V(b, 0) || (mesh.V(a, 0) == mesh.V(b, 0) && a < b);
  });
  std::vector<Index> rep(static_cast<std::size_t>(nv));
  std::iota(rep.begin(), rep.end(), 0);
  Index merged = 0;
  for (std::size_t s = 0; s < order.size(); ++s) {
    const Index a = order[s];
    for (std::size_t t = s + 1; t < order.size() && mesh.V(order[t], 0) - mesh.V(a, 0) <= tol; ++t) {
      const Index b = order[t];
      if (rep[b] != b) continue;
      if ((mesh.V.row(a) - mesh.V.row(b)).norm() <= tol) {
        const Index ra = rep[a];
        if (ra < b) {
          rep[b] = ra;
        } else {
          rep[ra] = b;
          rep[a] = b;
        }
      }
    }
  }
  for (Index i = 0; i < nv; ++i) {
    Index r = i;
    while (rep[r] != r) r = rep[r];
    rep[i] = r;
    if (r != i) ++merged;
  }
  // rebuild faces, drop degenerate
  std::vector<std::array<Index, 3>> faces;
  faces.reserve(static_cast<std::size_t>(mesh.num_faces()));
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    std::array<Index, 3> t{rep[mesh.F(f, 0)], rep[mesh.F(f, 1)], rep[mesh.F(f, 2)]};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    faces.push_back(t);
  }
  std::vector<Index> remap(static_cast<std::size_t>(nv), -1);
  Index next = 0;
  for (const auto& t : faces)
    for (Index v : t)
      if (remap[v] < 0) remap[v] = -2;
  for (Index i = 0; i < nv; ++i)
    if (remap[i] == -2) remap[i] = next++;
  MatX3 V(next, 3);
  for (Index i = 0; i < nv; ++i)
    if (remap[i] >= 0) V.row(remap[i]) = mesh.V.row(i);
  MatX3i F(static_cast<Index>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k) F(static_cast<Index>(f), k) = remap[faces[f][k]];
  if (old_to_new) {
    old_to_new->assign(static_cast<std::size_t>(nv), -1);
    for (Index i = 0; i < nv; ++i) (*old_to_new)[i] = remap[rep[i]];
  }
  mesh.V = std::move(V);
  mesh.F = std::move(F);
  return merged;
}

namespace {

// The accumulation is written with scalar loads and stores only: when the compiler pairs x and y into
// one 16-byte store, the next face's 8- or 16-byte load of the same vertex spans two earlier stores and
// cannot be forwarded (a stall per shared vertex). The same sums in the same order as the Eigen row form
// (the cross product may round differently).
#if defined(__GNUC__) && !defined(__clang__)
__attribute__((optimize("no-tree-slp-vectorize")))
#endif
void accumulate_face_normals(const double* X, const Index* T, Index nf, double* A) {
  for (Index f = 0; f < nf; ++f) {
    const Index a = 3 * T[3 * f], b = 3 * T[3 * f + 1], c = 3 * T[3 * f + 2];
    const double ux = X[b] - X[a], uy = X[b + 1] - X[a + 1], uz = X[b + 2] - X[a + 2];
    const double wx = X[c] - X[a], wy = X[c + 1] - X[a + 1], wz = X[c + 2] - X[a + 2];
    const double nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;  // 2 x area
    for (const Index q : {a, b, c}) {
      A[q] += nx;
      A[q + 1] += ny;
      A[q + 2] += nz;
    }
  }
}

}  // namespace

void vertex_normals(const MatX3& V, const MatX3i& F, MatX3& N) {
  N.setZero(V.rows(), 3);
  double* A = N.data();
  accumulate_face_normals(V.data(), F.data(), static_cast<Index>(F.rows()), A);
  // One division per node (times the reciprocal: within 1 ulp of dividing each component); a zero
  // normal stays zero.
  const auto n = static_cast<Index>(N.rows());
  for (Index i = 0; i < n; ++i) {
    const double x = A[3 * i], y = A[3 * i + 1], z = A[3 * i + 2];
    const double l = std::sqrt(x * x + y * y + z * z);
    const double r = 1.0 / (l > 0 ? l : 1.0);
    A[3 * i] = x * r;
    A[3 * i + 1] = y * r;
    A[3 * i + 2] = z * r;
  }
}

MatX3 face_normals(const MatX3& V, const MatX3i& F) {
  MatX3 N(F.rows(), 3);
  for (Index f = 0; f < F.rows(); ++f) {
    const Vec3 n =
        (V.row(F(f, 1)) - V.row(F(f, 0))).transpose().cross((V.row(F(f, 2)) - V.row(F(f, 0))).transpose());
    const double l = n.norm();
    N.row(f) = l > 0 ? Vec3(n / l) : Vec3::Zero();
  }
  return N;
}

double signed_volume(const MatX3& V, const MatX3i& F) {
  double vol = 0;
  for (Index f = 0; f < F.rows(); ++f) vol += V.row(F(f, 0)).dot(V.row(F(f, 1)).cross(V.row(F(f, 2))));
  return vol / 6.0;
}

double surface_area(const MatX3& V, const MatX3i& F) {
  double a = 0;
  for (Index f = 0; f < F.rows(); ++f)
    a += 0.5 * (V.row(F(f, 1)) - V.row(F(f, 0))).cross(V.row(F(f, 2)) - V.row(F(f, 0))).norm();
  return a;
}

}  // namespace medspring
