#include "medspring/sim/simulation.hpp"

#include <cmath>

#include "medspring/core/check.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/local/overlay.hpp"

namespace medspring {

Simulation::Simulation(BodyPtr body, const SimulationSettings& settings) : body_(std::move(body)) {
  require(body_ != nullptr, "simulation: no body");
  state_ = make_state(body_->model(), settings.step);
  set_settings(settings);
}

void Simulation::set_settings(const SimulationSettings& s) {
  validate_step_settings(body_->model(), s.step);
  settings_ = s;
  prepare_step(body_->model(), state_, settings_.step);  // worker pool started here, not in update()
  local_.reset();
  spread_.reset();
  local_active_ = spread_active_ = false;
  // the overlay's compliance multiplier a (VolumetricSettings::overlay_compliance): k_loc / a; a = 0: none
  const double a = body_->local_compliance();
  require(std::isfinite(a) && a >= 0, "simulation: the body's local overlay compliance must be >= 0 (got ", a,
          ")");
  if (s.local.enabled && a > 0) {
    LocalDeformationSettings ls = s.local.settings;
    if (s.local.use_body_stiffness) ls.patch.k_loc = body_->local_stiffness();
    ls.patch.k_loc /= a;
    const GridLayout g = body_->grid();
    std::vector<std::uint8_t> fixed = body_->fixed_surface_nodes();
    if (g.valid()) {
      local_ = LocalDeformer::tube(g.rings, g.spokes, ls, body_->rest_surface(), fixed);
    } else {
      Adjacency adj = vertex_adjacency(body_->num_surface_nodes(), unique_edges(body_->faces()));
      if (body_->distributed_local() && ls.solver.stiffness == LocalStiffness::Isotropic)
        spread_.emplace(adj, ls.patch.k_loc, fixed);  // the calibrated form (Isotropic, one ring)
      local_ = LocalDeformer::mesh(std::move(adj), body_->rest_surface(), ls, fixed);
    }
  }
  refresh_surface();
}

void Simulation::set_loads(std::vector<PointLoad> loads) {
  validate_loads(loads, body_->num_surface_nodes());
  if (local_)  // factor every contact patch now, so that update() never meets a set-up error
    for (const PointLoad& L : loads) local_->prepare(L.node);
  loads_ = std::move(loads);
}

void Simulation::set_tool_force(Index node, const Vec3& F) {
  require_index(node, body_->num_surface_nodes(), "tool force: surface node");
  require(F.allFinite(), "tool force on node ", node, " must be finite");
  if (local_ && node != tool_node_) local_->prepare(node);  // factored now: update() never throws
  tool_node_ = node;
  tool_force_ = F;
}

void Simulation::set_surface_forces(const SurfaceForces* forces) {
  if (forces && local_ && forces->centre >= 0 && forces->total.allFinite()) {
    require_index(forces->centre, body_->num_surface_nodes(), "surface forces: centre node");
    local_->prepare(forces->centre);  // a new centre's patch factored now, a cached one found
    if (spread_ && forces->nodes.size() > 1) {
      require(forces->force.rows() == body_->num_surface_nodes(), "surface forces: force has ",
              forces->force.rows(), " rows, the surface has ", body_->num_surface_nodes(), " nodes");
      // the workspace sized for this patch here, not in update(); validates the nodes
      spread_->reserve(spread_->patch_size_of(forces->nodes));
    }
  }
  surface_forces_ = forces;
}

Vec3 Simulation::applied_force() const {
  Vec3 F = tool_node_ >= 0 ? tool_force_ : Vec3::Zero();
  if (surface_forces_) F += surface_forces_->total;
  for (const PointLoad& L : loads_) F += L.at(state_.t);
  return F;
}

StepStatus Simulation::update() {
  // loads at the frame start, held over the frame, transferred to the DOFs (D-14 for the vessel)
  state_.f_ext.setZero();
  for (const PointLoad& L : loads_) {
    const double s = L.scale(state_.t);
    if (s != 0.0) body_->transfer_force(L.node, s * L.force, state_.f_ext);
  }
  if (tool_node_ >= 0) body_->transfer_force(tool_node_, tool_force_, state_.f_ext);
  if (surface_forces_)
    for (const Index n : surface_forces_->nodes)
      body_->transfer_force(n, surface_forces_->force.row(n).transpose(), state_.f_ext);
  const StepStatus st = step(body_->model(), state_, settings_.step, nullptr, substep_force_);
  refresh_surface();
  return st;
}

StepStatus Simulation::advance(long frames) {
  StepStatus worst;
  for (long i = 0; i < frames; ++i) {
    const StepStatus s = update();
    if (s.code != StepCode::Ok) worst = s;
  }
  return worst;
}

void Simulation::refresh_surface() {
  body_->map_to_surface(state_, global_);
  surface_ = global_;
  local_active_ = spread_active_ = false;
  if (local_) {
    // contact = the loaded node with the largest current force (eq. 6 uses the same force)
    Index contact = -1;
    Vec3 F = Vec3::Zero();
    double best = 0;
    if (tool_node_ >= 0 && tool_force_.norm() > 0) {
      best = tool_force_.norm();
      contact = tool_node_;
      F = tool_force_;
    }
    bool surface = false;  // the surface forces are the largest load
    if (surface_forces_ && surface_forces_->centre >= 0 && surface_forces_->total.norm() > best) {
      best = surface_forces_->total.norm();
      contact = surface_forces_->centre;
      F = surface_forces_->total;
      surface = true;
    }
    for (const PointLoad& L : loads_) {
      const Vec3 f = L.at(state_.t);
      if (f.norm() > best) {
        best = f.norm();
        contact = L.node;
        F = f;
        surface = false;
      }
    }
    // a distributed load: its own nodal forces on the patch of its nodes (the calibrated disk overlay)
    if (spread_ && surface && surface_forces_->nodes.size() > 1) {
      if (spread_->prepare(surface_forces_->nodes)) {  // factored only when the loaded set changed
        spread_->solve(surface_forces_->force);
        const auto U = spread_->displacement();
        for (Index a = 0; a < spread_->size(); ++a) surface_.row(spread_->nodes()[a]) += U.row(a);  // §6.5
        local_active_ = spread_active_ = true;
      }
    } else if (contact >= 0) {
      local_->compute(contact, F, U_);  // may throw only when a new patch is factored (set-up error)
      if (settings_.local.guard && body_->spoke_length(contact) > 0)
        limit_local_displacement(local_->patch(), U_, body_->spoke_length(contact), {});
      apply_local_overlay(local_->patch(), U_, surface_);
      local_active_ = true;
    }  // else U_ keeps its storage for the next contact; local_displacement() reads empty
  }
  normals_stale_ = true;  // recomputed when read (normals())
}

const MatX3& Simulation::normals() const {
  if (normals_stale_) {
    if (settings_.normals)
      vertex_normals(surface_, body_->faces(), normals_);
    else
      normals_.resize(0, 3);
    normals_stale_ = false;
  }
  return normals_;
}

const std::vector<Index>& Simulation::local_nodes() const {
  static const std::vector<Index> none;
  if (spread_active_) return spread_->nodes();
  return local_ && local_active_ ? local_->patch().nodes : none;
}

Eigen::Ref<const MatX3> Simulation::local_displacement() const {
  static const MatX3 none(0, 3);
  if (spread_active_) return spread_->displacement();
  return local_ && local_active_ ? U_ : none;
}

void Simulation::reset() {
  state_ = make_state(body_->model(), settings_.step);
  if (local_) local_->invalidate();
  refresh_surface();
}

void Simulation::set_state(const State& s) {
  require_state_in_reach(body_->model(), s.x, s.v, "simulation");
  State t = make_state(body_->model(), settings_.step);
  t.x = s.x;
  t.v = s.v;
  t.t = s.t;
  t.frames = s.frames;
  t.substeps = s.substeps;
  t.stiffening = s.stiffening;
  t.warnings = s.warnings;
  state_ = std::move(t);
  prepare_step(body_->model(), state_, settings_.step);
  refresh_surface();
}

}  // namespace medspring
