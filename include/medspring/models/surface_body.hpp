// The plain surface mass-spring body (ALGORITHMS.md §1): every surface node is a DOF.
#pragma once

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
  const MatX3& rest_surface() const override { return model_.x0; }
  void map_to_surface(const State& state, MatX3& surface) const override;
  void transfer_force(Index node, const Vec3& F, MatX3& f_dof) const override;
  GridLayout grid() const override { return grid_; }
  double local_stiffness() const override { return k_; }
  std::vector<std::uint8_t> fixed_surface_nodes() const override { return model_.fixed; }
  /// The parameters it was built with.
  const SurfaceBodyParams& params() const { return params_; }

 private:
  Model model_;
  MatX3i F_;
  GridLayout grid_;
  SurfaceBodyParams params_;
  double k_;
};

}  // namespace medspring
