// The watertight surface of a vessel tree from a mesh or a mask marched to the input's wall (docs/vessels.md,
// "A tree from a mesh or a mask gets the watertight surface marched to the wall"); internal to the builders.
#pragma once

#include <memory>
#include <vector>

#include "medspring/builders/organ_source.hpp"
#include "medspring/builders/vessel_build.hpp"

namespace medspring::builders_detail {

/// The tree with `tree`'s watertight surface marched to `input` (notes and warnings into s, and its
/// volume); null when the marched surface would intersect itself (then the circles stay, with a warning).
std::shared_ptr<SmrmTree> marched_tree(const CenterlineTree& ct, const SmrmTreeSettings& ts,
                                       const SmrmTree& tree, const SurfaceMesh& input, VesselSummary& s,
                                       bool refine = true);

/// Fills the background voxels of `mask` that the border cannot reach (6-connected): enclosed holes, a
/// segmentation's defects inside a vessel (they would bend the skeleton away from them and give the
/// wall an inner surface). Returns the voxels filled; *holes (if given) their 26-connected pieces.
Index fill_enclosed_holes(MaskVolume& mask, Index* holes = nullptr);

/// What recentre_tree did.
struct Recentring {
  Index points = 0, total = 0;  // skeleton points moved, of all
  double max_shift_mm = 0.0, mean_shift_mm = 0.0;
};

/// The skeleton re-centred in its cross-sections (as VMTK centres its centerlines): every point of every
/// branch moves to the area centroid of the input's wall section in the plane normal to the line there
/// (24 rays, 3 iterations), the shifts smoothed over about half a radius of arc, and its radius becomes
/// the distance to the wall from there (the largest inscribed sphere). Points within one radius of arc of
/// a cut end, within 2 (r + r_junction) of a junction, or whose section is not closed within 3 r or far
/// from round (a ray 2.5 times another), and shifts over half a radius, stay.
CenterlineTree recentre_tree(const CenterlineTree& ct, const SurfaceMesh& input, Recentring& report);

/// What fit_to_wall did.
struct WallFit {
  int rounds = 0;    // rounds kept
  Index held = 0;    // nodes the last kept round left where they were (their faces would cross or fold)
  Index pulled = 0;  // nodes pulled onto an input vertex the surface missed by more than 0.5 mm
  Index folds = 0;   // folded faces after the fit (a face folds only where it was folded before)
};

/// Fits the surface `m` to the wall of `input`: `rounds` rounds of half a tangential umbrella step (evens
/// out the nodes along the wall) followed by the closest point of the input. The nodes of faces that would
/// then intersect or fold stay where they were; a round that still leaves such faces is undone and ends
/// the fit. Then, up to 3 rounds, every input vertex farther than 0.5 mm from the surface pulls its
/// nearest node onto itself (the same checks). The connectivity is kept.
WallFit fit_to_wall(SurfaceMesh& m, const SurfaceMesh& input, int rounds);

/// Splits every edge of `m` longer than max_edge at its midpoint (a face with 1, 2 or 3 long edges becomes
/// 2, 3 or 4 faces, orientation kept); closed and manifold stay so. Returns the nodes added.
Index refine_long_edges(SurfaceMesh& m, double max_edge);

/// A cut end of a vessel: the start (at_end false) or the end of a branch's atom line.
struct CutEnd {
  Index branch = 0;
  bool at_end = false;
};

/// s.away: `rebuilt` against `input` away from the cut ends (VesselSummary::away); `lines` are the atoms of
/// every branch with their radii (VesselBuild::centerlines).
void measure_away_from_ends(const SurfaceMesh& rebuilt, const SurfaceMesh& input,
                            const std::vector<Centerline>& lines, const std::vector<CutEnd>& cuts,
                            VesselSummary& s);

}  // namespace medspring::builders_detail
