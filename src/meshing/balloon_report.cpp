// The parts of the balloon build that need no CGAL: the size warning and the report text.
#include <cmath>

#include "medspring/core/check.hpp"
#include "medspring/meshing/balloon.hpp"

namespace medspring {

std::string organ_size_warning(double diagonal_mm) {
  if (diagonal_mm < 5.0) {
    const double as_m = diagonal_mm * 1000.0;
    return cat("organ is ", diagonal_mm, " mm across: are the units metres? use --unit m (it would be ", as_m,
               " mm)");
  }
  if (diagonal_mm > 1000.0)
    return cat("organ is ", diagonal_mm,
               " mm across: are the units micrometres? use --unit um (or check the file's scale)");
  return {};
}

std::string BalloonReport::summary() const {
  std::string s = cat("balloon surface: ", nodes, " nodes, ", edges, " edges, ", faces, " faces\n");
  s += cat("  remeshed at edge length ", target_edge_length, " mm to ", remeshed_nodes, " nodes; ", collapses,
           " collapses, ", splits, " splits, ", flips, " valence flips, ", feature_snaps, " feature snaps\n");
  s += "  valences:";
  for (std::size_t d = 0; d < valence_histogram.size(); ++d)
    if (valence_histogram[d] > 0) s += cat(" ", d, ":", valence_histogram[d]);
  s += cat("  (", std::round(valence6_fraction * 1000.0) / 10.0, " % with six neighbours)\n");
  if (hausdorff_mm >= 0.0)
    s += cat("  distance to the organ: Hausdorff ", hausdorff_mm, " mm, mean ", mean_distance_mm, " mm\n");
  s += cat("  organ size ", organ_size_mm, " mm, built in ", seconds, " s\n");
  for (const auto& w : warnings) s += cat("  warning: ", w, "\n");
  return s;
}

std::vector<std::string> BalloonReport::note_lines() const {
  std::vector<std::string> n;
  n.push_back(cat(nodes, " nodes, ", faces, " triangles, ", std::round(1000 * valence6_fraction) / 10,
                  " % with six neighbours, Hausdorff ", hausdorff_mm, " mm, mean distance ", mean_distance_mm,
                  " mm to the organ, ", seconds, " s"));
  for (const auto& w : warnings) n.push_back("warning: " + w);
  return n;
}

}  // namespace medspring
