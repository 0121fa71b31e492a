#include "medspring/models/surface_body.hpp"

#include "medspring/core/check.hpp"

namespace medspring {

SurfaceBody::SurfaceBody(const SurfaceMesh& mesh, const SurfaceBodyParams& params, std::string name,
                         GridLayout grid)
    : model_(make_surface_model(mesh, params, name)), F_(mesh.F), grid_(grid), params_(params), k_(params.k) {
  if (grid_.valid())
    require(grid_.rings * grid_.spokes == mesh.num_vertices(), name, ": grid ", grid_.rings, " x ",
            grid_.spokes, " does not match ", mesh.num_vertices(), " nodes");
}

void SurfaceBody::map_to_surface(const State& state, MatX3& surface) const {
  surface = state.x;  // identity map (no reallocation when sizes match)
}

void SurfaceBody::transfer_force(Index node, const Vec3& F, MatX3& f_dof) const {
  f_dof.row(node) += F.transpose();
}

}  // namespace medspring
