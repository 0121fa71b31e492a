// `medspring accuracy` and `medspring calibrate` (docs/accuracy.md): the spring models against the
// CalculiX FEM reference of the same organ under the same supports and contact loads, with default and
// calibrated stiffnesses.
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
#include "medspring/scene/study_settings.hpp"
#include "medspring/sim/simulation.hpp"
#include "scene_support.hpp"
#include "thin_tet_options.hpp"

namespace medspring::cli::accuracy {

// --kinds surface,hybrid,volumetric (default all) and --nodes N (volumetric node count, default 2000).
// `known` plus the options read_kind_options reads, which accuracy and calibrate both accept.
std::vector<std::string> with_kind_options(std::vector<std::string> known) {
  for (const char* o :
       {"compression", "surface-subdivisions", "interior-sizing", "fit", "train-force", "train-sites",
        "site-readout", "site-weight", "fit-surface-springs", "thin-tet", "thin-tet-q-max"})
    known.emplace_back(o);
  return known;
}

void read_kind_options(const Args& args, Settings& st, const std::string& cmd) {
  if (auto k = args.get("kinds")) {
    std::stringstream ss(*k);
    std::string item;
    while (std::getline(ss, item, ',')) {
      require(item == "surface" || item == "hybrid" || item == "volumetric" || item == "volumetric-duffing" ||
                  item == "volumetric-corrected" || item == "volumetric-local" || item == "volumetric-static",
              cmd, ": --kinds: unknown kind '", item,
              "' (expected surface, hybrid, volumetric, volumetric-duffing, volumetric-corrected, "
              "volumetric-local, volumetric-static)");
      st.kinds.push_back(item);
    }
    require(!st.kinds.empty(), cmd, ": --kinds must name at least one kind");
  }
  if (auto f = args.get("forces")) {
    std::stringstream ss(*f);
    std::string item;
    while (std::getline(ss, item, ',')) {
      char* end = nullptr;
      const double v = std::strtod(item.c_str(), &end);
      require(end && *end == '\0' && std::isfinite(v) && v > 0 && v <= 100, cmd, ": --forces: '", item,
              "' is not a force in (0, 100] N");
      st.forces.push_back(v);
    }
    require(!st.forces.empty(), cmd, ": --forces must list at least one force");
  }
  const long long nodes = args.integer("nodes", 2000);
  require(nodes >= 10 && nodes <= 200000, cmd, ": --nodes must be in [10, 200000] (got ", nodes, ")");
  st.volumetric_nodes = static_cast<Index>(nodes);
  const long long sub = args.integer("surface-subdivisions", 0);
  require(sub >= 0 && sub <= 3, cmd, ": --surface-subdivisions must be in [0, 3] (got ", sub, ")");
  st.surface_subdivisions = static_cast<int>(sub);
  st.interior_sizing = fem::parse_mesh_sizing(args.get_or("interior-sizing", "volume"));
  // the training forces and the site read-out: the rules are fem::parse_train_forces / SiteReadout's, the
  // same as Python's medspring.calibrate(train_forces=, site_readout=)
  if (auto tf = args.get("train-force")) {  // one force or a list (the training sites' loads)
    try {
      st.train_forces = fem::parse_train_forces(*tf);
    } catch (const InvalidInput& e) {
      throw InvalidInput(cat(cmd, ": --train-force ", e.what()));
    }
  }
  if (auto ts = args.get("train-sites")) {  // indices among the organ's sites: 4, or 2 with --quick
    const long last = st.quick ? 1 : 3;
    std::stringstream ss(*ts);
    std::string item;
    while (std::getline(ss, item, ',')) {
      char* end = nullptr;
      const long v = std::strtol(item.c_str(), &end, 10);
      require(!item.empty() && end && *end == '\0' && v >= 0 && v <= last, cmd, ": --train-sites: '", item,
              "' is not a site index in [0, ", last, "]");
      require(std::find(st.train_sites.begin(), st.train_sites.end(), static_cast<int>(v)) ==
                  st.train_sites.end(),
              cmd, ": --train-sites: site ", v, " is listed twice");
      st.train_sites.push_back(static_cast<int>(v));
    }
    require(!st.train_sites.empty(), cmd, ": --train-sites must list at least one site");
  }
  const std::string fit = args.get_or("fit", st.quick ? "small-strain" : "nonlinear");  // --quick: seconds
  require(fit == "nonlinear" || fit == "small-strain", cmd,
          ": --fit must be nonlinear or small-strain (got '", fit, "')");
  st.fit_nonlinear = fit == "nonlinear";
  try {
    st.site_disk_mean = parse_enum(args.get_or("site-readout", "node"),
                                   static_cast<fem::SiteReadout*>(nullptr)) == fem::SiteReadout::DiskMean;
  } catch (const InvalidInput& e) {
    throw InvalidInput(cat(cmd, ": --site-readout ", e.what()));
  }
  if (auto w = args.get("site-weight")) {  // the rule is fem::checked_site_weight, Python's site_weight=
    try {
      st.site_weight = fem::parse_site_weight(*w);
    } catch (const InvalidInput& e) {
      throw InvalidInput(cat(cmd, ": --site-weight ", e.what()));
    }
  }
  st.fit_surface_springs = args.flag("fit-surface-springs");
  require(!st.fit_surface_springs || st.fit_nonlinear, cmd,
          ": --fit-surface-springs is fitted on the full response: it needs --fit nonlinear");
  VolumetricSettings thin;  // --thin-tet, --thin-tet-q-max through the declaration (thin_tet_options.hpp)
  read_thin_tet_options(args, thin, cmd);
  st.thin_tet = thin.thin_tet;
  st.thin_tet_q_max = thin.thin_tet_q_max;
  st.compression = args.number("compression", st.compression);
  require(std::isfinite(st.compression) && st.compression >= 0, cmd, ": --compression must be >= 0 (got ",
          st.compression, ")");
  require(!st.fit_surface_springs || st.compression > 0, cmd,
          ": --fit-surface-springs is fitted in the nonlinear refine, which needs --compression > 0");
}

void note(const Settings& s, const std::string& line) {
  if (!s.quiet) std::cerr << line << std::endl;
}

}  // namespace medspring::cli::accuracy

