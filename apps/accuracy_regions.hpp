// accuracy / calibrate: each case's error split by surface region (fem/error_regions.hpp) as a JSON object,
// in % of the FEM contact displacement like the case's rms_pct (docs/accuracy-calibration.md, "Where the
// held-out error sits").
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "medspring/fem/error_regions.hpp"

namespace medspring::cli::accuracy {

inline nlohmann::json regions_json(const MatX3& V, const MatX3& u, const MatX3& u_fem,
                                   const fem::ContactLoad& load, const std::vector<Index>& support,
                                   double contact_fem) {
  const auto e = fem::error_by_region(V, u, u_fem, load, support);
  const double pct = contact_fem > 0 ? 100 / contact_fem : 0.0;
  nlohmann::json out = nlohmann::json::object();
  for (std::size_t k = 0; k < e.size(); ++k)
    out[fem::kErrorRegionNames[k]] = {{"nodes", e[k].nodes},
                                      {"rms_pct", pct * e[k].rms},
                                      {"share_pct", 100 * e[k].share},
                                      {"along_pct", pct * e[k].along}};
  return out;
}

}  // namespace medspring::cli::accuracy
