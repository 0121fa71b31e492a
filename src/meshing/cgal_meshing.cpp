// The meshing layer's CGAL functions other than the balloon (cgal_balloon.cpp), compiled with it as one
// translation unit (cgal_support.hpp):
//  - close_small_holes (mesh_repair.hpp): triangulate_refine_and_fair_hole.
//  - surface_distance / hausdorff_distance / distances_to_surface (surface_distance.hpp): sampled,
//    exact point-to-triangle distances.
#include "cgal_support.hpp"

namespace medspring {

using namespace cgal_detail;

namespace {

void sample_surface(const SurfaceMesh& s, double spacing, std::vector<Point>& pts, std::vector<double>& w) {
  for (Index f = 0; f < s.num_faces(); ++f) {
    const Vec3 a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const int n = std::clamp(static_cast<int>(std::ceil(longest / spacing)), 1, 200);
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const double weight = area / (0.5 * (n + 1) * (n + 2));
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const double u = static_cast<double>(i) / n, v = static_cast<double>(j) / n;
        const Vec3 p = a + u * (b - a) + v * (c - a);
        pts.emplace_back(p.x(), p.y(), p.z());
        w.push_back(weight);
      }
  }
}

/// Organ samples for the fit: every vertex plus, on triangles longer than `spacing`, the
/// non-corner points of a barycentric grid of that spacing; each triangle's area is shared equally

void one_sided(const std::vector<Point>& pts, const std::vector<double>& w, const SurfaceQuery& to,
               double& max_d, double& mean_d) {
  double sum = 0.0, wsum = 0.0;
  max_d = 0.0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const double d = to.distance(pts[i]);
    max_d = std::max(max_d, d);
    sum += w[i] * d;
    wsum += w[i];
  }
  mean_d = wsum > 0.0 ? sum / wsum : 0.0;
}

void require_triangles(const SurfaceMesh& s, const char* what) {
  const MeshReport r = validate_mesh(s);
  require(r.vertices > 0 && r.faces > 0, what, ": mesh is empty");
  require(r.bad_indices == 0 && r.nonfinite_vertices == 0, what, ": invalid mesh: ", r.first_problem);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// surface_distance.hpp

SurfaceDistance surface_distance(const SurfaceMesh& a, const SurfaceMesh& b,
                                 const SurfaceDistanceSettings& settings) {
  require_triangles(a, "surface_distance: mesh a");
  require_triangles(b, "surface_distance: mesh b");
  require_nonnegative(settings.sample_spacing, "SurfaceDistanceSettings::sample_spacing");
  double spacing = settings.sample_spacing;
  if (spacing == 0.0) {
    const auto ba = bounds(a.V), bb = bounds(b.V);
    spacing = std::max((ba.row(1) - ba.row(0)).norm(), (bb.row(1) - bb.row(0)).norm()) / 250.0;
    if (spacing <= 0.0) spacing = 1.0;
  }
  const SurfaceQuery qa(to_triangles(a)), qb(to_triangles(b));
  SurfaceDistance r;
  std::vector<Point> pts;
  std::vector<double> w;
  sample_surface(a, spacing, pts, w);
  one_sided(pts, w, qb, r.a_to_b_max, r.a_to_b_mean);
  r.samples = static_cast<Index>(pts.size());
  pts.clear();
  w.clear();
  sample_surface(b, spacing, pts, w);
  one_sided(pts, w, qa, r.b_to_a_max, r.b_to_a_mean);
  r.samples += static_cast<Index>(pts.size());
  r.hausdorff = std::max(r.a_to_b_max, r.b_to_a_max);
  r.mean = 0.5 * (r.a_to_b_mean + r.b_to_a_mean);
  return r;
}

VecX distances_to_surface(const MatX3& points, const SurfaceMesh& surface) {
  require_triangles(surface, "distances_to_surface: surface");
  require_finite_points(points, "distances_to_surface: points");
  const SurfaceQuery q(to_triangles(surface));
  VecX d(points.rows());
  for (Index i = 0; i < points.rows(); ++i) d[i] = q.distance(to_point(points, i));
  return d;
}

MatX3 closest_points_on_surface(const MatX3& points, const SurfaceMesh& surface) {
  require_triangles(surface, "closest_points_on_surface: surface");
  require_finite_points(points, "closest_points_on_surface: points");
  const SurfaceQuery q(to_triangles(surface));
  MatX3 c(points.rows(), 3);
  for (Index i = 0; i < points.rows(); ++i) {
    const Point p = q.closest(to_point(points, i));
    c.row(i) << p.x(), p.y(), p.z();
  }
  return c;
}

MatX3 surface_samples(const SurfaceMesh& s, double spacing, VecX* weights) {
  require_triangles(s, "surface_samples: mesh");
  require_positive(spacing, "surface_samples: spacing");
  std::vector<Point> pts;
  std::vector<double> w;
  sample_surface(s, spacing, pts, w);
  MatX3 P(static_cast<Index>(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i)
    P.row(static_cast<Index>(i)) << pts[i].x(), pts[i].y(), pts[i].z();
  if (weights) *weights = Eigen::Map<const VecX>(w.data(), static_cast<Index>(w.size()));
  return P;
}

double hausdorff_distance(const SurfaceMesh& a, const SurfaceMesh& b,
                          const SurfaceDistanceSettings& settings) {
  return surface_distance(a, b, settings).hausdorff;
}

// ---------------------------------------------------------------------------------------------
// mesh_repair.hpp

HoleFillReport close_small_holes(SurfaceMesh& mesh, Index max_hole_edges) {
  require(max_hole_edges >= 3, "close_small_holes: max_hole_edges must be >= 3 (got ", max_hole_edges, ")");
  const ClosedManifoldReport c = check_closed_manifold(mesh);
  require(
      c.mesh.vertices > 0 && c.mesh.faces > 0 && c.mesh.bad_indices == 0 && c.mesh.nonfinite_vertices == 0,
      "close_small_holes: invalid mesh: ", c.mesh.first_problem);
  require(c.mesh.nonmanifold_edges == 0 && c.nonmanifold_vertices == 0,
          "close_small_holes: mesh is not manifold (", c.mesh.nonmanifold_edges, " non-manifold edges, ",
          c.nonmanifold_vertices, " non-manifold vertices); holes can only be closed in a manifold mesh");
  HoleFillReport r;
  Mesh m = to_cgal(mesh, "close_small_holes");
  std::vector<HD> cycles;
  PMP::extract_boundary_cycles(m, std::back_inserter(cycles));
  r.holes_found = static_cast<Index>(cycles.size());
  for (const HD h : cycles) {
    Index edges = 0;
    HD g = h;
    do {
      ++edges;
      g = m.next(g);
    } while (g != h);
    if (edges > max_hole_edges) {
      ++r.holes_skipped;
      continue;
    }
    std::vector<FD> faces;
    std::vector<VD> vertices;
    const auto result =
        PMP::triangulate_refine_and_fair_hole(m, h, std::back_inserter(faces), std::back_inserter(vertices));
    require(!faces.empty(), "close_small_holes: a hole of ", edges, " edges could not be triangulated");
    static_cast<void>(result);
    ++r.holes_filled;
    r.faces_added += static_cast<Index>(faces.size());
    r.vertices_added += static_cast<Index>(vertices.size());
  }
  m.collect_garbage();
  mesh = from_cgal(m);
  return r;
}

}  // namespace medspring
