// A branching SMRM vessel (issue 17, docs/vessels.md): centerline branches joined at junctions, one chain
// model over all atoms, and one SMRM tube per branch for the surface. Model kind "smrm_tree".
//
//   auto lines = read_centerlines(find_data_file("vmr-0159-aorta-centerline.vtp"), LengthUnit::Centimetre);
//   CenterlineTree tree = merge_centerlines(lines);      // 4 polylines sharing their start -> 7 branches
//   SmrmTree vessel(tree);                               // shared junction atoms, 30 spokes per atom
//
// Junction coupling: a child's first atom IS its parent's last atom (a shared atom), and a bending term
// joins the parent's second-to-last atom, the junction and the child's second atom (rest angle as zero),
// so a force on one branch reaches the others through the junction. The default surface is one tube per
// branch (the child's first ring sits at the junction inside the parent's last ring): not one watertight
// mesh. The watertight junction surface is the union of the closed path tubes (tree_path_tubes; the
// union itself is CGAL's, meshing/mesh_union.hpp, made by the builders) given to the second constructor:
// each of its vertices rides on the two bracket atoms (§5.9) of the branch whose rest tube it lies on.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "medspring/geometry/polyline.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/models/body.hpp"
#include "medspring/models/smrm_vessel.hpp"

namespace medspring {

/// Branches of a centerline tree. Branch 0 is the root (it starts at the inlet); every other branch
/// starts at the last point of its parent (the junction).
struct CenterlineTree {
  struct Branch {
    Centerline line;  // mm, >= 2 points; a child's first point is its parent's last point
    Index parent = -1;
  };
  std::vector<Branch> branches;
  Index junctions() const;  // branch ends with children
};

/// Merges centerlines that share their start (VMTK: each polyline repeats the trunk with its own points)
/// into a tree: points of two lines at the same index within `tolerance` mm are one point; where they
/// part, the trunk ends in a junction. Consecutive points closer than 1e-3 mm are merged first. Throws
/// InvalidInput naming the line and point for fewer than 2 points, non-finite points, radii <= 0 or NaN,
/// a line whose start is farther than `tolerance` from line 0's start (branches that do not meet), and a
/// line that comes back within `tolerance` of a point of its own branch path more than 2 radii behind
/// (a loop).
CenterlineTree merge_centerlines(const std::vector<Centerline>& lines, double tolerance = 0.05);

/// A tree from NumPy-style arrays: atoms (#n x 3, mm), parent index of every atom (-1 for the root atom
/// 0 only; parent < index) and radii (#n, mm). Runs of atoms form branches; an atom with several children
/// is a junction. Throws InvalidInput naming the atom for bad parents or radii.
CenterlineTree tree_from_parents(const MatX3& atoms, const std::vector<Index>& parent, const VecX& radii);

struct SmrmTreeSettings {
  SmrmSettings vessel{};  // chain, bending, wall, spokes, frames; vessel.atoms = atoms on the longest
                          // root-to-leaf path (sets the spacing of every branch)
};

/// The closed tubes whose union is the watertight surface of a tree (docs/vessels.md): the branches are
/// joined into paths (at every junction the parent continues into the child whose start is best aligned
/// with its end; every other child starts a path of its own), every path is resampled from the input
/// centerline at `spacing` mm and gets `spokes` circular spokes per ring in rotation-minimising frames
/// and a flat cap at both ends. A path that starts at a junction is narrowed where it runs inside its
/// parent (within the junction radius of the start): radius min(r, r at the junction radius), so that
/// its start cap lies inside the parent tube. Each tube is closed, manifold and outward-oriented.
/// `path_branches` (if given) receives the branches of every path. Throws InvalidInput for spacing
/// <= 0 or spokes < 3.
std::vector<SurfaceMesh> tree_path_tubes(const CenterlineTree& tree, Index spokes, double spacing,
                                         std::vector<std::vector<Index>>* path_branches = nullptr);

class SmrmTree final : public Body {
 public:
  /// Resamples every branch at the common spacing (>= 3 atoms per branch), shares the junction atoms,
  /// fixes the root's first atom and every leaf's last atom. Throws InvalidInput naming the branch.
  explicit SmrmTree(const CenterlineTree& tree, const SmrmTreeSettings& settings = {});
  /// The same tree with `surface` (closed, e.g. the union of tree_path_tubes) as its surface instead of
  /// one tube per branch. Every vertex belongs to the branch whose rest tube it lies closest to (min over
  /// branches of |distance to the branch's atom polyline - the interpolated atom radius|), rides on the
  /// bracket (i, lambda) of its closest point there (§5.9) and follows both bracket atoms' frames,
  /// blended linearly: p = (1 - lambda) (C_i + F_i o0) + lambda (C_i+1 + F_i+1 o1), with o0, o1 its
  /// rest offsets in the two rest frames (exact at rest; no trigonometry per update). Throws
  /// InvalidInput for an invalid or open mesh.
  SmrmTree(const CenterlineTree& tree, const SmrmTreeSettings& settings, const SurfaceMesh& surface);
  /// True for a tree built with its own (watertight) surface.
  bool blended() const { return !blend_.empty(); }

