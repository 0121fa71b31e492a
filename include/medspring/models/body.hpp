// A simulated organ = physics degrees of freedom + a map to the surface the user sees (DESIGN.md).
#pragma once

#include <memory>
#include <string>

#include "medspring/core/types.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/physics/state.hpp"

namespace medspring {

/// Structured tube-grid layout of a surface (rings x spokes, node i*spokes + j), when it has one.
struct GridLayout {
  Index rings = 0, spokes = 0;
  bool valid() const { return rings > 0 && spokes > 0; }
};

/// The three model kinds of MedSpring implement this interface:
///  - SurfaceBody (plain surface mass-spring, identity map),
///  - HybridKidney (surface + centerline atoms tied by spokes, identity on the surface nodes),
///  - SmrmVessel (centerline chain; surface rebuilt from rings of spokes, eqs. 3-4).
/// A force on a surface node travels the map backwards (transfer_force); positions travel it
/// forwards (map_to_surface). Both are called once per update (not per spring): virtual is fine.
class Body {
 public:
  virtual ~Body() = default;
  /// "surface", "hybrid" or "smrm".
  virtual std::string kind() const = 0;
  /// The physics model integrated by the engine.
  virtual const Model& model() const = 0;
  /// Surface triangles (#F x 3) over the surface nodes.
  virtual const MatX3i& faces() const = 0;
  /// Rest positions of the surface nodes (#S x 3), mm.
  virtual const MatX3& rest_surface() const = 0;
  Index num_surface_nodes() const { return static_cast<Index>(rest_surface().rows()); }
  /// Writes the surface positions for the physics state (forward map). surface is resized if needed
  /// (no allocation once it has the right size).
  virtual void map_to_surface(const State& state, MatX3& surface) const = 0;
  /// Adds the DOF forces equivalent to a force F (N) on surface node `node` to f_dof (#N x 3).
  virtual void transfer_force(Index node, const Vec3& F, MatX3& f_dof) const = 0;
  /// The structured grid layout of the surface, if any (vessel tube grid), for the 5 x 5 local window.
  virtual GridLayout grid() const { return {}; }
  /// Surface springs' stiffness used for the local patch (k_loc default), N/mm.
  virtual double local_stiffness() const = 0;
  /// Compliance multiplier a of the local overlay (the patch springs get k_loc / a; 0 = no overlay). 1 unless
  /// the model stores a calibrated one (VolumetricSettings::overlay_compliance).
  virtual double local_compliance() const { return 1.0; }
  /// True when a force spread over several surface nodes (a tool's contact area, a disk load) gets the
  /// overlay of its own nodal forces on the patch of the loaded nodes plus one ring (local/distributed.hpp),
  /// the form the volumetric kind's overlay_compliance is calibrated with; false: the whole force on the
  /// contact node (§6.3).
  virtual bool distributed_local() const { return false; }
  /// Surface nodes fixed by the model (excluded from local patches). Empty = none.
  virtual std::vector<std::uint8_t> fixed_surface_nodes() const { return {}; }
  /// Spoke length (distance surface node -> its atom) at rest, used by the local-deformation guard
  /// of §6.5; 0 where the model has no atoms.
  virtual double spoke_length(Index /*node*/) const { return 0.0; }
};

using BodyPtr = std::shared_ptr<const Body>;

}  // namespace medspring
