// The plain surface mass-spring body (ALGORITHMS.md §1): every surface node is a DOF.
//
// Locality (issue 15): a large mesh whose numbering scatters neighbours (bandwidth more than twice that
// of its reverse Cuthill-McKee order, geometry/locality.hpp) is simulated in that order: the model's
// nodes (the DOFs, state.x) are the surface nodes renumbered, and the body maps the numbers both ways.
// Everything indexed by surface node (loads, fixed nodes, tool contact, local patches, surface(),
// normals, output files) keeps the mesh's own numbering; only the raw DOF arrays (model(), state.x/v,
// Python positions/velocities) are in the model's order, dof_of_surface() relating the two.
#pragma once

#include "medspring/geometry/locality.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/models/body.hpp"

namespace medspring {

class SurfaceBody final : public Body {
 public:
  SurfaceBody(const SurfaceMesh& mesh, const SurfaceBodyParams& params, std::string name = "surface",
              GridLayout grid = {});
  std::string kind() const override { return "surface"; }
  const Model& model() const override { return model_; }
  const MatX3i& faces() const override { return F_; }
  const MatX3& rest_surface() const override { return dof_of_surface_.empty() ? model_.x0 : rest_surface_; }
  void map_to_surface(const State& state, MatX3& surface) const override;
  void transfer_force(Index node, const Vec3& F, MatX3& f_dof) const override;
  GridLayout grid() const override { return grid_; }
  double local_stiffness() const override { return k_; }
  std::vector<std::uint8_t> fixed_surface_nodes() const override;
  /// The parameters it was built with.
  const SurfaceBodyParams& params() const { return params_; }
  /// The DOF (model node) of every surface node; empty when they coincide (small, grid or well-ordered
  /// meshes).
  const std::vector<Index>& dof_of_surface() const { return dof_of_surface_; }
  Index dof_of(Index surface_node) const {
    return dof_of_surface_.empty() ? surface_node : dof_of_surface_[static_cast<std::size_t>(surface_node)];
  }

 private:
  Model model_;
  MatX3i F_;
  MatX3 rest_surface_;                 // the mesh's vertices in its own order (only when reordered)
  std::vector<Index> dof_of_surface_;  // surface node -> DOF (empty: identity)
  GridLayout grid_;
  SurfaceBodyParams params_;
  double k_;
};

}  // namespace medspring
