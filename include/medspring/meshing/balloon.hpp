// Balloon surfaces: a closed, near-regular triangle surface with an exact number of nodes, fitted
// to an organ surface (ALGORITHMS.md §1.1 "six neighbouring points", §4.4 "balloon/marching-cubes
// mesh decimated to the desired node count"). Built with CGAL's isotropic remeshing, then exact
// count control, valence-driven edge flips (greedy, then random plateau flips that move 5-7 valence
// pairs until they cancel), tangential relaxation, and a final error-weighted fit that pulls nodes
// onto ridges; every vertex is projected back onto the input surface. CGAL stays private to the meshing layer
// (this header uses engine types).
//
//   SurfaceMesh organ = read_mesh(find_data_file("kidney_left_hubmap_vhm.obj"), {.unit = LengthUnit::Metre});
//   BalloonResult r = build_balloon_surface(organ, {.target_nodes = 458});
//   // r.mesh: 458 nodes; r.report.valence6_fraction, r.report.hausdorff_mm, r.report.warnings
//
// Errors: InvalidInput for an organ that is not a valid, closed, manifold, single-component surface
// (the message counts the boundary / non-manifold edges and names close_small_holes), for
// target_nodes below BalloonSettings::min_nodes, and for a target so small that the surface cannot
// stay manifold and free of self-intersections.
#pragma once

#include <string>
#include <vector>

#include "medspring/geometry/surface_mesh.hpp"

namespace medspring {

struct BalloonSettings {
  Index target_nodes = 458;          // exact node count of the result (458: the paper's kidney, §1.1)
  Index min_nodes = 20;              // smaller targets are refused (too coarse to follow any organ)
  int remesh_iterations = 12;        // CGAL isotropic-remeshing iterations per trial edge length
  int length_trials = 8;             // at most this many trial edge lengths (secant on V ~ 2A/(sqrt(3) l^2))
  int migration_rounds = 150;        // rounds of plateau flips that let 5-7 valence pairs meet and cancel
  int migration_patience = 50;       // stop after this many rounds without fewer irregular nodes
  int fit_iterations = 30;           // error-weighted relaxation iterations (pull nodes onto ridges)
  double fit_error_scale = 0.05;     // error scale of the fit weights, fraction of the edge length
  int feature_snaps = 40;            // at most this many nodes moved onto the farthest organ point
  double max_flip_deviation = 0.15;  // a flip may not put its new edge's midpoint farther than this
                                     // fraction of the edge length from the organ surface
  bool measure_distance = true;      // fill BalloonReport::hausdorff_mm / mean_distance_mm
  bool locality_order = true;        // nodes numbered in reverse Cuthill-McKee order (cache locality)
};

struct BalloonReport {
  Index nodes = 0, edges = 0, faces = 0;
  double target_edge_length = 0.0;       // mm, the isotropic-remeshing length that was used
  Index remeshed_nodes = 0;              // node count after remeshing, before exact count control
  Index collapses = 0, splits = 0;       // edge operations of the exact count control
  Index flips = 0;                       // valence-driven edge flips of the regularisation
  Index feature_snaps = 0;               // nodes moved onto organ ridges by the final fit
  std::vector<Index> valence_histogram;  // [d] = nodes with d neighbours
  double valence6_fraction = 0.0;        // nodes with six neighbours / nodes
  double hausdorff_mm = -1.0;            // symmetric Hausdorff distance to the organ (-1: not measured)
  double mean_distance_mm = -1.0;        // symmetric mean surface distance to the organ (-1: not measured)
  double organ_size_mm = 0.0;            // bounding-box diagonal of the input
  double seconds = 0.0;                  // wall time of the whole build (including the distances)
  std::vector<std::string> warnings;     // e.g. implausible organ size (units?)

  /// Multi-line human-readable summary (counts, valence histogram, distances, time, warnings).
  std::string summary() const;
  /// One line per finding worth reporting in a scene run: the size, valence and distances, then each
  /// warning ("warning: ...").
  std::vector<std::string> note_lines() const;
};

struct BalloonResult {
  SurfaceMesh mesh;  // closed, manifold, outward-oriented, exactly target_nodes vertices (mm)
  BalloonReport report;
};

/// Builds the balloon surface of `organ` (closed, manifold, one component; mm) with exactly
/// settings.target_nodes nodes. Deterministic: the same input gives a bit-identical mesh.
/// An organ whose bounding-box diagonal is under 5 mm or over 1000 mm is still meshed, with a
/// warning naming the likely unit error.
BalloonResult build_balloon_surface(const SurfaceMesh& organ, const BalloonSettings& settings = {});

/// build_balloon_surface(organ, settings).mesh.
SurfaceMesh balloon_surface(const SurfaceMesh& organ, const BalloonSettings& settings = {});

/// The unit warning for an organ of bounding-box diagonal `diagonal_mm`, or "" when 5..1000 mm.
std::string organ_size_warning(double diagonal_mm);

}  // namespace medspring
