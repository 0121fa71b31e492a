#include "medspring/models/surface_body.hpp"

#include "medspring/core/check.hpp"
#include "medspring/core/memory.hpp"
#include "medspring/geometry/locality.hpp"

namespace medspring {

SurfaceBody::SurfaceBody(const SurfaceMesh& mesh, const SurfaceBodyParams& params, std::string name,
                         GridLayout grid)
    : F_(mesh.F), grid_(grid), params_(params), k_(params.k) {
  if (grid_.valid())
    require(grid_.rings * grid_.spokes == mesh.num_vertices(), name, ": grid ", grid_.rings, " x ",
            grid_.spokes, " does not match ", mesh.num_vertices(), " nodes");
  require_memory(kModelBuildBytesPerNode * static_cast<double>(mesh.num_vertices()),
                 cat(name, ": a model of ", mesh.num_vertices(), " nodes"));  // before any work
  if (!grid_.valid() && mesh.num_vertices() >= kLocalityReorderMinNodes) {
    // errors name the user's numbering: check the mesh and the fixed nodes before renumbering
    require_valid_mesh(mesh, name, {.closed = false, .manifold = false});
    for (std::size_t q = 0; q < params.fixed.size(); ++q)
      require_index(params.fixed[q], mesh.num_vertices(), name, ": fixed[", q, "]");
    const std::vector<Index> order = locality_order(mesh);  // order[dof] = surface node
    SurfaceMesh ordered = permute_vertices(mesh, order);
    if (2 * mesh_bandwidth(ordered) < mesh_bandwidth(mesh)) {
      dof_of_surface_ = inverse_permutation(order);
      SurfaceBodyParams p = params;
      for (Index& f : p.fixed) f = dof_of_surface_[static_cast<std::size_t>(f)];
      model_ = make_surface_model(ordered, p, name);
      rest_surface_ = mesh.V;
      return;
    }
  }
  model_ = make_surface_model(mesh, params, name);
}

void SurfaceBody::map_to_surface(const State& state, MatX3& surface) const {
  if (dof_of_surface_.empty()) {
    surface = state.x;  // identity map (no reallocation when sizes match)
    return;
  }
  const Index n = static_cast<Index>(dof_of_surface_.size());
  surface.resize(n, 3);
  for (Index s = 0; s < n; ++s) surface.row(s) = state.x.row(dof_of_surface_[static_cast<std::size_t>(s)]);
}

void SurfaceBody::transfer_force(Index node, const Vec3& F, MatX3& f_dof) const {
  f_dof.row(dof_of(node)) += F.transpose();
}

std::vector<std::uint8_t> SurfaceBody::fixed_surface_nodes() const {
  if (dof_of_surface_.empty()) return model_.fixed;
  std::vector<std::uint8_t> out(dof_of_surface_.size());
  for (std::size_t s = 0; s < out.size(); ++s)
    out[s] = model_.fixed[static_cast<std::size_t>(dof_of_surface_[s])];
  return out;
}

}  // namespace medspring
