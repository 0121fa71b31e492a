// The SMRM vessel (ALGORITHMS.md §5) of a real vessel from a centerline file, a surface mesh or a
// segmentation: atoms with radii, 30 spokes per atom, the rebuilt surface, its rest reconstruction error
// and, from a mesh or segmentation, its distance to the input; written with a model package (.msm).
//
//   VesselBuild v = build_vessel({.centerline = find_data_file("vmr-0159-aorta-centerline.vtp"),
//                                 .centerline_unit = LengthUnit::Centimetre});
//   v.summary.rest_error_mm;   // <= 1e-9 (exact reconstruction, D-13)
//   write_vessel_files(dir, v);  // surface.vtp atoms.vtp spokes.vtp vessel.msm
//
// Centerline input: one branch of the file (--branch N, default the longest), or all of them merged
// into a tree where they share their start (all_branches: SmrmTree, shared junction atoms). Mesh /
// segmentation input: the distance-mapping centerline (§3, build_centerline) and spoke lengths marched to the
// boundary (§5.6). Errors: those of read_centerlines / load_organ / build_centerline; InvalidInput for a
// branch out of range, a segmentation with several components (naming the count and the voxels of each),
// settings out of range. Nothing is written by build_vessel.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "medspring/builders/organ_source.hpp"
#include "medspring/core/units.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/models/smrm_tree.hpp"
#include "medspring/models/smrm_vessel.hpp"

namespace medspring {

struct VesselBuildSettings {
  std::filesystem::path centerline{};  // a centerline file (.vtp / .vtk with radii), or
  LengthUnit centerline_unit = LengthUnit::Millimetre;
  Index branch = -1;              // centerline: the polyline to use; -1 = the longest
  bool all_branches = false;      // centerline: every polyline, merged into a tree (SmrmTree)
  double merge_tolerance = 0.05;  // mm: points of two polylines closer than this are one
  bool blend = false;             // tree: one watertight surface (union of the closed path tubes, CGAL)
                                  // instead of one open tube per branch; always for a mesh / mask tree
                                  // (there fitted to the input's wall) unless no_blend
  bool no_blend = false;          // mesh / mask tree: one open tube per branch (the skeleton's circles)
  double blend_spacing = 0.0;     // mm between the rings of the path tubes; 0 = the atom spacing
  OrganSource source{};           // a mesh or a segmentation (exactly one source in all)
  SmrmSettings smrm{};            // atoms (40), spokes (30), bending, chain
};

/// The rebuilt surface against the input away from the cut ends (docs/vessels.md, "Distance to the input"):
/// sample points of both surfaces (surface_distance's grid) whose closest point on the atoms' polylines
/// lies at least one end radius of arc from a cut end (the root's start and every leaf's end; both ends of
/// a single vessel), each to the other surface. Distances in mm.
struct AwayFromEnds {
  bool measured = false;
  double hausdorff_mm = 0.0;  // symmetric, over the samples away from the cut ends
  double mean_mm = 0.0;       // average of the two one-sided area-weighted means
  Index samples = 0, samples_over_2mm = 0;
  Index nodes = 0, nodes_over_2mm = 0;  // rebuilt surface nodes away from the cut ends
  double node_max_mm = 0.0;             // their largest distance to the input
  // where the largest distance sits: branch, atom (nearer atom of the closest axis segment), arc to the
  // nearest cut end of that branch (-1: the branch has none), the sample point, and which way
  Index worst_branch = -1, worst_atom = -1;
  double worst_from_cut_mm = 0.0;
  Vec3 worst_point = Vec3::Zero();
  std::string worst_direction;
};

/// What build_vessel made. Distances in mm, times in seconds.
struct VesselSummary {
  std::string input;       // file name
  std::string input_kind;  // "centerline", "mesh" or "mask"
  Index atoms = 0, branches = 1, junctions = 0, surface_nodes = 0, faces = 0, spokes = 0;
  Index input_branches = 0;  // centerline input: polylines in the file
  Index branch = 0;          // centerline input: the polyline used
  double length_mm = 0.0;    // arc length of the atoms
  double radius_min_mm = 0.0, radius_max_mm = 0.0;
  double rest_error_mm = 0.0;         // max |rebuilt rest surface - rest surface| (exact: rounding only)
  double kb_min = 0.0, kb_max = 0.0;  // bending stiffness of the interior atoms, N/mm
  double max_rho_kappa = 0.0;         // §5.6 validity at rest
  double dt_safe_ms = 0.0;            // stable step at rest (Gershgorin, with the bending terms)
  // mesh / mask input: the rebuilt tube against the input surface
  bool has_distance = false;
  double hausdorff_mm = 0.0;      // symmetric (sampled), cut ends included
  double mean_distance_mm = 0.0;  // average of the two one-sided means
  double to_input_max_mm = 0.0;   // rebuilt surface nodes -> input surface, max
  double to_input_mean_mm = 0.0;  // rebuilt surface nodes -> input surface, mean
  Index spokes_without_hit = 0;   // spoke marching found no boundary (rho = r_i used)
  AwayFromEnds away;              // the same away from the cut ends
  // tree with blend: the watertight junction surface
  bool blended = false;
  Index path_tubes = 0;             // closed tubes united
  bool surface_closed = false;      // no boundary edge, edge- and vertex-manifold, consistently oriented
  Index surface_components = 0;     // connected components of the surface
  Index self_intersections = -1;    // intersecting triangle pairs (-1: not checked)
  double surface_volume_mm3 = 0.0;  // signed volume (> 0: outward)
  double seconds = 0.0;
  std::vector<std::string> notes;
  std::vector<std::string> warnings;

