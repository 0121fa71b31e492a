// Centerline extraction by distance mapping (after Wan et al. 2002), ALGORITHMS.md §3.1-3.5, 3.7.
//
//   MaskVolume mask = ...;                       // 1 = object
//   SkeletonResult r = extract_centerline(mask, {.atom_count = 42});
//   r.atoms, r.radii                             // world mm
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/geometry/polyline.hpp"
#include "medspring/geometry/volume.hpp"

namespace medspring {

/// How the ends of the object are treated (§3.1.2, D-5, D-6, D-8).
enum class EndMode {
  Auto,    // object voxels on the volume border form open ends (components of >= min_open_end_voxels)
  Closed,  // ignore border contact: background padding, double-sweep endpoints, both ends trimmed
  Open,    // as Auto for the endpoints, but edge-replicate padding and no trimming at either end
};

/// How the voxel path between the two endpoints is found (§3.4).
enum class PathMethod {
  MaximumSpanningTree,  // D-7: Prim's maximum spanning tree of w(u,v) = min(DFB(u), DFB(v))
  PenalizedDijkstra,    // TEASAR-style: step cost |step| (1 + lambda (1 - DFB(w)/DFB_max)^p)
};

/// What an end of the centerline is.
enum class EndKind {
  Open,    // the object is cut by the volume border here: no trimming (D-8)
  Closed,  // a closed tip: trimmed where the arc length to the end is below the inscribed radius (D-8)
  Capped,  // a cap that closed an open tube mesh (§3.6): trimmed as Closed, then re-extended linearly
           // along the end tangent to the cap plane
};

/// A user-supplied endpoint (overrides D-6 for its end). It is snapped to the nearest object voxel of
/// the component used (ties: smallest linear index).
struct UserEndpoint {
  Vec3 position = Vec3::Zero();      // world mm
  std::optional<Vec3> cap_normal{};  // set for a cap of an open tube (§3.6): the end is Capped and the
                                     // curve is re-extended to the plane through `position` with this
                                     // normal (need not be unit)
};

/// Settings of extract_centerline; defaults of ALGORITHMS.md §9.
struct SkeletonSettings {
  int connectivity = 26;  // 6, 18 or 26: voxel graph for components, open ends, DFS and tree
  EndMode end_mode = EndMode::Auto;
  PathMethod path_method = PathMethod::MaximumSpanningTree;  // D-7
  Index atom_count = 40;                                     // N_a >= 2 (vessel 40, kidney 42)
  double smoothing_sigma = 0.0;                // mm, Gaussian sigma along arc length; 0 = 2 h_min (§3.5.2)
  double resampling_step = 0.0;                // mm, arc-length step delta of the resampled path; 0 = h_min/2
  Index min_open_end_voxels = 4;               // smallest open-end component kept (§3.1.2)
  bool trim_closed_ends = true;                // D-8 trimming of Closed and Capped ends
  double penalty_lambda = 5000.0;              // PenalizedDijkstra lambda
  double penalty_power = 16.0;                 // PenalizedDijkstra p
  std::optional<UserEndpoint> start{}, end{};  // user endpoints (world mm); each overrides its end of D-6
  bool keep_distance_field = false;            // fill SkeletonResult::dfb
};

/// One end of the extracted centerline.
struct SkeletonEnd {
  Index voxel = -1;              // linear index in the input mask of the path's end voxel
  Vec3 position = Vec3::Zero();  // world mm, centre of that voxel (before smoothing/trimming)
  EndKind kind = EndKind::Closed;
  double trimmed = 0.0;   // mm of smoothed curve removed at this end (D-8)
  double extended = 0.0;  // mm of linear extension to the cap plane (Capped ends, §3.6)
};

/// Result of extract_centerline. Curves run from the root R (ends[0]) to the far endpoint E (ends[1]).
struct SkeletonResult {
  MatX3 atoms;                        // N_a x 3, world mm, at equal arc-length spacing along `curve`
  VecX radii;                         // N_a, mm: max(DFB(C_i) - h_min/2, h_min/2) (§3.5.5)
  std::vector<Index> path_voxels;     // raw voxel path R -> E, linear indices in the input mask
  MatX3 raw_path;                     // world mm, centres of path_voxels
  MatX3 smoothed;                     // resampled (step <= delta) and smoothed path, before trimming, mm
  MatX3 curve;                        // the smoothed path after trimming / extension; the atoms lie on it
  VecX atom_arc_length;               // N_a, arc length of every atom along `curve`, mm
  std::array<SkeletonEnd, 2> ends;    // [0] = start (R), [1] = end (E)
  std::vector<Index> open_end_sizes;  // voxel counts of the open-end components found, largest first
  Index components = 0;               // connected components of the mask
  Index object_voxels = 0;            // object voxels of the mask
  Index component_voxels = 0;         // voxels of the component used (the largest)
  double h_min = 0.0;                 // mm, smallest voxel spacing
  double max_dfb = 0.0;               // mm, largest DFB on the component used
  ScalarVolume dfb;                   // DFB on the padded working grid (its own dims and origin), mm;
                                      // only with settings.keep_distance_field
  std::vector<std::string> notes;     // what was decided on the way, e.g. "used the largest of 3 components"

  /// The atoms and radii as a Centerline.
  Centerline centerline() const;
};

/// Extracts the centerline of the largest connected component of `mask` (value != 0 = object):
/// ALGORITHMS.md §3.1 preprocessing and D-5 padding, §3.2 exact DFB, §3.3 DFS and D-6 endpoints,
/// §3.4 D-7 maximum spanning tree (or penalised Dijkstra), §3.5 smoothing, D-8 trimming, evenly spaced
/// atoms and radii. Deterministic (bit-identical across runs). Throws InvalidInput for an invalid
/// volume (non-positive spacing, wrong data size), an empty mask ("mask: no object voxels"),
/// atom_count < 2, bad settings, or a component whose two endpoints coincide (a single voxel).
SkeletonResult extract_centerline(const MaskVolume& mask, const SkeletonSettings& settings = {});

const char* to_string(EndKind kind);

}  // namespace medspring
