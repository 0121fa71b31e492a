// The hybrid kidney (ALGORITHMS.md §4): a surface mass-spring body and a centerline skeleton of
// medial atoms, tied by spokes and integrated together as one system. Model kind "hybrid".
//
//   HybridKidney kidney = hybrid_kidney_phantom();          // 458 surface + 42 atoms, §4.1
//   State s = make_state(kidney.model());
//   kidney.transfer_force(223, F, s.f_ext);                 // a force on a surface node
//   step(kidney.model(), s, {.dt = 0.5});
//
// Locality (issue 15): a large surface (>= kLocalityReorderMinNodes nodes) whose numbering scatters
// neighbours (bandwidth more than twice that of its reverse Cuthill-McKee order, geometry/locality.hpp)
// is simulated in that order, as SurfaceBody does: the model's first #S nodes (the DOFs) are the surface
// nodes renumbered, the atoms follow in their own order (atom_dof). Everything indexed by surface node
// (settings.fixed, loads, tool contact, local patches, spokes(), spoke_length(), surface(), normals,
// output files, model packages) keeps the mesh's own numbering; only the raw DOF arrays (model(),
// state.x/v, Python positions/velocities) are in the model's order, dof_of_surface() relating the two.
#pragma once

#include <vector>

#include "medspring/geometry/locality.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/geometry/volume.hpp"
#include "medspring/models/body.hpp"

namespace medspring {

/// Parameters of the hybrid kidney; defaults are the kidney column of ALGORITHMS.md §9.
struct HybridSettings {
  NodeParams surface_node{0.3, 0.5, 0.02};  // mass g, beta 1/ms, k_r N/mm of surface nodes
  NodeParams atom_node{0.3, 0.5, 0.02};     // same for centerline atoms
  double k_surf = 0.05;                     // surface springs, N/mm
  double k_spoke = 0.05;                    // spokes, N/mm
  double k_cl = 0.1;                        // centerline springs, N/mm
  bool nonlinear = true;                    // D-4: every inter-node spring Duffing (else all linear)
  DuffingSettings duffing{};                // Strain, eta = 1 (D-3)
  Index spokes_per_atom = 8;                // K_a of the union rule (D-9)
  bool visibility_filter = true;            // D-9: reject spokes leaving the organ, when a mask is given
  std::vector<Index> fixed;                 // pinned surface nodes (default none)
  std::vector<Index> fixed_atoms;           // pinned centerline atoms (default none)
};

/// The declaration of HybridSettings (core/params.hpp): the "parameters" of a hybrid model in a scene,
/// the Python properties and keywords of HybridSettings, `medspring build kidney --set NAME=VALUE`, the
/// table in docs/parameters.md. A new parameter: a member above and a line here (CONTRIBUTING.md).
/// `nonlinear` is the model's "nonlinear" key, not a parameter.
template <ParamOf<HybridSettings> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"mass", "g", "mass of a surface node"}.positive(), s.surface_node.mass);
  v(ParamSpec{"beta", "1/ms", "mass-proportional damping of a surface node, d = beta m"}.nonnegative(),
    s.surface_node.beta);
  v(ParamSpec{"k_r", "N/mm", "return spring of a surface node to its rest position"}.nonnegative(),
    s.surface_node.return_k);
  v(ParamSpec{"atom_mass", "g", "mass of a centerline atom"}.positive(), s.atom_node.mass);
  v(ParamSpec{"atom_beta", "1/ms", "mass-proportional damping of an atom"}.nonnegative(), s.atom_node.beta);
  v(ParamSpec{"atom_k_r", "N/mm", "return spring of an atom"}.nonnegative(), s.atom_node.return_k);
  v(ParamSpec{"k_surf", "N/mm", "surface springs (one per mesh edge)"}.positive(), s.k_surf);
  v(ParamSpec{"k_spoke", "N/mm", "spokes between surface nodes and atoms (D-9)"}.positive(), s.k_spoke);
  v(ParamSpec{"k_cl", "N/mm", "centerline springs between consecutive atoms"}.positive(), s.k_cl);
  v(ParamSpec{"spokes_per_atom", "",
              "K_a of the union rule: each atom to its K_a nearest surface nodes (D-9)"}
        .at_least(1),
    s.spokes_per_atom);
  v(ParamSpec{"duffing", "", "Duffing law of every inter-node spring (D-3, D-4)"}, s.duffing);
  v(ParamSpec{"visibility_filter", "",
              "D-9: reject spokes whose segment leaves the organ (needs a segmentation mask)"},
    s.visibility_filter);
  v(ParamSpec{"fixed", "", "pinned surface nodes"}, s.fixed);
  v(ParamSpec{"fixed_atoms", "", "pinned centerline atoms (e.g. where the renal vessels hold the hilum)"},
    s.fixed_atoms);
}
/// What the visibility filter of D-9 did (all zero without a mask).
struct SpokeVisibility {
  Index rejected = 0;   // candidates skipped because their segment leaves the organ
  Index fallbacks = 0;  // surface nodes with no visible atom, linked to their nearest atom anyway
};

