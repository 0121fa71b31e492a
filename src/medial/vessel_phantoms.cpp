#include "medspring/medial/vessel_phantoms.hpp"

#include <cmath>
#include <numbers>

#include "medspring/core/check.hpp"

namespace medspring {

VesselPath parse_vessel_path(const std::string& text) {
  if (text == "straight_x" || text == "straight-x") return VesselPath::StraightX;
  if (text == "straight_z" || text == "straight-z") return VesselPath::StraightZ;
  if (text == "arc") return VesselPath::Arc;
  if (text == "helix") return VesselPath::Helix;
  throw InvalidInput(
      cat("vessel path: unknown value '", text, "' (expected straight_x, straight_z, arc or helix)"));
}

CrossSectionShape parse_cross_section(const std::string& text) {
  if (text == "circular") return CrossSectionShape::Circular;
  if (text == "elliptical") return CrossSectionShape::Elliptical;
  if (text == "non_planar" || text == "non-planar") return CrossSectionShape::NonPlanar;
  throw InvalidInput(
      cat("cross-section: unknown value '", text, "' (expected circular, elliptical or non_planar)"));
}

std::string to_string(VesselPath path) {
  switch (path) {
    case VesselPath::StraightX:
      return "straight_x";
    case VesselPath::StraightZ:
      return "straight_z";
    case VesselPath::Arc:
      return "arc";
    case VesselPath::Helix:
      return "helix";
  }
  return "straight_x";
}

std::string to_string(CrossSectionShape shape) {
  switch (shape) {
    case CrossSectionShape::Circular:
      return "circular";
    case CrossSectionShape::Elliptical:
      return "elliptical";
    case CrossSectionShape::NonPlanar:
      return "non_planar";
  }
  return "circular";
}

MatX3 vessel_phantom_atoms(VesselPath path, Index n, double h) {  // §8.0
  require(n >= 2, "vessel phantom: need at least 2 atoms (got ", n, ")");
  require_positive(h, "vessel phantom: spacing");
  MatX3 C(n, 3);
  for (Index i = 0; i < n; ++i) {
    const double s = static_cast<double>(i);
    switch (path) {
      case VesselPath::StraightX:
        C.row(i) << h * s, 0, 0;
        break;
      case VesselPath::StraightZ:
        C.row(i) << 0, 0, h * s;
        break;
      case VesselPath::Arc: {
        const double R = 40.0, phi = h * s / R;
        C.row(i) << R * std::sin(phi), R * (1.0 - std::cos(phi)), 0;
        break;
      }
      case VesselPath::Helix:
        C.row(i) << 20.0 * std::cos(0.12 * s), 20.0 * std::sin(0.12 * s), 1.5 * s;
        break;
    }
  }
  return C;
}

Centerline vessel_phantom_centerline(VesselPath path, Index n, double radius, double spacing) {
  require_positive(radius, "vessel phantom: radius");
  Centerline line;
  line.points = vessel_phantom_atoms(path, n, spacing);
  line.radii = VecX::Constant(n, radius);
  line.name = to_string(path);
  return line;
}

MatX3 cross_section_offsets(CrossSectionShape shape, Index M, double scale) {  // §8.0
  require(M >= 3, "cross-section: need at least 3 spokes (got ", M, ")");
  require_positive(scale, "cross-section: scale");
  MatX3 O(M, 3);
  for (Index j = 0; j < M; ++j) {
    const double th = 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(M);
    const double b = shape == CrossSectionShape::Circular ? 3.0 : 1.8;
    const double ot = shape == CrossSectionShape::NonPlanar ? 0.3 * std::sin(3.0 * th) : 0.0;
    O.row(j) << 3.0 * std::cos(th), b * std::sin(th), ot;
  }
  return scale * O;
}

}  // namespace medspring
