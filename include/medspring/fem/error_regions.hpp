// Where on the surface a spring model's error against the FEM sits (docs/accuracy-calibration.md, "Where the
// held-out error sits"): the surface nodes split by their distance to the load and to the supports.
#pragma once

#include <array>
#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/fem/organ.hpp"

namespace medspring::fem {

/// The four regions, in this order:
///   disk:     within the contact radius a of the load centre (the loaded disk);
///   near:     between a and 3 a from it;
///   supports: farther than 3 a from the load, within a of a supported node (the supported nodes included);
///   far:      the rest.
enum class ErrorRegion { Disk = 0, Near = 1, Supports = 2, Far = 3 };
inline constexpr std::array<const char*, 4> kErrorRegionNames = {"disk", "near", "supports", "far"};

struct RegionError {
  Index nodes = 0;
  double rms = 0;    // sqrt(mean |u_model - u_fem|^2) over the region's nodes, mm (0: no nodes)
  double share = 0;  // the region's part of the sum of |u_model - u_fem|^2 over all nodes, in [0, 1]
  double along = 0;  // mean of (u_model - u_fem) . u_fem / |u_fem| over the region's nodes with
                     // u_fem != 0, mm: < 0 where the model moves too little along the FEM
};

/// The error of u_model against u_fem (both #S x 3, the organ's surface nodes V) split into the regions of
/// ErrorRegion, for a load of centre load.centre and radius load.radius held at the nodes `support`.
/// The shares sum to 1 (all 0 when the two displacements are equal). InvalidInput on sizes that differ, a
/// radius <= 0 or a support index out of range.
std::array<RegionError, 4> error_by_region(const MatX3& V, const MatX3& u_model, const MatX3& u_fem,
                                           const ContactLoad& load, const std::vector<Index>& support);

/// The region of each node (the rule above).
std::vector<ErrorRegion> error_regions(const MatX3& V, const ContactLoad& load,
                                       const std::vector<Index>& support);

}  // namespace medspring::fem
