// The SceneLoader of the medspring command and the Python module, written once: file readers, isosurfaces,
// balloon surfaces and tetrahedral meshes come from hooks that each host fills from the layers it was built
// with (io: VTK readers; meshing: CGAL; fem: TetGen), and this class adds what both need — meshes cached per
// file and unit, balloon surfaces cached per organ and node count (the paper's four kidney scenes remesh
// the kidney once), and a one-line error naming the missing layer where a hook is empty.
//
//   SceneFileAccess a;
//   a.read_mesh = [](const fs::path& f, LengthUnit u) { return read_mesh(f, {.unit = u}); };  // io layer
//   CachingSceneLoader loader(std::move(a));
//   BuiltScene b = build_scene(scene, &loader);
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "medspring/scene/build.hpp"

namespace medspring {

/// A balloon surface and one line per finding worth reporting (distance to the organ, warnings).
struct BalloonSurface {
  SurfaceMesh mesh;
  std::vector<std::string> notes;
};

/// The hooks of a CachingSceneLoader; an empty one is refused with a line naming its layer.
struct SceneFileAccess {
  std::function<SurfaceMesh(const std::filesystem::path&, LengthUnit)> read_mesh;  // io
  std::function<std::vector<Centerline>(const std::filesystem::path&, LengthUnit, const std::string&)>
      read_centerlines;                                                                 // io
  std::function<LabelVolume(const std::filesystem::path&)> read_label_volume;           // io
  std::function<SurfaceMesh(const MaskVolume&)> isosurface;                             // meshing
  std::function<BalloonSurface(const SurfaceMesh&, Index)> balloon;                     // meshing
  std::function<VolumetricMesh(const SurfaceMesh&, Index, MeshSizing)> tetrahedralize;  // fem
  std::function<SurfaceMesh(const CenterlineTree&, const SmrmTree&, double, std::vector<std::string>&)>
      tree_surface;  // builders (CGAL union of the path tubes)
  std::function<std::shared_ptr<const SmrmTree>(const OrganTreeRequest&, std::vector<std::string>&)>
      organ_tree;  // builders (build_vessel of a mesh / segmentation, all branches)
};

class CachingSceneLoader : public SceneLoader {
 public:
  explicit CachingSceneLoader(SceneFileAccess access) : access_(std::move(access)) {}
  SurfaceMesh read_mesh(const std::filesystem::path& file, LengthUnit unit) override;
  std::vector<Centerline> read_centerlines(const std::filesystem::path& file, LengthUnit unit,
                                           const std::string& radius_array) override;
  LabelVolume read_label_volume(const std::filesystem::path& file) override;
  SurfaceMesh isosurface(const MaskVolume& mask) override;
  /// A balloon built earlier for the same organ and node count is reused (its notes say so).
  SurfaceMesh balloon(const SurfaceMesh& organ, Index nodes, std::vector<std::string>& notes) override;
  VolumetricMesh tetrahedralize(const SurfaceMesh& organ, Index nodes, MeshSizing sizing) override;
  SurfaceMesh tree_surface(const CenterlineTree& tree, const SmrmTree& plain, double spacing,
                           std::vector<std::string>& notes) override;
  std::shared_ptr<const SmrmTree> organ_tree(const OrganTreeRequest& request,
                                             std::vector<std::string>& notes) override;

 private:
  SceneFileAccess access_;
  std::map<std::string, SurfaceMesh> meshes_;
  struct Balloon {
    SurfaceMesh organ, mesh;
    std::vector<std::string> notes;
  };
  std::vector<Balloon> balloons_;
};

}  // namespace medspring
