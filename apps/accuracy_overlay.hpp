// `medspring accuracy` / `calibrate`: the volumetric kind with the local overlay as a site family
// (`--kinds volumetric-local`, `calibrate --local`; docs/accuracy-calibration.md, "The local overlay as a
// site family").
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "accuracy_tables.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/models/body.hpp"

namespace medspring::cli::accuracy {

/// Fits the multipliers m = (springs, volume terms, c, overlay compliance a) of the volumetric + local kind
/// on the training loads (fem::calibrate_volumetric_overlay; the nonlinear refine with st.fit_nonlinear and
/// compression > 0). make(m): the volumetric body at (springs, volume terms[, c]); response(m, load): the
/// kind's response at the four multipliers (the static response plus a times the disk overlay at k_ref, the
/// E, nu body's local_stiffness(), N/mm). Returns the fit's record for accuracy.json / calibrate --json.
nlohmann::json fit_volumetric_overlay(const std::string& organ, const Settings& st, double compression,
                                      double k_ref, const std::function<BodyPtr(const VecX&)>& make,
                                      const fem::Response& response,
                                      const std::vector<fem::CalibrationCase>& training, VecX& m);

}  // namespace medspring::cli::accuracy
