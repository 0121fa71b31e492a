#include "medspring/skeleton/voxelize.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "medspring/core/check.hpp"

namespace medspring {
namespace {

/// Signed solid angle of triangle (a, b, c) seen from the origin (Van Oosterom & Strackee 1983).
double solid_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  const double num = a.dot(b.cross(c));
  const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
  return 2.0 * std::atan2(num, den);
}

}  // namespace

double winding_number(const SurfaceMesh& mesh, const Vec3& p) {
  double sum = 0.0;
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    const Vec3 a = mesh.V.row(mesh.F(f, 0)).transpose() - p;
    const Vec3 b = mesh.V.row(mesh.F(f, 1)).transpose() - p;
    const Vec3 c = mesh.V.row(mesh.F(f, 2)).transpose() - p;
    sum += solid_angle(a, b, c);
  }
  return sum / (4.0 * std::numbers::pi);
}

MaskVolume voxelize(const SurfaceMesh& mesh, const VoxelizeSettings& settings, VoxelizeStats* stats) {
  require(mesh.num_vertices() > 0 && mesh.num_faces() > 0, "voxelize: mesh is empty (", mesh.num_vertices(),
          " vertices, ", mesh.num_faces(), " faces)");
  require_finite_points(mesh.V, "voxelize: mesh vertex");
  for (Index f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) require_index(mesh.F(f, c), mesh.num_vertices(), cat("voxelize: face ", f));
  require_nonnegative(settings.voxel_size, "voxelize: voxel_size");
  require(settings.divisions >= 1, "voxelize: divisions must be >= 1 (got ", settings.divisions, ")");
  require(settings.padding >= 0, "voxelize: padding must be >= 0 (got ", settings.padding, ")");
  require_nonnegative(settings.jitter, "voxelize: jitter");

  const Eigen::Matrix<double, 2, 3> box = bounds(mesh.V);
  const Vec3 extent = (box.row(1) - box.row(0)).transpose();
  const double hv = settings.voxel_size > 0 ? settings.voxel_size
                                            : extent.minCoeff() / static_cast<double>(settings.divisions);
  require(hv > 0, "voxelize: mesh is flat (smallest bounding-box extent is 0); give voxel_size");
  MaskVolume vol;
  vol.spacing = Vec3::Constant(hv);
  const Vec3 centre = 0.5 * (box.row(0) + box.row(1)).transpose();
  for (int a = 0; a < 3; ++a) {
    const double cells = std::ceil(extent[a] / hv - 1e-9);
    require(cells < 1e5, "voxelize: ", cells, " voxels along axis ", a, " (voxel_size too small)");
    vol.dims[a] = static_cast<Index>(cells) + 1 + 2 * settings.padding;
    vol.origin[a] = centre[a] - 0.5 * hv * static_cast<double>(vol.dims[a] - 1);
  }
  require(static_cast<double>(vol.dims[0]) * vol.dims[1] * vol.dims[2] < 2147483647.0,
          "voxelize: grid too large (voxel_size too small)");
  vol.data.assign(vol.size(), 0);
  const Index nx = vol.dims[0], ny = vol.dims[1], nz = vol.dims[2];
  const double jy = settings.jitter * hv * std::numbers::sqrt2,
               jz = settings.jitter * hv * std::numbers::sqrt3;
  auto row_y = [&](Index j) { return vol.origin.y() + hv * static_cast<double>(j) + jy; };
  auto row_z = [&](Index k) { return vol.origin.z() + hv * static_cast<double>(k) + jz; };

  // crossings of every (y, z) row with every triangle: (row id j + ny k, x)
  std::vector<std::pair<Index, double>> hits;
  for (Index f = 0; f < mesh.num_faces(); ++f) {
    const Vec3 A = mesh.V.row(mesh.F(f, 0)).transpose(), B = mesh.V.row(mesh.F(f, 1)).transpose(),
               C = mesh.V.row(mesh.F(f, 2)).transpose();
    const double ylo = std::min({A.y(), B.y(), C.y()}), yhi = std::max({A.y(), B.y(), C.y()});
    const double zlo = std::min({A.z(), B.z(), C.z()}), zhi = std::max({A.z(), B.z(), C.z()});
    const Index j0 = std::max<Index>(0, static_cast<Index>(std::ceil((ylo - vol.origin.y() - jy) / hv)));
    const Index j1 =
        std::min<Index>(ny - 1, static_cast<Index>(std::floor((yhi - vol.origin.y() - jy) / hv)));
    const Index k0 = std::max<Index>(0, static_cast<Index>(std::ceil((zlo - vol.origin.z() - jz) / hv)));
    const Index k1 =
        std::min<Index>(nz - 1, static_cast<Index>(std::floor((zhi - vol.origin.z() - jz) / hv)));
    for (Index k = k0; k <= k1; ++k)
      for (Index j = j0; j <= j1; ++j) {
        const double y = row_y(j), z = row_z(k);
        // edge functions in the yz projection: e_a is twice the signed area of (p, b, c), etc.
        const double ea = (B.y() - y) * (C.z() - z) - (B.z() - z) * (C.y() - y);
        const double eb = (C.y() - y) * (A.z() - z) - (C.z() - z) * (A.y() - y);
        const double ec = (A.y() - y) * (B.z() - z) - (A.z() - z) * (B.y() - y);
        const bool in = (ea > 0 && eb > 0 && ec > 0) || (ea < 0 && eb < 0 && ec < 0);
        if (!in) continue;
        const double sum = ea + eb + ec;
        hits.emplace_back(j + ny * k, (ea * A.x() + eb * B.x() + ec * C.x()) / sum);
      }
  }
  std::sort(hits.begin(), hits.end());

  const double orientation = signed_volume(mesh.V, mesh.F) >= 0 ? 1.0 : -1.0;
  VoxelizeStats st;
  st.rows = ny * nz;
  st.voxel_size = hv;
  for (std::size_t b = 0; b < hits.size();) {
    std::size_t e = b;
    while (e < hits.size() && hits[e].first == hits[b].first) ++e;
    const Index row = hits[b].first;
    const Index j = row % ny, k = row / ny;
    const std::size_t base = vol.index(0, j, k);
    if ((e - b) % 2 == 0) {
      for (std::size_t p = b; p < e; p += 2) {  // fill between pairs
        const Index i0 =
            std::max<Index>(0, static_cast<Index>(std::ceil((hits[p].second - vol.origin.x()) / hv)));
        const Index i1 = std::min<Index>(
            nx - 1, static_cast<Index>(std::floor((hits[p + 1].second - vol.origin.x()) / hv)));
        for (Index i = i0; i <= i1; ++i) vol.data[base + i] = 1;
      }
    } else {  // not watertight: generalized winding number per voxel centre
      ++st.odd_rows;
      for (Index i = 0; i < nx; ++i) {
        const Vec3 p(vol.origin.x() + hv * static_cast<double>(i), row_y(j) - jy, row_z(k) - jz);
        if (orientation * winding_number(mesh, p) > 0.5) vol.data[base + i] = 1;
      }
    }
    b = e;
  }
  for (std::uint8_t v : vol.data) st.inside_voxels += v;
  if (stats) *stats = st;
  return vol;
}