  std::string text() const;
};

struct VesselBuild {
  std::shared_ptr<const SmrmVessel> vessel;  // one branch, or
  std::shared_ptr<const SmrmTree> tree;      // all branches (--branches all)
  std::vector<Centerline> centerlines;       // the atoms of every branch with their radii (mm)
  SurfaceMesh input;  // mesh / mask input: the boundary surface (empty for a centerline)
  VesselSummary summary;
};

/// The watertight junction surface of a vessel tree (docs/vessels.md, "--blend"): the union (CGAL) of
/// the closed path tubes of tree_path_tubes, every path with the first ring spacing of spacing x (1, 0.9,
/// 1.1, 0.8, ...) that gives a simple tube, checked closed and manifold.
struct TreeSurface {
  SurfaceMesh mesh;
  Index path_tubes = 0;
  double spacing_min_mm = 0.0, spacing_max_mm = 0.0;  // ring spacings the paths took
  bool closed = false;                                // closed, manifold, consistently oriented
  Index components = 0;
  Index self_intersections = -1;  // intersecting triangle pairs
  double volume_mm3 = 0.0;        // signed volume (> 0: outward)
  std::vector<std::string> notes, warnings;
};

/// The watertight surface of `tree` with `spokes` spokes per ring and rings `spacing` mm apart (0 = the
/// atom spacing of `plain`'s root branch, `plain` = SmrmTree(tree, settings)). Throws InvalidInput for
/// a spacing < 0 or NaN, a path that intersects itself at every spacing tried (naming the path) or a
/// union that is not a closed manifold.
TreeSurface blended_tree_surface(const CenterlineTree& tree, const SmrmTree& plain, double spacing = 0.0);

/// SmrmTree(tree, settings, blended_tree_surface(...).mesh): the tree with its watertight surface;
/// `report` (if given) receives what the surface is.
std::shared_ptr<SmrmTree> make_blended_tree(const CenterlineTree& tree, const SmrmTreeSettings& settings,
                                            double spacing = 0.0, TreeSurface* report = nullptr);

/// Builds the vessel of settings (see the file comment). Deterministic.
VesselBuild build_vessel(const VesselBuildSettings& settings);

/// Writes surface.vtp (rebuilt rest surface, point arrays "atom" and "branch"), atoms.vtp (the atoms of
/// every branch as a polyline with "MaximumInscribedSphereRadius", readable by read_centerlines),
/// spokes.vtp (atom -> surface node segments) and vessel.msm (the model package; kind smrm_tree for a
/// tree) into the existing folder `dir`.
void write_vessel_files(const std::filesystem::path& dir, const VesselBuild& build);

}  // namespace medspring
