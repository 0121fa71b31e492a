// One simulated organ over time: a Body, its state, loads on surface nodes and the local-deformation
// overlay. One update (D-18) = loads -> DOF forces -> step -> map to the surface -> + local U; normals when
// read.
//
//   Simulation sim(std::make_shared<HybridKidney>(hybrid_kidney_phantom()));
//   sim.set_loads({{.node = 223, .force = {0, 0, -1}, .t_release = 500}});
//   while (sim.time() < 1000) sim.update();
//   const MatX3& S = sim.surface();                      // displayed surface (#S x 3), mm
#pragma once

#include <optional>
#include <vector>

#include "medspring/local/deformer.hpp"
#include "medspring/local/distributed_overlay.hpp"
#include "medspring/models/body.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/tools/contact.hpp"

namespace medspring {

struct LocalOptions {
  bool enabled = false;               // eq. (6) overlay while a force acts (§6.5)
  LocalDeformationSettings settings;  // patch (k_loc, 5 x 5 window / 25-node BFS), mode, cache_local
  bool use_body_stiffness = true;     // k_loc = Body::local_stiffness() (kidney: k_surf; vessel 0.05)
  bool guard = false;                 // §6.5: limit |U_c| to 0.9 x the contact's spoke length
};

/// The declaration of LocalOptions (core/params.hpp): the scene's "local" block, the Python properties
/// and keywords, `run --set local.NAME=VALUE`, the table in docs/parameters.md. In a scene file a "local"
/// object means enabled unless it says otherwise, and a "k_loc" turns use_body_stiffness off (scene.cpp).
template <ParamOf<LocalOptions> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"enabled", "", "eq. (6) overlay while a force acts (§6.5)"}, s.enabled);
  v(ParamSpec{"stiffness", "",
              "patch stiffness (§6.2): isotropic, linearized, axis_projected or paper_literal"},
    s.settings.solver.stiffness);
  v(ParamSpec{"k_loc", "N/mm", "patch spring stiffness (default: the body's own, k_surf or 0.05)"}.positive(),
    s.settings.patch.k_loc);
  v(ParamSpec{"cache", "", "keep the factor while the contact node stays the same (§6.5)"},
    s.settings.cache_local);
  v(ParamSpec{"guard", "", "limit |U_c| to 0.9 x the contact's spoke length (§6.5)"}, s.guard);
  v(ParamSpec{"patch_nodes", "", "nodes of a BFS patch (unstructured surfaces)"}.at_least(2),
    s.settings.patch.count);
  v(ParamSpec{"half_width", "", "half-width of the structured window (2: 5 x 5)"}.at_least(1),
    s.settings.patch.half_width);
}

struct SimulationSettings {
  StepSettings step{};  // dt 0.5 ms, symplectic Euler, sub-stepping on
  LocalOptions local{};
  bool normals = true;  // vertex normals available (computed lazily when read after an update; false: none)
};

class Simulation {
 public:
  explicit Simulation(BodyPtr body, const SimulationSettings& settings = {});

  /// Loads on SURFACE nodes (the body transfers them to its DOFs). Validated: throws InvalidInput
  /// naming "loads[k].field".
  void set_loads(std::vector<PointLoad> loads);
  const std::vector<PointLoad>& loads() const { return loads_; }
  /// External tool force F (N) on SURFACE node `node`, added to the loads in every update until it is
  /// changed or cleared: the per-tick force of a haptic virtual coupling (§2.5, sim/haptics.hpp). A
  /// new node gets its local patch factored here (throws InvalidInput for a bad node or force).
  void set_tool_force(Index node, const Vec3& F);
  void clear_tool_force() { tool_node_ = -1; }
  /// The tool's node (-1 when none) and force.
  Index tool_node() const { return tool_node_; }
  const Vec3& tool_force() const { return tool_force_; }

  /// Forces on surface nodes from rigid tools (tools/contact.hpp, sim/tool_sim.hpp) or a distributed load
  /// (a disk), refreshed by their owner before every update and added to that update's loads; they get
  /// the local overlay when their total force is the largest load: on a body with distributed_local()
  /// (volumetric) and two or more loaded nodes, the patch of the loaded nodes plus one ring under their own
  /// nodal forces (local/distributed_overlay.hpp, factored when the loaded set changes); otherwise the
  /// whole force on the centre node. nullptr: none. The pointee must outlive its use. A new centre's patch
  /// is factored and the distributed patch's workspace sized here (throws InvalidInput for a node out of
  /// range).
  void set_surface_forces(const SurfaceForces* forces);
  /// A force re-evaluated at every substep of update() (physics/integrators.hpp; the tools' contact at
  /// the substep rate, sim/tool_sim.hpp). nullptr: none. The pointee must outlive its use.
  void set_substep_force(const SubstepForce* force) { substep_force_ = force; }

  /// Advances one frame of settings.step.dt and refreshes the displayed surface. Never throws;
  /// numerical trouble is in the returned status and state().warnings.
  StepStatus update();
  /// Runs `frames` updates; returns the status of the last one that was not Ok (or Ok).
  StepStatus advance(long frames);

  double time() const { return state_.t; }
  const Body& body() const { return *body_; }
  BodyPtr body_ptr() const { return body_; }
  const Model& model() const { return body_->model(); }
  const State& state() const { return state_; }
  State& state() { return state_; }
  /// Displayed surface (#S x 3, mm): mapped global positions + local overlay.
  const MatX3& surface() const { return surface_; }
  /// Global (mapped) surface without the local overlay.
  const MatX3& global_surface() const { return global_; }
  /// Area-weighted unit vertex normals of surface() (empty unless settings.normals). Computed on demand:
  /// an update only marks them stale, and the first read after it recomputes them (a renderer reading
  /// once per displayed frame pays once per frame, not once per 0.5 ms update). The returned matrix
  /// keeps its storage; it holds the current normals until the next update.
  const MatX3& normals() const;
  /// Displacement of the displayed surface from rest (#S x 3).
  MatX3 displacement() const { return surface_ - body_->rest_surface(); }
  /// Total external force currently applied (loads + tool force, N) = minus the reaction on the tool.
  Vec3 applied_force() const;
  /// The local patch (global surface indices) and its displacement (#P x 3, mm) of the last update (empty
  /// if none).
  const std::vector<Index>& local_nodes() const;
  Eigen::Ref<const MatX3> local_displacement() const;
  const SimulationSettings& settings() const { return settings_; }
  void set_settings(const SimulationSettings& settings);
  /// Back to rest: x = x0, v = 0, t = 0 (loads kept).
  void reset();
  /// Replaces the state (e.g. restored checkpoint); sizes must match the model.
  void set_state(const State& state);

 private:
  void refresh_surface();

  BodyPtr body_;
  SimulationSettings settings_;
  State state_;
  std::vector<PointLoad> loads_;
  MatX3 global_, surface_, U_;
  mutable MatX3 normals_;  // valid when !normals_stale_ (see normals())
  mutable bool normals_stale_ = true;
  std::optional<LocalDeformer> local_;
  std::optional<DistributedOverlay> spread_;  // distributed_local() bodies: the patch of a distributed load
  bool local_active_ = false, spread_active_ = false;
  Index tool_node_ = -1;
  Vec3 tool_force_ = Vec3::Zero();
  const SurfaceForces* surface_forces_ = nullptr;
  const SubstepForce* substep_force_ = nullptr;
};

}  // namespace medspring
