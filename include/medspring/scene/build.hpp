// Building the model of a scene: phantoms directly, files through a SceneLoader (the CLI's loader reads
// them with VTK and remeshes with CGAL; those stay out of the engine). The real kidney of the paper is
// balloon_surface(mesh, 458 nodes) + the 42 atoms of the skeleton of the voxelised mesh (§3.6, §4.4).
//
//   Scene scene = load_scene(file);
//   BuiltScene built = build_scene(scene, &loader);   // body, resolved loads, simulation settings
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "medspring/geometry/polyline.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/geometry/volume.hpp"
#include "medspring/models/smrm_tree.hpp"
#include "medspring/scene/scene.hpp"

namespace medspring {

/// A vessel tree from a mesh or a segmentation ("kind": "smrm", "branches": "all"): what the loader's
/// organ_tree builds, as `medspring build vessel --mesh F | --segmentation F --branches all` does.
struct OrganTreeRequest {
  std::filesystem::path mesh;  // a closed (or open-ended tube) surface mesh, or
  LengthUnit mesh_unit = LengthUnit::Millimetre;
  std::filesystem::path segmentation;  // a label volume (world mm) and its label
  std::int32_t label = 1;
  SmrmSettings smrm{};         // atoms, spokes, bending, chain
  bool blend = true;           // the watertight surface fitted to the wall; false: one open tube per branch
  double blend_spacing = 0.0;  // mm between the rings of its path tubes (0 = the atom spacing)
};

/// File access and surface meshing needed by file-based sources. Every function throws (IoError,
/// InvalidInput) naming the file at fault.
class SceneLoader {
 public:
  virtual ~SceneLoader() = default;
  /// A triangle mesh scaled to mm.
  virtual SurfaceMesh read_mesh(const std::filesystem::path& file, LengthUnit unit) = 0;
  /// Every polyline of a centerline file, scaled to mm, radii from `radius_array`.
  virtual std::vector<Centerline> read_centerlines(const std::filesystem::path& file, LengthUnit unit,
                                                   const std::string& radius_array) = 0;
  /// A label volume in world mm.
  virtual LabelVolume read_label_volume(const std::filesystem::path& file) = 0;
  /// The closed boundary surface of a mask (marching cubes), world mm.
  virtual SurfaceMesh isosurface(const MaskVolume& mask) = 0;
  /// A balloon surface of `organ` with exactly `nodes` nodes (§1.1, §4.4); `notes` receives one line
  /// per finding worth reporting (distance to the organ, warnings).
  virtual SurfaceMesh balloon(const SurfaceMesh& organ, Index nodes, std::vector<std::string>& notes) = 0;
  /// Linear tetrahedra of a closed surface with about `nodes` nodes, the surface's vertices first and its
  /// triangles as the boundary (TetGen -pqY; the volumetric model kind, issue 23). This default refuses
  /// (a loader without a tetrahedral mesher); the medspring command's and the Python module's mesh.
  virtual VolumetricMesh tetrahedralize(const SurfaceMesh& organ, Index nodes, MeshSizing sizing);
  /// The watertight junction surface of a vessel tree ("blend": true; the union of its closed path tubes
  /// with rings `spacing` mm apart, 0 = the atom spacing of `plain`, builders' blended_tree_surface);
  /// `notes` receives what it is. This default refuses (a loader without CGAL); the medspring command's
  /// and the Python module's unite the tubes.
  virtual SurfaceMesh tree_surface(const CenterlineTree& tree, const SmrmTree& plain, double spacing,
                                   std::vector<std::string>& notes);
  /// The vessel tree of a mesh or a segmentation, built as `medspring build vessel --branches all` builds
  /// it (builders' build_vessel: holes of a mask filled, the skeleton re-centred in its wall sections, the
  /// watertight surface fitted to the wall; docs/vessels.md); `notes` receives the build's notes and
  /// warnings. This default refuses (a loader without the builders layer); the medspring command's and
  /// the Python module's call build_vessel.
  virtual std::shared_ptr<const SmrmTree> organ_tree(const OrganTreeRequest& request,
                                                     std::vector<std::string>& notes);
};

/// A scene whose model is built and whose loads are resolved on surface nodes.
struct BuiltScene {
  Scene scene;
  BodyPtr body;
  SimulationSettings settings;         // step + local (+ normals)
  std::vector<PointLoad> loads;        // on surface nodes, force = magnitude x unit direction
  std::vector<Index> trace_nodes;      // load nodes first, then record.nodes (unique)
  std::vector<Index> trace_atoms;      // atom indices (hybrid, smrm)
  std::vector<Index> trace_atom_dofs;  // their DOF indices in the model
  MatX3 atoms_rest;                    // rest atoms (#A x 3, mm; empty for a surface model)
  Index atom_dof_begin = -1;           // DOF of atom 0 (atoms are consecutive DOFs); -1 without atoms
  double dt_safe_rest = 0.0;           // stable step of the model at rest (ms, §2.2)
  double build_seconds = 0.0;          // wall time to build the model
  std::vector<std::string> notes;      // what the build decided (sizes, remeshing, skeleton, ...)
};

/// Builds the model of `scene` and resolves its loads. `loader` may be null when the source is a
/// phantom. Throws InvalidInput naming the scene and JSON path for everything that can be checked only
/// on the model: a node or atom index out of range, a ring/spoke pick on a model without grid, a
/// picked point that is not finite, a direction that needs atoms on a surface model, a unit that makes
/// the organ implausibly small or large, an integrator.dt above the stable step with substep off.
BuiltScene build_scene(const Scene& scene, SceneLoader* loader);

/// As build_scene, but on the model of `prior` (built by build_scene from a scene with the same `model`
/// section): only settings and loads are resolved, so a study running many loads on one model builds it
/// once. The caller guarantees the model sections agree (the body is shared, not copied).
BuiltScene build_scene_reusing(const Scene& scene, const BuiltScene& prior);

}  // namespace medspring
