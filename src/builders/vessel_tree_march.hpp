// The watertight surface of a vessel tree from a mesh or a mask marched to the input's wall (docs/vessels.md,
// "A tree from a mesh or a mask gets the watertight surface marched to the wall"); internal to the builders.
#pragma once

#include <memory>
#include <vector>

#include "medspring/builders/vessel_build.hpp"

namespace medspring::builders_detail {

/// The tree with `tree`'s watertight surface marched to `input` (notes and warnings into s, and its
/// volume); null when the marched surface would intersect itself (then the circles stay, with a warning).
std::shared_ptr<SmrmTree> marched_tree(const CenterlineTree& ct, const SmrmTreeSettings& ts,
                                       const SmrmTree& tree, const SurfaceMesh& input, VesselSummary& s);

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