std::vector<BoundaryCap> close_boundary_loops(SurfaceMesh& mesh) {
  const Index nv = mesh.num_vertices(), nf = mesh.num_faces();
  // undirected edge multiplicities
  struct HalfEdge {
    Index lo, hi, from, to, order;
  };
  std::vector<HalfEdge> he;
  he.reserve(3 * static_cast<std::size_t>(nf));
  for (Index f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      const Index a = mesh.F(f, c), b = mesh.F(f, (c + 1) % 3);
      require_index(a, nv, cat("close_boundary_loops: face ", f));
      he.push_back({std::min(a, b), std::max(a, b), a, b, 3 * f + c});
    }
  std::vector<HalfEdge> sorted = he;
  std::sort(sorted.begin(), sorted.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.lo != y.lo ? x.lo < y.lo : x.hi != y.hi ? x.hi < y.hi : x.order < y.order;
  });
  std::vector<Index> next(nv, -1);
  std::vector<HalfEdge> boundary;
  for (std::size_t b = 0; b < sorted.size();) {
    std::size_t e = b;
    while (e < sorted.size() && sorted[e].lo == sorted[b].lo && sorted[e].hi == sorted[b].hi) ++e;
    if (e - b == 1) {
      const HalfEdge& h = sorted[b];
      require(next[h.from] < 0, "close_boundary_loops: vertex ", h.from,
              " has two outgoing boundary edges (non-manifold boundary)");
      next[h.from] = h.to;
      boundary.push_back(h);
    }
    b = e;
  }
  std::sort(boundary.begin(), boundary.end(),
            [](const HalfEdge& x, const HalfEdge& y) { return x.order < y.order; });

  std::vector<BoundaryCap> caps;
  std::vector<std::uint8_t> used(nv, 0);
  std::vector<Vec3> new_vertices;
  std::vector<std::array<Index, 3>> new_faces;
  for (const HalfEdge& start : boundary) {
    if (used[start.from]) continue;
    BoundaryCap cap;
    Index v = start.from;
    do {
      require(!used[v], "close_boundary_loops: boundary loop through vertex ", v, " is not simple");
      used[v] = 1;
      cap.loop.push_back(v);
      v = next[v];
      require(v >= 0, "close_boundary_loops: open boundary chain at vertex ", cap.loop.back());
    } while (v != start.from);
    for (Index u : cap.loop) cap.centroid += mesh.V.row(u).transpose();
    cap.centroid /= static_cast<double>(cap.loop.size());
    cap.center_vertex = nv + static_cast<Index>(new_vertices.size());
    new_vertices.push_back(cap.centroid);
    Vec3 normal = Vec3::Zero();
    for (std::size_t q = 0; q < cap.loop.size(); ++q) {
      const Index a = cap.loop[q], b = cap.loop[(q + 1) % cap.loop.size()];
      new_faces.push_back({b, a, cap.center_vertex});  // the existing face runs a -> b
      const Vec3 pb = mesh.V.row(b).transpose(), pa = mesh.V.row(a).transpose();
      normal += (pa - pb).cross(cap.centroid - pb);
    }
    cap.normal = normal.norm() > 0 ? Vec3(normal.normalized()) : Vec3::Zero();
    caps.push_back(std::move(cap));
  }
  if (caps.empty()) return caps;
  mesh.V.conservativeResize(nv + static_cast<Index>(new_vertices.size()), 3);
  for (std::size_t q = 0; q < new_vertices.size(); ++q)
    mesh.V.row(nv + static_cast<Index>(q)) = new_vertices[q];
  mesh.F.conservativeResize(nf + static_cast<Index>(new_faces.size()), 3);
  for (std::size_t q = 0; q < new_faces.size(); ++q)
    mesh.F.row(nf + static_cast<Index>(q)) << new_faces[q][0], new_faces[q][1], new_faces[q][2];
  return caps;
}