namespace medspring::cli {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace accuracy;

int cmd_accuracy(const Args& args) {
  args.require_known(with_kind_options({"out",
                                        "force",
                                        "quick",
                                        "quiet",
                                        "json",
                                        "E-kPa",
                                        "nu",
                                        "radius",
                                        "level",
                                        "scenes",
                                        "kinds",
                                        "nodes",
                                        "no-validation",
                                        "forces",
                                        "organs",
                                        "vessel-E-kPa",
                                        "wall-ratio",
                                        "no-vessel",
                                        "vessel-only",
                                        "indentation-only",
                                        "no-indentation",
                                        "volume-term-variants"}));
  const auto out = args.get("out");
  if (!out) throw InvalidInput("accuracy: --out DIR is required");
  Settings st;
  const FemCaseSettings def{};  // the declared defaults (scene/study_settings.hpp)
  st.material = fem::Material::from_kpa(args.number("E-kPa", def.E_kPa), args.number("nu", def.nu));
  fem::validate_material(st.material, "accuracy: --E-kPa/--nu");
  st.radius = args.number("radius", def.radius);
  require(std::isfinite(st.radius) && st.radius > 0, "accuracy: --radius must be > 0 mm");
  st.quick = args.flag("quick");
  st.quiet = args.flag("quiet") || args.flag("json");
  st.level = static_cast<int>(args.integer("level", 1));
  require(st.level >= 1 && st.level <= 3, "accuracy: --level must be 1, 2 or 3");
  read_kind_options(args, st, "accuracy");
  st.volume_term_variants = args.flag("volume-term-variants");
  const bool force = args.flag("force");
  check_output_folder(*out, force);

  json j = {{"material", {{"E_kPa", st.material.E * 1e3}, {"nu", st.material.nu}}},
            {"contact_radius_mm", st.radius},
            {"quick", st.quick},
            {"units", "mm, N, MPa; times in s (FEM) and us (updates)"}};
  const bool vessel_only = args.flag("vessel-only");
  require(!(vessel_only && args.flag("no-vessel")),
          "accuracy: --vessel-only and --no-vessel exclude each other");
  const bool indentation_only = args.flag("indentation-only");  // issue 18: only the sphere indentation
  require(!(vessel_only && indentation_only),
          "accuracy: --vessel-only and --indentation-only exclude each other");
  json val = json::array();
  for (int level = 1; level <= (args.flag("no-validation") || vessel_only || indentation_only ? 0
                                : st.quick                                                    ? 1
                                                                                              : 3);
       ++level) {
    note(st, cat("validation level ", level));
    std::vector<fem::ValidationResult> rs = {fem::validate_uniaxial(level), fem::validate_cantilever(level)};
    if (!st.quick || level == 1)
      for (const auto& r : fem::validate_boussinesq(level)) rs.push_back(r);
    for (const auto& r : rs) val.push_back(validation_json(r));
  }
  j["validation"] = val;

  // --organs: a comma list of phantom, kidney, aorta (default phantom,kidney; --quick: the phantom)
  const std::string organ_list = args.get_or("organs", "phantom,kidney");
  bool want_phantom = false, want_kidney = false, want_aorta = false;
  {
    std::stringstream ss(organ_list);
    std::string item;
    while (std::getline(ss, item, ',')) {
      require(item == "phantom" || item == "kidney" || item == "aorta", "accuracy: --organs: unknown organ '",
              item, "' (expected a comma list of phantom, kidney, aorta)");
      (item == "phantom" ? want_phantom : item == "kidney" ? want_kidney : want_aorta) = true;
    }
    require(want_phantom || want_kidney || want_aorta, "accuracy: --organs must name at least one organ");
  }
  std::vector<Organ> organs;
  if (!vessel_only && want_phantom) organs.push_back(phantom_organ());
  FileLoader loader;
  if ((!st.quick || indentation_only) && !vessel_only && want_kidney) {
    const fs::path scenes =
        find_folder(args.get("scenes"), MEDSPRING_SOURCE_SCENES_DIR, "scenes", "bundled scenes", "phantom");
    std::string why;
    if (auto k = real_kidney(scenes, loader, why))
      organs.push_back(std::move(*k));
    else
      j["notes"].push_back("real kidney left out: " + why);
  }
  if (!vessel_only && !indentation_only && want_aorta) {  // the aorta as a solid organ (surface, volumetric)
    std::string why;
    if (auto a = real_aorta(why))
      organs.push_back(std::move(*a));
    else
      j["notes"].push_back("real aorta left out: " + why);
  }
  // The vessel material and wall (checked before any solve)
  const fem::Material vessel_mat =
      fem::Material::from_kpa(args.number("vessel-E-kPa", 1e3 * SmrmSettings{}.wall.E), st.material.nu);
  fem::validate_material(vessel_mat, "accuracy: --vessel-E-kPa");
  fem::VesselMeshSettings vms;  // 10 FEM spokes, one ring per atom interval: ~4,400 nodes on the aorta
  vms.spoke_stride = 3;
  vms.axial_subdivisions = 1;
  vms.solver.increments = 2;
  vms.thickness_ratio = args.number("wall-ratio", SmrmSettings{}.wall.thickness_ratio);
  require(std::isfinite(vms.thickness_ratio) && vms.thickness_ratio > 0 && vms.thickness_ratio <= 1,
          "accuracy: --wall-ratio must be in (0, 1] (wall thickness / lumen radius)");
  json maps = json::object();
  j["organs"] = json::array();
  for (const auto& o : organs)
    if (!indentation_only) j["organs"].push_back(run_organ(o, st, maps));
  if (!args.flag("no-vessel") && !indentation_only) {
    const fs::path scenes =
        find_folder(args.get("scenes"), MEDSPRING_SOURCE_SCENES_DIR, "scenes", "bundled scenes", "phantom");
    Scene vs = load_scene(scenes / "phantom" / "vessel_light_nonlinear.json");
    std::string vname = "vessel phantom (straight)";
    if (st.quick) {
      vs.model.atoms = 12;  // 27.5 mm of the straight phantom: a wall mesh that solves in seconds
      vs.model.smrm.atoms = 12;
    } else {
      try {
        Scene real = load_scene(scenes / "vessel_light_nonlinear.json");
        build_scene(real, &loader);  // the aorta centerline must be readable
        vs = real;
        vname = "aorta (VMR 0159)";
      } catch (const Error& e) {
        j["notes"].push_back(std::string("real aorta left out (phantom vessel used): ") + e.what());
      }
    }
    vs.model.smrm.wall.thickness_ratio = vms.thickness_ratio;
    j["vessels"].push_back(run_vessel(vs, vname, st, vessel_mat, vms, loader));
  }
  require(!(indentation_only && args.flag("no-indentation")),
          "accuracy: --indentation-only and --no-indentation exclude each other");
  if ((!st.quick || indentation_only) && !vessel_only && !args.flag("no-indentation") &&
      std::any_of(organs.begin(), organs.end(), [](const Organ& o) { return o.atoms.rows() > 0; })) {
    // a rigid sphere (issue 18) on the last kidney (the real one when it could be built; not the aorta)
    const Organ& o =
        *std::find_if(organs.rbegin(), organs.rend(), [](const Organ& og) { return og.atoms.rows() > 0; });
    const Frame f = principal_frame(o.surface.V);
    IndentationOrgan io{o.name,
                        o.surface,
                        o.atoms,
                        o.name == "real kidney" ? TissueOrgan::RealKidney : TissueOrgan::Phantom,
                        o.surface.V.row(pick_sites(o.surface.V, f, {-0.45})[0]).transpose(),
                        -f.e3,
                        fem::SupportRule{-f.e3, 0.2 * f.thickness}};
    IndentationSettings is;
    is.material = st.material;
    is.level = st.level;
    is.note = [&](const std::string& m) { note(st, m); };
    note(st, "indentation: Hertz validation");
    j["indentation"]["hertz"] = hertz_validation_json(is.hertz_level);
    j["indentation"]["organs"].push_back(indentation_study(io, is));
  }

  const fs::path scripts = find_folder(std::nullopt, MEDSPRING_SOURCE_PAPER_SCRIPTS_DIR, "scripts",
                                       "figure scripts", "accuracy_plots.py");
  const char* py_env = std::getenv("MEDSPRING_PYTHON");
  const std::string python = py_env && *py_env ? py_env : "/usr/bin/python3";
  write_output_folder(*out, force, [&](const fs::path& dir) {
    fs::create_directories(dir / "figures");
    std::ofstream(dir / "accuracy.json") << j.dump(1) << '\n';
    std::ofstream(dir / "error_maps.json") << maps.dump() << '\n';
    std::ofstream(dir / "accuracy.md") << markdown(j);
    const std::string cmd = "'" + python + "' '" + (scripts / "accuracy_plots.py").string() + "' '" +
                            dir.string() + "' > '" + (dir / "figures.log").string() + "' 2>&1";
    if (std::system(cmd.c_str()) != 0)
      throw Error(cat("accuracy: the figures failed (python3 with matplotlib); see ",
                      (dir / "figures.log").string()));
    fs::remove(dir / "figures.log");
  });
  // The full run is kept as the latest for `medspring paper`'s summary (accuracy_summary.hpp).
  if (!st.quick && !vessel_only && !indentation_only && !keep_latest_accuracy(j) && !args.flag("json"))
    std::cout << "accuracy: note: could not keep the run as " << latest_accuracy_path().string() << std::endl;
  if (args.flag("json"))
    std::cout << j.dump(1) << '\n';
  else
    std::cout << "accuracy: wrote " << *out << "/accuracy.md, accuracy.json and figures/" << std::endl;
  return 0;
}

int cmd_calibrate(const Args& args) {
  args.require_known(with_kind_options(
      {"organ", "kind", "linear", "E-kPa", "nu", "radius", "json", "quiet", "scenes", "nodes", "local"}));
  Settings st;
  const FemCaseSettings def{};  // the declared defaults (scene/study_settings.hpp)
  st.material = fem::Material::from_kpa(args.number("E-kPa", def.E_kPa), args.number("nu", def.nu));
  fem::validate_material(st.material, "calibrate: --E-kPa/--nu");
  st.radius = args.number("radius", def.radius);
  require(std::isfinite(st.radius) && st.radius > 0, "calibrate: --radius must be > 0 mm");
  st.quiet = args.flag("quiet") || args.flag("json");
  const std::string organ = args.get_or("organ", "phantom"), kind = args.get_or("kind", "hybrid");
  require(organ == "phantom" || organ == "kidney" || organ == "aorta",
          "calibrate: --organ must be phantom, kidney or aorta");
  require(kind == "hybrid" || kind == "surface" || kind == "volumetric",
          "calibrate: --kind must be hybrid, surface or volumetric");
  require(!(organ == "aorta" && kind == "hybrid"),
          "calibrate: --organ aorta has no medial skeleton for the hybrid kind (use surface or volumetric)");
  const bool local = args.flag("local");  // the disk overlay as a site family, beside the kind without it
  require(!local || (kind == "volumetric" && args.flag("linear")),
          "calibrate: --local needs --kind volumetric --linear (got --kind ", kind,
          args.flag("linear") ? "" : " without --linear", ")");
  read_kind_options(args, st, "calibrate");
  require(!(local && st.fit_surface_springs),
          "calibrate: --local and --fit-surface-springs are two different fourth families: use one");
  require(!st.fit_surface_springs || kind == "volumetric",
          "calibrate: --fit-surface-springs is a family of the volumetric kind (got --kind ", kind, ")");
  Organ o;
  FileLoader loader;
  if (organ == "phantom") {
    o = phantom_organ();
  } else if (organ == "aorta") {
    std::string why;
    auto a = real_aorta(why);
    if (!a) throw InvalidInput("calibrate: the real aorta could not be built: " + why);
    o = std::move(*a);
  } else {
    const fs::path scenes =
        find_folder(args.get("scenes"), MEDSPRING_SOURCE_SCENES_DIR, "scenes", "bundled scenes", "phantom");
    std::string why;
    auto k = real_kidney(scenes, loader, why);
    if (!k) throw InvalidInput("calibrate: the real kidney could not be built: " + why);
    o = std::move(*k);
  }
  json maps;
  std::vector<Kind> kinds{{kind, !args.flag("linear"), false}};
  if (local) kinds.push_back({kind, false, true});
  const json r = run_organ(o, st, maps, kinds, false);
  json out = {{"organ", r["organ"]}, {"material", {{"E_kPa", st.material.E * 1e3}, {"nu", st.material.nu}}}};
  if (r.contains("volumetric")) out["volumetric"] = r["volumetric"];  // mesh, effective moduli
  for (const auto& m : r["models"]) {
    if (local && !m["local"].get<bool>()) {  // the same run without the overlay, for comparison
      const char* pre = m["calibrated"].get<bool>() ? "calibrated" : "default";
      for (const char* key : {"multipliers", "held_out_mean_rms_pct", "held_out_max_rms_pct",
                              "held_out_mean_contact_pct", "held_out_max_contact_pct",
                              "held_out_mean_disk_mean_pct", "held_out_max_disk_mean_pct", "update_us"})
        out["without_overlay"][pre][key] = m[key];
      if (m.contains("fit")) out["without_overlay"][pre]["fit"] = m["fit"];
      continue;
    }
    if (!m["calibrated"].get<bool>()) {
      out["default_held_out_mean_rms_pct"] = m["held_out_mean_rms_pct"];
      out["default_held_out_mean_disk_mean_pct"] = m["held_out_mean_disk_mean_pct"];
      out["default_held_out_mean_contact_pct"] = m["held_out_mean_contact_pct"];
      continue;
    }
    const auto mult = m["multipliers"].get<std::vector<double>>();
    out["multipliers"] = mult;
    if (kind == "surface")
      out["parameters"] = {{"k_N_per_mm", 0.05 * mult[0]}, {"k_r_N_per_mm", 0.02 * mult[1]}};
    else if (kind == "volumetric") {
      out["parameters"] = {{"spring_scale", mult[0]}, {"volume_scale", mult[1]}};
      if (mult.size() > 3 && !local)
        out["parameters"]["surface_spring_scale"] = mult[3];  // --fit-surface-springs
      if (m.contains("fit")) {  // c and what the nonlinear fit moved (docs/accuracy.md)
        out["parameters"]["compression"] = m["fit"]["compression"];
        out["fit"] = m["fit"];
      }
      if (local) {  // the overlay compliance a and k_loc = k_ref / a (null: off)
        out["parameters"]["overlay_compliance"] = mult[3];
        out["parameters"]["k_loc_N_per_mm"] = m["fit"]["k_loc_N_per_mm"];
      }
    } else
      out["parameters"] = {{"k_surf_N_per_mm", 0.05 * mult[0]},
                           {"k_spoke_N_per_mm", 0.05 * mult[1]},
                           {"k_cl_N_per_mm", 0.1 * mult[2]},
                           {"k_r_N_per_mm", 0.02 * mult[3]},
                           {"k_loc_N_per_mm", 0.05 * mult[0]}};
    if (!args.flag("linear") && mult.size() > (kind == "surface" ? 2u : 4u))
      out["parameters"]["eta"] = mult[kind == "surface" ? 2 : 4];  // Duffing strength (D-3), default 1
    out["held_out_mean_rms_pct"] = m["held_out_mean_rms_pct"];
    out["held_out_sites_mean_rms_pct"] = m["held_out_sites_mean_rms_pct"];
    for (const char* key :
         {"update_us", "held_out_max_rms_pct", "held_out_mean_contact_pct", "held_out_max_contact_pct",
          "held_out_mean_disk_mean_pct", "held_out_max_disk_mean_pct"})
      out[key] = m[key];
    out["cases"] = m["cases"];
  }
  if (args.flag("json")) {
    std::cout << out.dump(1) << '\n';
    return 0;
  }
  std::cout << "calibrate: " << o.name << ", " << kind << (args.flag("linear") ? " (linear)" : " (Duffing)")
            << ", E = " << st.material.E * 1e3 << " kPa, nu = " << st.material.nu << "\n";
  for (const auto& [key, v] : out["parameters"].items())
    std::cout << "  " << key << " = " << (v.is_null() ? std::string("off") : cat(v.get<double>())) << "\n";
  if (out.contains("fit")) {
    const auto& f = out["fit"];
    std::cout << "  small-strain fit: spring_scale = " << f["small_strain_multipliers"][0].get<double>()
              << ", volume_scale = " << f["small_strain_multipliers"][1].get<double>()
              << ", compression = " << f["compression_start"].get<double>() << " (not fitted)"
              << (f["nonlinear"].get<bool>() ? "; refined on the nonlinear response above" : "") << "\n";
  }
  std::cout << "  held-out mean RMS surface error: " << out["held_out_mean_rms_pct"].get<double>()
            << " % of the FEM contact displacement (default parameters: "
            << out["default_held_out_mean_rms_pct"].get<double>()
            << " %); at the sites no training load touched: "
            << out["held_out_sites_mean_rms_pct"].get<double>() << " %\n"
            << "  held-out site error, mean / max: contact node "
            << out["held_out_mean_contact_pct"].get<double>() << " / "
            << out["held_out_max_contact_pct"].get<double>() << " %, disk mean "
            << out["held_out_mean_disk_mean_pct"].get<double>() << " / "
            << out["held_out_max_disk_mean_pct"].get<double>() << " %\n";
  if (local) {
    const auto& w = out["without_overlay"]["calibrated"];
    std::cout << "  without the overlay (same run): held-out RMS " << w["held_out_mean_rms_pct"].get<double>()
              << " / " << w["held_out_max_rms_pct"].get<double>() << " %, contact node "
              << w["held_out_mean_contact_pct"].get<double>() << " %, disk mean "
              << w["held_out_mean_disk_mean_pct"].get<double>() << " / "
              << w["held_out_max_disk_mean_pct"].get<double>() << " %\n";
  }
  for (const auto& c : out["cases"])
    if (c.contains("train") && !c["train"].get<bool>())
      std::cout << "  held out: site " << c["site"] << ", " << c["force_N"].get<double>() << " N: contact "
                << c["contact_error_pct"].get<double>() << " %, disk mean "
                << c["disk_mean_error_pct"].get<double>() << " %, RMS " << c["rms_pct"].get<double>()
                << " %\n";
  return 0;
}

}  // namespace medspring::cli
