#include "medspring/fem/volumetric.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/fem/organ.hpp"

namespace medspring::fem {

namespace {

VolumetricMesh linear_mesh(const SurfaceMesh& surface, TetgenSettings ts) {
  ts.preserve_surface = true;
  const TetMesh q = tet_mesh_from_surface(surface, ts);
  VolumetricMesh m;
  m.T = q.T.leftCols(4);
  const Index nn = m.T.maxCoeff() + 1;
  m.X = q.X.topRows(nn);
  m.F = surface.F;
  m.surface_nodes = surface.num_vertices();
  require(nn >= m.surface_nodes, "volumetric mesh: TetGen returned ", nn, " nodes for a surface of ",
          m.surface_nodes, " vertices");
  const double d = (m.X.topRows(m.surface_nodes) - surface.V).cwiseAbs().maxCoeff();
  if (!(d <= 1e-9 * (1.0 + surface.V.cwiseAbs().maxCoeff())))
    throw SolverError(cat("volumetric mesh: TetGen moved or reordered the surface vertices (by ", d, " mm)"));
  return m;
}

// The mean length of the surface edges at each vertex (every edge counted once per face side, which weighs
// all of a closed manifold's edges twice, equally).
std::vector<double> surface_edge_sizes(const SurfaceMesh& s) {
  std::vector<double> sum(static_cast<std::size_t>(s.num_vertices()), 0.0), count(sum.size(), 0.0);
  for (Index f = 0; f < s.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Index a = s.F(f, k), b = s.F(f, (k + 1) % 3);
      const double l = (s.V.row(a) - s.V.row(b)).norm();
      sum[a] += l;
      sum[b] += l;
      count[a] += 1;
      count[b] += 1;
    }
  for (std::size_t i = 0; i < sum.size(); ++i) {
    require(count[i] > 0, "volumetric mesh: surface vertex ", i, " is on no face");
    sum[i] /= count[i];
  }
  return sum;
}

// sizing surface: the background mesh is TetGen's quality mesh of the surface with no size bound; its nodes
// get the size of the nearest surface vertex plus grading times the distance to it.
TetgenSettings surface_sizing(const SurfaceMesh& surface, const VolumetricMeshSettings& s) {
  TetgenSettings ts;
  ts.radius_edge = s.radius_edge;
  ts.vertex_sizes = surface_edge_sizes(surface);
  const VolumetricMesh bg = linear_mesh(surface, {.radius_edge = s.radius_edge});
  ts.background_X = bg.X;
  ts.background_T = bg.T;
  ts.background_sizes.resize(static_cast<std::size_t>(bg.X.rows()));
  for (Index i = 0; i < bg.X.rows(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    Index j = 0;
    for (Index v = 0; v < surface.num_vertices(); ++v) {
      const double d2 = (bg.X.row(i) - surface.V.row(v)).squaredNorm();
      if (d2 < best) {
        best = d2;
        j = v;
      }
    }
    ts.background_sizes[i] = ts.vertex_sizes[j] + s.grading * std::sqrt(best);
  }
  return ts;
}

TetgenSettings scaled(TetgenSettings ts, double f) {
  for (double& h : ts.vertex_sizes) h *= f;
  for (double& h : ts.background_sizes) h *= f;
  return ts;
}

}  // namespace

VolumetricMesh volumetric_mesh(const SurfaceMesh& given, const VolumetricMeshSettings& s) {
  require(s.surface_subdivisions >= 0 && s.surface_subdivisions <= 3,
          "volumetric mesh: surface_subdivisions must be in [0, 3] (got ", s.surface_subdivisions, ")");
  require(std::isfinite(s.grading) && s.grading >= 0, "volumetric mesh: grading must be >= 0 (got ",
          s.grading, ")");
  SurfaceMesh surface = given;
  for (int i = 0; i < s.surface_subdivisions; ++i) surface = subdivide_midpoint(surface);
  require(
      s.target_nodes >= surface.num_vertices(), "volumetric mesh: target_nodes ", s.target_nodes,
      " is below the surface's ", surface.num_vertices(), " vertices",
      s.surface_subdivisions > 0 ? cat(" (after ", s.surface_subdivisions, " subdivisions)") : std::string());
  require(s.attempts >= 1, "volumetric mesh: attempts must be >= 1");
  const double interior = std::max<double>(1.0, static_cast<double>(s.target_nodes - surface.num_vertices()));
  VolumetricMesh best;
  Index best_err = -1;
  auto keep = [&](VolumetricMesh&& m) {
    const Index n = static_cast<Index>(m.X.rows());
    const Index err = std::abs(n - s.target_nodes);
    if (best_err < 0 || err < best_err) {
      best = std::move(m);
      best_err = err;
    }
    return std::max<double>(1.0, static_cast<double>(n - surface.num_vertices()));
  };
  if (s.sizing == MeshSizing::Surface) {
    // interior node count ~ 1 / size^3; the scale never goes below 1 (no tetrahedron at the surface smaller
    // than its edges), so a target above the 1x count gets the 1x mesh
    TetgenSettings base = surface_sizing(surface, s);
    double f = 1.0;
    for (int it = 0; it < s.attempts; ++it) {
      VolumetricMesh m;
      try {
        m = linear_mesh(surface, scaled(base, f));
      } catch (const SolverError&) {
        // TetGen 1.5.0 can abort locating a point in the background mesh (scoutpoint: "ori4 != 0"; seen on
        // midpoint-subdivided surfaces, whose facets are coplanar in fours): the sizes at the surface
        // vertices alone then size the interior (interpolated inside: no finer than the surface, not graded)
        if (base.background_T.rows() == 0) throw;
        base.background_T.resize(0, 4);
        base.background_X.resize(0, 3);
        base.background_sizes.clear();
        m = linear_mesh(surface, scaled(base, f));
      }
      const double got = keep(std::move(m));
      if (best_err <= s.target_nodes / 20 || (f == 1.0 && got <= interior)) break;
      f = std::max(1.0, f * std::cbrt(got / interior));
    }
    return best;
  }
  // first guess: interior nodes ~ volume / a * 0.2 (TetGen's quality meshes have ~5-6 tets per node and
  // mean tet volume ~ a / 2)
  const double vol = surface.num_faces() > 0 ? std::abs(signed_volume(surface.V, surface.F)) : 0.0;
  double a = vol / (interior * 2.5);
  for (int it = 0; it < s.attempts; ++it) {
    TetgenSettings ts;
    ts.max_volume = a;
    ts.radius_edge = s.radius_edge;
    const double got = keep(linear_mesh(surface, ts));
    if (best_err <= s.target_nodes / 20) break;  // within 5 %
    a *= got / interior;                         // interior node count ~ 1 / a
  }
  return best;
}

}  // namespace medspring::fem
