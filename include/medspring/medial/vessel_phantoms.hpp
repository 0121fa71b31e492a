// Procedural vessel phantoms of ALGORITHMS.md §8.0: centerlines and cross-section offsets.
#pragma once

#include <string>

#include "medspring/core/types.hpp"
#include "medspring/geometry/polyline.hpp"

namespace medspring {

/// The test centerlines of §8.0 (n atoms; default spacing 2.5 mm).
enum class VesselPath {
  StraightX,  // C_i = (h i, 0, 0)
  StraightZ,  // C_i = (0, 0, h i): parallel to the scanner axis (degenerate for eq. (3))
  Arc,        // radius 40 mm in the xy-plane, arc-length spacing h, starting at the origin along +x
  Helix,      // C_i = (20 cos 0.12 i, 20 sin 0.12 i, 1.5 i) (spacing ~2.83 mm; h is ignored)
};

/// The cross-sections of §8.0, as local offsets (o_u, o_v, o_t) per spoke j (theta_j = 2 pi j / M).
enum class CrossSectionShape {
  Circular,    // (3 cos, 3 sin, 0)
  Elliptical,  // (3 cos, 1.8 sin, 0)
  NonPlanar,   // (3 cos, 1.8 sin, 0.3 sin 3 theta)
};

VesselPath parse_vessel_path(const std::string& text);  // "straight_x" | "straight_z" | "arc" | "helix"
CrossSectionShape parse_cross_section(const std::string& text);  // "circular" | "elliptical" | "non_planar"
std::string to_string(VesselPath path);
std::string to_string(CrossSectionShape shape);

/// Atoms of a phantom centerline (#n x 3, mm).
MatX3 vessel_phantom_atoms(VesselPath path, Index n = 40, double spacing = 2.5);

/// The phantom centerline with a constant radius (mm) at every atom.
Centerline vessel_phantom_centerline(VesselPath path, Index n = 40, double radius = 3.0,
                                     double spacing = 2.5);

/// Local offsets of the M spokes of one cross-section (#M x 3, mm); `scale` multiplies them (1 = §8.0).
MatX3 cross_section_offsets(CrossSectionShape shape, Index spokes = 30, double scale = 1.0);

}  // namespace medspring
