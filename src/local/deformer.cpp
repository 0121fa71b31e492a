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

std::size_t LocalDeformer::select(Index contact) {
  if (settings_.cache_local && contact >= 0)
    for (std::size_t i = 0; i < cache_.size(); ++i)
      if (cache_[i].contact == contact) {
        cache_[i].used = ++clock_;
        return i;
      }
  // a new factor (or every call without cache_local, the paper's path): an entry left invalid by a
  // failed select, a free slot, or the least recently used
  std::size_t slot = 0;
  while (slot < cache_.size() && cache_[slot].contact >= 0) ++slot;
  if (slot == cache_.size() &&
      (cache_.empty() || (settings_.cache_local && cache_.size() < kCachedPatches))) {
    cache_.emplace_back();
  } else if (slot == cache_.size()) {
    slot = 0;
    if (settings_.cache_local)
      for (std::size_t i = 1; i < cache_.size(); ++i)
        if (cache_[i].used < cache_[slot].used) slot = i;
  }
  Entry& e = cache_[slot];
  e.contact = -1;  // until the factor is complete (select may throw)
  e.patch = structured_ ? structured_window_patch(rings_, spokes_, contact, settings_.patch, fixed_)
                        : bfs_local_patch(adj_, X_, contact, settings_.patch, fixed_);
  e.solver.precompute(e.patch, X_, settings_.solver);
  e.contact = settings_.cache_local ? contact : -1;
  e.used = ++clock_;
  return slot;
}

void LocalDeformer::prepare(Index contact) {
  select(contact);  // without cache_local: still selected and factored once here, so that set-up errors
                    // surface now
}

LocalSolveInfo LocalDeformer::compute(Index contact, const Vec3& F, MatX3& U) {
  active_ = select(contact);  // §6.5 cache_local
  return cache_[active_].solver.solve(F, U);
}

const LocalPatch& LocalDeformer::patch() const {
  static const LocalPatch none;
  return cache_.empty() ? none : cache_[active_].patch;
}

const LocalSolver& LocalDeformer::solver() const {
  static const LocalSolver none;
  return cache_.empty() ? none : cache_[active_].solver;
}

}  // namespace medspring