/// Spokes by the union rule of D-9: (a) every surface node to its nearest atom (ties: lower atom);
/// (b) every atom to its K nearest surface nodes; duplicates removed. Rows (surface node, atom),
/// sorted by atom then node. With a `mask` (the organ's voxels, same frame as the points), the
/// visibility filter of D-9 applies: a candidate whose segment leaves the organ is rejected and the next
/// nearest taken (a node that sees no atom keeps its nearest one, counted in `visibility->fallbacks`).
MatX2i union_spokes(const MatX3& surface, const MatX3& atoms, Index spokes_per_atom,
                    const MaskVolume* mask = nullptr, SpokeVisibility* visibility = nullptr);

/// D-9's test of one spoke: the segment p-q sampled every min(voxel spacing) mm; true when no sample lies
/// outside the mask by more than one voxel (its distance to the nearest object voxel's box > the largest
/// voxel spacing).
bool segment_inside_mask(const MaskVolume& mask, const Vec3& p, const Vec3& q);

/// Statistics of a hybrid model for build summaries and tests.
struct HybridStats {
  Index surface_nodes = 0, atoms = 0, surface_springs = 0, centerline_springs = 0, spokes = 0;
  Index min_spokes_per_atom = 0, max_spokes_per_atom = 0;
  Index surface_nodes_without_spoke = 0;
  bool visibility_filtered = false;  // D-9's filter ran (a mask was given and the setting is on)
  SpokeVisibility visibility;
};

class HybridKidney final : public Body {
 public:
  /// surface: closed organ surface (mm); atoms: #A x 3 centerline atoms (mm) in order along the skeleton;
  /// mask: the organ's voxels when known (the skeleton's mask): spokes then pass D-9's visibility filter
  /// unless settings.visibility_filter is off.
  /// locality_min_nodes: the surface is renumbered for locality (see above) only from this many nodes on
  /// (0: whenever its order helps, as for a small shuffled mesh; a huge value: never).
  HybridKidney(const SurfaceMesh& surface, const MatX3& atoms, const HybridSettings& settings = {},
               std::string name = "kidney", const MaskVolume* mask = nullptr,
               Index locality_min_nodes = kLocalityReorderMinNodes);

  std::string kind() const override { return "hybrid"; }
  const Model& model() const override { return model_; }
  const MatX3i& faces() const override { return F_; }
  const MatX3& rest_surface() const override { return rest_surface_; }
  void map_to_surface(const State& state, MatX3& surface) const override;
  void transfer_force(Index node, const Vec3& F, MatX3& f_dof) const override;
  double local_stiffness() const override { return settings_.k_surf; }
  std::vector<std::uint8_t> fixed_surface_nodes() const override;
  double spoke_length(Index node) const override { return spoke_length_[node]; }

  Index num_atoms() const { return num_atoms_; }
  /// DOF index of atom a (atoms follow the surface nodes).
  Index atom_dof(Index a) const { return num_surface_nodes() + a; }
  /// The DOF (model node) of every surface node; empty when they coincide (small or well-ordered meshes).
  const std::vector<Index>& dof_of_surface() const { return dof_of_surface_; }
  Index dof_of(Index surface_node) const {
    return dof_of_surface_.empty() ? surface_node : dof_of_surface_[static_cast<std::size_t>(surface_node)];
  }
  /// Spokes as rows (surface node, atom), surface nodes in the mesh's numbering.
  const MatX2i& spokes() const { return spokes_; }
  const HybridSettings& settings() const { return settings_; }
  HybridStats stats() const { return stats_; }

 private:
  Model model_;
  MatX3i F_;
  MatX3 rest_surface_;
  MatX2i spokes_;
  VecX spoke_length_;
  std::vector<Index> dof_of_surface_;  // surface node -> DOF (empty: identity)
  HybridSettings settings_;
  HybridStats stats_;
  Index num_atoms_ = 0;
};

/// The atoms of the kidney phantom (§4.1): A_k = B((-0.85 a + 1.7 a k / (n-1), 0, 0)), n = 42.
MatX3 kidney_phantom_atoms(Index count = 42);

/// The hybrid kidney phantom: kidney_phantom() + kidney_phantom_atoms() (458 + 42 masses).
HybridKidney hybrid_kidney_phantom(const HybridSettings& settings = {});

}  // namespace medspring
