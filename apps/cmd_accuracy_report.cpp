// accuracy.md of `medspring accuracy` (docs/accuracy.md).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "accuracy_indentation.hpp"
#include "accuracy_summary.hpp"
#include "accuracy_tables.hpp"
#include "commands.hpp"
#include "medspring/core/check.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/validation.hpp"
#include "medspring/fem/vessel.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/io/output_folder.hpp"
#include "medspring/medial/chain.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/models/tissue.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/sim/simulation.hpp"
#include "scene_support.hpp"

namespace medspring::cli::accuracy {

namespace fs = std::filesystem;

namespace {

std::string pct(double v) {
  return cat(std::round(v * 10) / 10);
}

}  // namespace

json validation_json(const fem::ValidationResult& r) {
  return {
      {"name", r.name}, {"level", r.level},       {"nodes", r.nodes},         {"quantity", r.quantity},
      {"fem", r.fem},   {"analytic", r.analytic}, {"rel_error", r.rel_error}, {"solve_s", r.solve_seconds}};
}

std::string markdown(const json& j) {
  std::ostringstream md;
  md << "# MedSpring accuracy against the CalculiX FEM reference\n\n";
  md << "Material: compressible Neo-Hookean, E = " << j["material"]["E_kPa"].get<double>()
     << " kPa, nu = " << j["material"]["nu"].get<double>()
     << ". Loads: uniform traction over a contact disk of radius " << j["contact_radius_mm"].get<double>()
     << " mm, the same total force and distribution on the FEM "
     << "boundary and on the spring surface. Support: surface nodes within 20 % of the thickness of the "
     << "extreme point opposite the load (fixed in the FEM, pinned in the springs). Spring models are "
        "compared "
     << "at their static equilibrium. Errors in mm and in % of the FEM contact displacement. "
        "\"contact err\": at the surface node at the disk centre; \"disk-mean err\": of the mean "
        "displacement "
        "over the disk (1/A ∫ u dA, each side with its own elements: the displacement conjugate to the "
        "traction), |mean_model - mean_FEM| / |mean_FEM|.\n\n";
  md << "## FEM pipeline against closed forms\n\n| case | level | nodes | quantity | FEM | analytic | error "
        "% | solve s |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& v : j["validation"])
    md << "| " << v["name"].get<std::string>() << " | " << v["level"] << " | " << v["nodes"] << " | "
       << v["quantity"].get<std::string>() << " | " << v["fem"].get<double>() << " | "
       << v["analytic"].get<double>() << " | " << pct(100 * v["rel_error"].get<double>()) << " | "
       << pct(v["solve_s"].get<double>()) << " |\n";
  for (const auto& o : j["organs"]) {
    md << "\n## " << o["organ"].get<std::string>() << "\n\n";
    md << "FEM: " << o["fem"]["nodes"] << " nodes, " << o["fem"]["elements"]
       << " quadratic tetrahedra (C3D10), " << o["fem"]["fixed_nodes"] << " fixed; median CalculiX solve "
       << pct(o["fem"]["median_solve_s"].get<double>()) << " s. Spring support: " << o["support_nodes"]
       << " pinned surface nodes";
    if (o.contains("support_rule") && !o["support_rule"].value("text", std::string()).empty())
      md << " (" << o["support_rule"]["text"].get<std::string>() << ")";
    md << ".\n";
    for (const auto& n : o.value("notes", json::array())) md << n.get<std::string>() << ".\n";
    if (o["fem"].contains("convergence")) {
      const auto& c = o["fem"]["convergence"];
      md << "Mesh convergence of the reference (site 0, 0.2 N): contact displacement "
         << c["contact_mm_level"].get<double>() << " mm -> " << c["contact_mm"].get<double>()
         << " mm at level " << c["level"] << " (" << c["nodes"] << " nodes): change "
         << pct(100 * c["rel_change"].get<double>()) << " % (target < 2 %).\n";
    }
    for (const auto& f : o.value("fem_failed", json::array()))
      md << "CalculiX found no equilibrium at site " << f["site"] << ", " << f["force_N"].get<double>()
         << " N (left out of the table): " << f["error"].get<std::string>().substr(0, 160) << "\n";
    if (o.contains("volumetric"))
      md << "Volumetric spring model: " << o["volumetric"]["nodes"] << " nodes ("
         << o["volumetric"]["surface_nodes"] << " on the surface), " << o["volumetric"]["tetrahedra"]
         << " linear tetrahedra (TetGen -pqY)"
         << (o["volumetric"].value("surface_subdivisions", 0) > 0
                 ? cat(", the organ's surface subdivided ", o["volumetric"].value("surface_subdivisions", 0),
                       " times (compared with the FEM at the organ's own surface nodes)")
                 : std::string())
         << ".\n";
    md << "\n| model | parameters | update us | case | contact FEM mm | contact model mm | contact err % | "
          "disk-mean err % | RMS mm | RMS % | max mm | max % |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : o["models"]) {
      for (const auto& c : r["cases"]) {
        md << "| " << r["kind"].get<std::string>() << " | "
           << (r["calibrated"].get<bool>() ? "calibrated" : "default") << " | "
           << pct(r["update_us"].get<double>()) << " | site " << c["site"] << ", "
           << c["force_N"].get<double>() << " N";
        if (c.contains("error")) {
          md << " | no equilibrium | | | | | | | |\n";
          continue;
        }
        md << (c["train"].get<bool>() ? " (train)" : "") << " | " << pct(c["contact_fem_mm"].get<double>())
           << " | " << pct(c["contact_model_mm"].get<double>()) << " | "
           << pct(c["contact_error_pct"].get<double>()) << " | " << pct(c.value("disk_mean_error_pct", 0.0))
           << " | " << pct(c["rms_mm"].get<double>()) << " | " << pct(c["rms_pct"].get<double>()) << " | "
           << pct(c["max_mm"].get<double>()) << " | " << pct(c["max_pct"].get<double>()) << " |\n";
      }
    }
    for (const auto& r : o["models"]) {  // what the volumetric calibration moved (docs/accuracy.md)
      if (!r.contains("fit")) continue;
      const auto& f = r["fit"];
      const auto m = r["multipliers"].get<std::vector<double>>();
      md << "\nCalibrated " << r["kind"].get<std::string>() << ": small-strain fit springs x "
         << f["small_strain_multipliers"][0].get<double>() << ", volume terms x "
         << f["small_strain_multipliers"][1].get<double>();
      if (f["nonlinear"].get<bool>())
        md << "; on the full response (start: " << f["start"].get<std::string>() << ") springs x " << m[0]
           << ", volume terms x " << m[1] << ", c " << f["compression_start"].get<double>() << " -> "
           << f["compression"].get<double>() << " (training cost " << f["small_strain_cost"].get<double>()
           << " at the small-strain fit, " << f["cost"].get<double>() << " fitted; " << f["evaluations"]
           << " evaluations)";
      md << "; " << pct(f["seconds"].get<double>()) << " s. Held-out mean RMS "
         << pct(r["held_out_mean_rms_pct"].get<double>()) << " %, at the sites no training load touched "
         << pct(r["held_out_sites_mean_rms_pct"].get<double>()) << " %";
      if (r.contains("held_out_mean_disk_mean_pct"))  // docs/accuracy-calibration.md
        md << "; site error (fit on the " << f.value("site_readout", std::string("node"))
           << " read-out), mean / max: contact node " << pct(r["held_out_mean_contact_pct"].get<double>())
           << " / " << pct(r["held_out_max_contact_pct"].get<double>()) << " %, disk mean "
           << pct(r["held_out_mean_disk_mean_pct"].get<double>()) << " / "
           << pct(r["held_out_max_disk_mean_pct"].get<double>()) << " %";
      md << ".\n";
    }
  }
  for (const auto& v : j.value("vessels", json::array())) {
    md << "\n## " << v["vessel"].get<std::string>() << ": SMRM centerline against the FEM wall\n\n";
    md << "The wall as a tube of quadratic tetrahedra around the SMRM's rest rings (" << v["atoms"]
       << " atoms, length " << pct(v["length_mm"].get<double>()) << " mm, lumen radius "
       << pct(v["radius_min_mm"].get<double>()) << "-" << pct(v["radius_max_mm"].get<double>())
       << " mm), wall thickness " << v["thickness_ratio"].get<double>()
       << " x the lumen radius, both end rings clamped; E = " << v["material"]["E_kPa"].get<double>()
       << " kPa, nu = " << v["material"]["nu"].get<double>() << ". FEM: " << v["fem"]["nodes"] << " nodes, "
       << v["fem"]["elements"] << " C3D10 (" << v["fem"]["spokes"] << " spokes, "
       << v["fem"]["axial_subdivisions"] << " rings per atom interval, " << v["fem"]["layers"]
       << " layer(s) through the wall); median CalculiX solve "
       << pct(v["fem"]["median_solve_s"].get<double>()) << " s. Load: " << v["load"].get<std::string>()
       << ". Compared: the SMRM atoms against the centroid of the FEM wall's mid-surface ring at each atom, "
          "in % of the FEM displacement of the loaded atom; lumen = the SMRM's rebuilt surface against the "
          "FEM lumen (RMS). Parameters: default = the scene's (wall E "
       << v["default_wall_E_kPa"].get<double>()
       << " kPa), material = wall E set to the material's, calibrated = the material's with k_cl, k_r, k_b "
          "fitted on the (train) cases.\n";
    if (v["fem"].contains("convergence")) {
      const auto& c = v["fem"]["convergence"];
      md << "Mesh convergence (first case on a wall of " << c["nodes"] << " nodes, " << c["spokes"]
         << " spokes, " << c["axial_subdivisions"] << " rings per interval, " << c["layers"]
         << " layers): loaded-atom displacement " << c["loaded_mm_level"].get<double>() << " mm -> "
         << c["loaded_mm"].get<double>() << " mm, change " << pct(100 * c["rel_change"].get<double>())
         << " %.\n";
    }
    for (const auto& f : v.value("fem_failed", json::array()))
      md << "CalculiX found no equilibrium at atom " << f["atom"] << ", " << f["force_N"].get<double>()
         << " N (left out of the table): " << f["error"].get<std::string>().substr(0, 160) << "\n";
    md << "\n| model | parameters | update us | case | loaded FEM mm | loaded SMRM mm | loaded err % | "
          "centerline RMS % | centerline max % | lumen RMS % |\n|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : v["models"])
      for (const auto& c : r["cases"]) {
        md << "| " << r["kind"].get<std::string>() << " | " << r["params"].get<std::string>() << " | "
           << pct(r["update_us"].get<double>()) << " | atom " << c["atom"] << ", "
           << c["force_N"].get<double>() << " N";
        if (c.contains("error")) {
          md << " | no equilibrium | | | | | |\n";
          continue;
        }
        md << (c["train"].get<bool>() ? " (train)" : "") << " | " << pct(c["loaded_fem_mm"].get<double>())
           << " | " << pct(c["loaded_model_mm"].get<double>()) << " | "
           << pct(c["loaded_error_pct"].get<double>()) << " | " << pct(c["rms_pct"].get<double>()) << " | "
           << pct(c["max_pct"].get<double>()) << " | " << pct(c["lumen_rms_pct"].get<double>()) << " |\n";
      }
  }
  if (j.contains("indentation")) md << indentation_markdown(j["indentation"]);
  md << "\nFigures: figures/speed_accuracy.png (time per update against the mean held-out RMS error, FEM "
        "solve "
        "time for scale), figures/error_*.png (surface error maps).\n";
  return md.str();
}

}  // namespace medspring::cli::accuracy
