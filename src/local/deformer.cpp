#include "medspring/local/deformer.hpp"

#include <utility>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

void validate(const LocalDeformationSettings& s, Index n, const MatX3& X,
              const std::vector<std::uint8_t>& fixed, const char* what) {
  require_positive(s.patch.k_loc, cat(what, ": k_loc"));
  require(fixed.empty() || static_cast<Index>(fixed.size()) == n, what, ": model-fixed flags have ",
          fixed.size(), " entries, the mesh has ", n, " nodes");
  const bool needs_X =
      s.solver.stiffness == LocalStiffness::Linearized || s.solver.stiffness == LocalStiffness::AxisProjected;
  require(!needs_X || X.rows() == n, what, " (", to_string(s.solver.stiffness), "): positions have ",
          X.rows(), " rows, the mesh has ", n, " nodes");
  if (X.rows() > 0) require_finite_points(X, cat(what, ": positions"));
}

}  // namespace

LocalDeformer LocalDeformer::tube(Index rings, Index spokes, const LocalDeformationSettings& settings,
                                  MatX3 X, std::vector<std::uint8_t> fixed) {
  require(rings >= 2 && spokes >= 3, "local deformation (tube): grid of ", rings, " rings x ", spokes,
          " spokes is too small (needs >= 2 x 3)");
  validate(settings, rings * spokes, X, fixed, "local deformation (tube)");
  LocalDeformer d;
  d.settings_ = settings;
  d.structured_ = true;
  d.rings_ = rings;
  d.spokes_ = spokes;
  d.X_ = std::move(X);
  d.fixed_ = std::move(fixed);
  return d;
}

LocalDeformer LocalDeformer::mesh(Adjacency adj, MatX3 X0, const LocalDeformationSettings& settings,
                                  std::vector<std::uint8_t> fixed) {
  const Index n = adj.num_nodes();
  require(n > 0, "local deformation (mesh): the adjacency has no nodes");
  require(X0.rows() == n, "local deformation (mesh): rest positions have ", X0.rows(), " rows, the mesh has ",
          n, " nodes");
  validate(settings, n, X0, fixed, "local deformation (mesh)");
  LocalDeformer d;
  d.settings_ = settings;
  d.adj_ = std::move(adj);
  d.X_ = std::move(X0);
  d.fixed_ = std::move(fixed);
  return d;
}

void LocalDeformer::select(Index contact) {
  cached_ = false;
  patch_ = structured_ ? structured_window_patch(rings_, spokes_, contact, settings_.patch, fixed_)
                       : bfs_local_patch(adj_, X_, contact, settings_.patch, fixed_);
  solver_.precompute(patch_, X_, settings_.solver);
  cached_contact_ = contact;
  cached_ = settings_.cache_local;
}

LocalSolveInfo LocalDeformer::compute(Index contact, const Vec3& F, MatX3& U) {
  if (!cached_ || contact != cached_contact_) select(contact);  // §6.5 cache_local
  return solver_.solve(F, U);
}

}  // namespace medspring
