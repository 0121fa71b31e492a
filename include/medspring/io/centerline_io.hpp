// Centerline files: polylines with a per-point lumen radius (VMTK output), .vtp or legacy .vtk.
//
//   auto lines = read_centerlines(find_data_file("vmr-0159-aorta-centerline.vtp"), LengthUnit::Centimetre);
//   // 4 lines of 457, 401, 581, 431 points; radii 2.61-14.83 mm
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "medspring/core/units.hpp"
#include "medspring/geometry/polyline.hpp"

namespace medspring {

/// Reads every line cell of a .vtp / .vtk PolyData file as one Centerline (named "line <n>", n the
/// cell's 0-based position among the lines), points and radii scaled from `unit` to mm. Each polyline
/// keeps its own points: VMTK's branches repeat their shared trunk and are not merged.
/// Throws IoError naming the file for: a missing or unreadable file, an unknown extension, no line
/// cells, no point array `radius_array` (the message lists the arrays that exist), a radius array
/// with more than one component, and a non-finite point or a radius that is not > 0 (the message
/// names the line and the point).
std::vector<Centerline> read_centerlines(const std::filesystem::path& path,
                                         LengthUnit unit = LengthUnit::Millimetre,
                                         const std::string& radius_array = "MaximumInscribedSphereRadius");

/// Writes centerlines (mm) as VTK XML PolyData, one polyline per Centerline, with the radii in the
/// point array `radius_array`. Atomic like write_vtp. Throws InvalidInput for a line with fewer than 2
/// points or radii of the wrong length.
void write_centerlines(const std::filesystem::path& path, const std::vector<Centerline>& lines,
                       const std::string& radius_array = "MaximumInscribedSphereRadius");

}  // namespace medspring
