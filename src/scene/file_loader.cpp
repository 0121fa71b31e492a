// CachingSceneLoader (scene/file_loader.hpp): the caches and the missing-layer errors of the file loader
// shared by the medspring command (apps/scene_support.cpp) and the Python module (python/src/bind_scene.cpp).
#include "medspring/scene/file_loader.hpp"

#include "medspring/core/check.hpp"

namespace medspring {

SurfaceMesh CachingSceneLoader::read_mesh(const std::filesystem::path& file, LengthUnit unit) {
  if (!access_.read_mesh)
    throw InvalidInput(cat(file.string(), ": reading meshes needs the io layer (VTK) in this build"));
  const std::string key = file.string() + "|" + to_string(unit);
  auto it = meshes_.find(key);
  if (it == meshes_.end()) it = meshes_.emplace(key, access_.read_mesh(file, unit)).first;
  return it->second;
}

std::vector<Centerline> CachingSceneLoader::read_centerlines(const std::filesystem::path& file,
                                                             LengthUnit unit,
                                                             const std::string& radius_array) {
  if (!access_.read_centerlines)
    throw InvalidInput(cat(file.string(), ": reading centerlines needs the io layer (VTK) in this build"));
  return access_.read_centerlines(file, unit, radius_array);
}

LabelVolume CachingSceneLoader::read_label_volume(const std::filesystem::path& file) {
  if (!access_.read_label_volume)
    throw InvalidInput(cat(file.string(), ": reading volumes needs the io layer (VTK) in this build"));
  return access_.read_label_volume(file);
}

SurfaceMesh CachingSceneLoader::isosurface(const MaskVolume& mask) {
  if (!access_.isosurface)
    throw InvalidInput("isosurfaces need the meshing layer (build with MEDSPRING_WITH_CGAL=ON)");
  return access_.isosurface(mask);
}

SurfaceMesh CachingSceneLoader::balloon(const SurfaceMesh& organ, Index nodes,
                                        std::vector<std::string>& notes) {
  if (!access_.balloon)
    throw InvalidInput(
        "model.surface_nodes: balloon remeshing needs the meshing layer (MEDSPRING_WITH_CGAL=ON)");
  for (const Balloon& b : balloons_)
    if (b.mesh.num_vertices() == nodes && b.organ.V == organ.V && b.organ.F == organ.F) {
      notes = b.notes;
      notes.push_back("(reused from an earlier scene of this run)");
      return b.mesh;
    }
  BalloonSurface r = access_.balloon(organ, nodes);
  balloons_.push_back({organ, r.mesh, r.notes});
  notes = std::move(r.notes);
  return std::move(r.mesh);
}

VolumetricMesh CachingSceneLoader::tetrahedralize(const SurfaceMesh& organ, Index nodes, MeshSizing sizing) {
  if (!access_.tetrahedralize) return SceneLoader::tetrahedralize(organ, nodes, sizing);  // refuses (TetGen)
  return access_.tetrahedralize(organ, nodes, sizing);
}

SurfaceMesh CachingSceneLoader::tree_surface(const CenterlineTree& tree, const SmrmTree& plain,
                                             double spacing, std::vector<std::string>& notes) {
  if (!access_.tree_surface) return SceneLoader::tree_surface(tree, plain, spacing, notes);  // refuses
  return access_.tree_surface(tree, plain, spacing, notes);
}

std::shared_ptr<const SmrmTree> CachingSceneLoader::organ_tree(const OrganTreeRequest& request,
                                                               std::vector<std::string>& notes) {
  if (!access_.organ_tree) return SceneLoader::organ_tree(request, notes);  // refuses
  return access_.organ_tree(request, notes);
}

}  // namespace medspring