  std::string kind() const override { return "smrm_tree"; }
  const Model& model() const override { return model_; }
  const MatX3i& faces() const override { return faces_; }
  const MatX3& rest_surface() const override { return rest_surface_; }
  void map_to_surface(const State& state, MatX3& surface) const override;
  /// The node's branch atom receives F (D-14); nothing for a fixed atom.
  void transfer_force(Index node, const Vec3& F, MatX3& f_dof) const override;
  double local_stiffness() const override { return settings_.vessel.k_loc; }
  double spoke_length(Index node) const override;

  /// The tree and settings it was built from (a model package stores them: make_body rebuilds the same
  /// model from them, docs/model_packages.md).
  const CenterlineTree& centerline_tree() const { return tree_; }
  const SmrmTreeSettings& settings() const { return settings_; }

  Index num_branches() const { return static_cast<Index>(branches_.size()); }
  Index num_junctions() const { return junctions_; }
  Index num_atoms() const { return model_.num_nodes(); }
  Index parent(Index branch) const { return parent_[static_cast<std::size_t>(branch)]; }
  /// The tree atoms of a branch in order (the first is the parent's last for a child).
  const std::vector<Index>& branch_atoms(Index branch) const {
    return atoms_[static_cast<std::size_t>(branch)];
  }
  const SmrmVessel& branch_vessel(Index branch) const { return *branches_[static_cast<std::size_t>(branch)]; }
  /// The surface nodes of a branch are [node_begin(b), node_begin(b + 1)).
  Index node_begin(Index branch) const { return node_begin_[static_cast<std::size_t>(branch)]; }
  Index node_branch(Index node) const;
  Index node_atom(Index node) const;  // the tree atom a surface node rides on (the nearer one, blended)

  struct Workspace {
    std::vector<MatX3> atoms;    // per branch: its atoms (gathered from the tree's)
    std::vector<MatX3> surface;  // per branch: room for its rows (map_to_surface writes the tree surface
                                 // directly; e.g. for per-branch normals)
    std::vector<SmrmVessel::Workspace> vessel;
  };
  Workspace make_workspace() const;
  /// Surface (#S x 3) of tree atoms (#n x 3); no allocation once `surface` has its size.
  void map_to_surface(const MatX3& atoms, Workspace& ws, MatX3& surface) const;
  /// §5.6 validity rho kappa < 1 of every branch's interior atoms (SmrmVessel::validity per branch;
  /// first_atom is a tree atom). The junction's own turn is not a branch's interior: not counted.
  /// No allocation (ws from make_workspace).
  CurvatureCheck validity(const MatX3& atoms, Workspace& ws) const;
  /// Largest |alpha_i - alpha_i^0| over every branch's interior atoms, degrees; the tree atom where it is
  /// largest in *atom. No allocation.
  double max_turning_change_deg(const MatX3& atoms, Workspace& ws, Index* atom = nullptr) const;

 private:
  WorkspacePool<Workspace> workspaces_;  // of map_to_surface(State, ...), one per concurrent caller
  SmrmTreeSettings settings_;
  CenterlineTree tree_;
  std::vector<std::shared_ptr<const SmrmVessel>> branches_;
  std::vector<std::vector<Index>> atoms_;
  std::vector<Index> parent_;
  std::vector<Index> node_begin_;
  Index junctions_ = 0;
  // blended surface: per branch its nodes (global indices) and their generic binding to the branch atoms
  struct BlendBranch {
    std::vector<Index> nodes;
    SurfaceBinding binding;  // bracket (atom, lambda) of every node on the branch's rest atoms
    MatX3 o0, o1;            // rest offsets in the rest frames of the bracket's two atoms
  };
  std::vector<BlendBranch> blend_;
  std::vector<Index> blend_branch_, blend_local_;  // per node: its branch, its row in that branch
  VecX blend_spoke_;                               // per node: rest distance to its centerline point
  Index surface_rows(std::size_t branch) const;    // rows of ws.surface[branch]
  Model model_;
  MatX3 rest_surface_;
  MatX3i faces_;
};

}  // namespace medspring
