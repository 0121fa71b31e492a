#include "medspring/fem/error_regions.hpp"

#include <cmath>
#include <limits>

#include "medspring/core/check.hpp"

namespace medspring::fem {

std::vector<ErrorRegion> error_regions(const MatX3& V, const ContactLoad& load,
                                       const std::vector<Index>& support) {
  require(std::isfinite(load.radius) && load.radius > 0,
          "error_by_region: the load radius must be > 0 mm (got ", load.radius, ")");
  for (Index s : support)
    require(s >= 0 && s < V.rows(), "error_by_region: support node ", s, " is not one of the ", V.rows(),
            " surface nodes");
  const double a = load.radius;
  std::vector<ErrorRegion> r(static_cast<std::size_t>(V.rows()), ErrorRegion::Far);
  for (Index i = 0; i < V.rows(); ++i) {
    const double d = (V.row(i).transpose() - load.centre).norm();
    if (d <= a) {
      r[i] = ErrorRegion::Disk;
      continue;
    }
    if (d <= 3 * a) {
      r[i] = ErrorRegion::Near;
      continue;
    }
    double ds = std::numeric_limits<double>::infinity();
    for (Index s : support) ds = std::min(ds, (V.row(i) - V.row(s)).norm());
    if (ds <= a) r[i] = ErrorRegion::Supports;
  }
  return r;
}

std::array<RegionError, 4> error_by_region(const MatX3& V, const MatX3& u_model, const MatX3& u_fem,
                                           const ContactLoad& load, const std::vector<Index>& support) {
  require(u_model.rows() == V.rows() && u_fem.rows() == V.rows(), "error_by_region: ", V.rows(),
          " surface nodes but displacements of ", u_model.rows(), " (model) and ", u_fem.rows(),
          " (FEM) rows");
  const std::vector<ErrorRegion> region = error_regions(V, load, support);
  std::array<RegionError, 4> out{};
  std::array<double, 4> sq{}, along_n{};
  double total = 0;
  for (Index i = 0; i < V.rows(); ++i) {
    const auto k = static_cast<std::size_t>(region[i]);
    const Vec3 d = (u_model.row(i) - u_fem.row(i)).transpose();
    out[k].nodes += 1;
    sq[k] += d.squaredNorm();
    total += d.squaredNorm();
    const double n = u_fem.row(i).norm();
    if (n > 0) {
      out[k].along += d.dot(u_fem.row(i).transpose()) / n;
      along_n[k] += 1;
    }
  }
  for (std::size_t k = 0; k < 4; ++k) {
    out[k].rms = out[k].nodes > 0 ? std::sqrt(sq[k] / static_cast<double>(out[k].nodes)) : 0.0;
    out[k].share = total > 0 ? sq[k] / total : 0.0;
    out[k].along = along_n[k] > 0 ? out[k].along / along_n[k] : 0.0;
  }
  return out;
}

}  // namespace medspring::fem