MeshCenterline centerline_from_mesh(const SurfaceMesh& mesh, const SkeletonSettings& settings,
                                    const VoxelizeSettings& voxelize_settings) {
  require_valid_mesh(mesh, "mesh");
  MeshCenterline out;
  SurfaceMesh closed = mesh;
  out.caps = close_boundary_loops(closed);
  SkeletonSettings s = settings;
  std::vector<std::string> notes;
  if (out.caps.size() == 2 && !s.start && !s.end) {
    s.start = UserEndpoint{out.caps[0].centroid, out.caps[0].normal};
    s.end = UserEndpoint{out.caps[1].centroid, out.caps[1].normal};
    notes.push_back("open tube: 2 boundary loops closed by fans; cap centroids used as endpoints");
  } else if (!out.caps.empty()) {
    notes.push_back(
        cat(out.caps.size(), " boundary loop(s) closed by fans; cap centroids not used as endpoints"));
  }
  out.mask = voxelize(closed, voxelize_settings, &out.voxel_stats);
  if (out.voxel_stats.odd_rows > 0)
    notes.push_back(cat(out.voxel_stats.odd_rows,
                        " scanline(s) with an odd number of crossings classified by winding number"));
  out.skeleton = extract_centerline(out.mask, s);
  out.skeleton.notes.insert(out.skeleton.notes.begin(), notes.begin(), notes.end());
  return out;
}

}  // namespace medspring
