#include "medspring/fem/volumetric.hpp"

#include <cmath>
#include <string>

#include "medspring/core/check.hpp"
#include "medspring/fem/organ.hpp"

namespace medspring::fem {

namespace {

VolumetricMesh linear_mesh(const SurfaceMesh& surface, double max_volume, double radius_edge) {
  TetgenSettings ts;
  ts.max_volume = max_volume;
  ts.radius_edge = radius_edge;
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

}  // namespace

VolumetricMesh volumetric_mesh(const SurfaceMesh& given, const VolumetricMeshSettings& s) {
  require(s.surface_subdivisions >= 0 && s.surface_subdivisions <= 3,
          "volumetric mesh: surface_subdivisions must be in [0, 3] (got ", s.surface_subdivisions, ")");
  SurfaceMesh surface = given;
  for (int i = 0; i < s.surface_subdivisions; ++i) surface = subdivide_midpoint(surface);
  require(
      s.target_nodes >= surface.num_vertices(), "volumetric mesh: target_nodes ", s.target_nodes,
      " is below the surface's ", surface.num_vertices(), " vertices",
      s.surface_subdivisions > 0 ? cat(" (after ", s.surface_subdivisions, " subdivisions)") : std::string());
  require(s.attempts >= 1, "volumetric mesh: attempts must be >= 1");
  // first guess: interior nodes ~ volume / a * 0.2 (TetGen's quality meshes have ~5-6 tets per node and
  // mean tet volume ~ a / 2)
  const double vol = surface.num_faces() > 0 ? std::abs(signed_volume(surface.V, surface.F)) : 0.0;
  const double interior = std::max<double>(1.0, static_cast<double>(s.target_nodes - surface.num_vertices()));
  double a = vol / (interior * 2.5);
  VolumetricMesh best;
  Index best_err = -1;
  for (int it = 0; it < s.attempts; ++it) {
    VolumetricMesh m = linear_mesh(surface, a, s.radius_edge);
    const Index n = static_cast<Index>(m.X.rows());
    const Index err = std::abs(n - s.target_nodes);
    if (best_err < 0 || err < best_err) {
      best = std::move(m);
      best_err = err;
    }
    if (err <= s.target_nodes / 20) break;  // within 5 %
    const double got = std::max<double>(1.0, static_cast<double>(n - surface.num_vertices()));
    a *= got / interior;  // interior node count ~ 1 / a
  }
  return best;
}

}  // namespace medspring::fem
