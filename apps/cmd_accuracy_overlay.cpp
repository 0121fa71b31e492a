// `medspring accuracy` / `calibrate`: the fit of the volumetric kind with the local overlay as a site family
// (docs/accuracy-calibration.md, "The local overlay as a site family").
#include <chrono>

#include "accuracy_overlay.hpp"
#include "medspring/core/check.hpp"
#include "medspring/fem/local_site.hpp"

namespace medspring::cli::accuracy {

using json = nlohmann::json;

json fit_volumetric_overlay(const std::string& organ, const Settings& st, double compression, double k_ref,
                            const std::function<BodyPtr(const VecX&)>& make, const fem::Response& response,
                            const std::vector<fem::CalibrationCase>& training, VecX& m) {
  const auto t0 = std::chrono::steady_clock::now();
  const bool nonlinear = st.fit_nonlinear && compression > 0;
  const fem::Response full = [&](const VecX& m3, const fem::ContactLoad& l) {
    VecX mm = VecX::Zero(4);  // a = 0: the fit adds the overlay itself
    mm.head(3) = m3;
    return response(mm, l);
  };
  const BodyPtr body = make(VecX::Ones(2));  // the surface and supports are those of every m
  const fem::OverlayFit of = fem::calibrate_volumetric_overlay(
      [&](const VecX& mm, const std::vector<fem::ContactLoad>& ls) {
        return fem::spring_displacement_linear(*make(mm), ls);
      },
      nonlinear ? &full : nullptr,
      [&](const fem::ContactLoad& l) { return fem::disk_local_overlay(*body, l, k_ref); }, training);
  m = of.m;
  note(st, cat(organ, ": overlay fit springs x ", m(0), ", volume x ", m(1), ", c x ", m(2), ", overlay a ",
               of.a_small_strain, " (small strain) -> ", m(3), " (k_ref ", k_ref, " N/mm)"));
  return {{"nonlinear", nonlinear},
          {"start", "small-strain fit with the overlay (a held, then refitted)"},
          {"site_readout", st.site_disk_mean ? "disk-mean" : "node"},
          {"small_strain_multipliers", {of.m_small_strain(0), of.m_small_strain(1)}},
          {"overlay_compliance", m(3)},
          {"overlay_compliance_small_strain", of.a_small_strain},
          {"k_ref_N_per_mm", k_ref},
          {"k_loc_N_per_mm", m(3) > 0 ? json(k_ref / m(3)) : json(nullptr)},  // null: the overlay is off
          {"small_strain_cost", of.small_strain_cost},
          {"cost", of.cost},
          {"evaluations", of.evaluations},
          {"compression", compression * m(2)},
          {"compression_start", compression},
          {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()}};
}

}  // namespace medspring::cli::accuracy
