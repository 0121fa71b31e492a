// Internals of `medspring accuracy` / `medspring calibrate` (docs/accuracy.md), split by concern:
//   cmd_accuracy_organ.cpp   the organ tables: FEM cases, model kinds, calibration, errors
//   cmd_accuracy_vessel.cpp  the vessel: SMRM centerline against the FEM wall
//   cmd_accuracy_report.cpp  accuracy.md
//   cmd_accuracy.cpp         the two commands (options, output folder, figures)
#pragma once

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/validation.hpp"
#include "medspring/fem/vessel.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/scene/scene.hpp"
#include "scene_support.hpp"

namespace medspring::cli::accuracy {

using json = nlohmann::json;

struct Organ {
  std::string name;
  SurfaceMesh surface;
  MatX3 atoms;  // the medial skeleton of the hybrid kind (empty: no hybrid rows, e.g. the aorta)
  // the supports: empty = the bed of the tables (within 20 % of the thickness opposite the load)
  std::optional<fem::SupportRule> support;
  std::string support_text;  // the rule in words for accuracy.md (empty: the bed)
  // volumetric kind (issue 23): the TetGen mesh of the surface (made once) and the material it gets
  mutable std::shared_ptr<const VolumetricMesh> vmesh;
  mutable double E_kPa = 10, nu = 0.45;
  mutable Index target_nodes = 2000;
  // --surface-subdivisions: the volumetric model's surface is `surface` subdivided this many times
  // (VolumetricMeshSettings::surface_subdivisions), held by the same rule (vsupport: its pinned nodes);
  // its first #V surface nodes are `surface`'s, where it is compared with the FEM
  mutable int surface_subdivisions = 0;
  mutable fem::MeshSizing interior_sizing = fem::MeshSizing::Volume;  // --interior-sizing
  mutable std::vector<Index> vsupport;
  // VolumetricSettings::compression
  mutable double compression = kDefaultVolumetricCompression;
  // VolumetricSettings::thin_tet, thin_tet_q_max (--thin-tet, --thin-tet-q-max)
  mutable ThinTetMode thin_tet = ThinTetMode::Off;
  mutable double thin_tet_q_max = kDefaultThinTetQMax;
};

// A model kind of the tables: "surface", "hybrid" or "volumetric", linear or Duffing, with or without the
// local overlay.
struct Kind {
  std::string base;  // surface | hybrid | volumetric
  bool nonlinear = false;
  bool local = false;
  bool corrected = false;  // volumetric: the opt-in moduli correction (VolumetricSettings::moduli_correction)
  // volumetric: the quasi-static linear response (Integrator::LinearStatic, docs/linear-response.md)
  bool linear_static = false;
  std::string label() const {
    if (linear_static) return base + " (linear static)";
    return base + (local ? " + local" : "") + (nonlinear ? " (Duffing" : " (linear") +
           (corrected ? ", moduli-corrected)" : ")");
  }
  Index stiffness_families() const { return base == "surface" || base == "volumetric" ? 2 : 4; }
  // + eta of the Duffing springs (D-3: k' = eta k / L0^2; the volumetric kind keeps eta = 1: its
  // calibration fits springs and volume terms only) + k_loc
  bool fits_eta() const { return nonlinear && base != "volumetric"; }
  // volumetric + local: (springs, volume terms, c, overlay compliance a): c keeps its slot, a sits last
  // (docs/accuracy-calibration.md, "The local overlay as a site family")
  Index families() const {
    return stiffness_families() + (fits_eta() ? 1 : 0) + (local ? (base == "volumetric" ? 2 : 1) : 0);
  }
  Index eta_index() const { return fits_eta() ? stiffness_families() : -1; }
  Index local_index() const { return local ? families() - 1 : -1; }
};

struct Frame {
  Vec3 c, e1, e3;  // centroid, long axis, thin axis (the load presses along -e3, the support is at -e3)
  double half_length = 0, thickness = 0;
};

struct Settings {
  fem::Material material;
  double radius = 8.0;
  bool quick = false;
  std::vector<std::string> kinds;                             // --kinds: the bases to run (empty: all)
  Index volumetric_nodes = 2000;                              // --nodes
  int surface_subdivisions = 0;                               // --surface-subdivisions (volumetric kinds)
  fem::MeshSizing interior_sizing = fem::MeshSizing::Volume;  // --interior-sizing (volumetric kinds)
  // --compression (volumetric kinds)
  double compression = kDefaultVolumetricCompression;
  // --thin-tet, --thin-tet-q-max (volumetric kinds; declared in VolumetricSettings)
  ThinTetMode thin_tet = ThinTetMode::Off;
  double thin_tet_q_max = kDefaultThinTetQMax;
  // --fit nonlinear (default) | small-strain: the volumetric calibration refined on the full response
  bool fit_nonlinear = true;
  // --train-force F[,F...] (N): the training sites' loads (empty: 0.5 N or the smallest force)
  std::vector<double> train_forces;
  // --train-sites I[,I...]: the training sites' indices (empty: 0 and 1, --quick: 0)
  std::vector<int> train_sites;
  // --site-readout node (default) | disk-mean: the site term of the calibration objective reads the contact
  // node or the mean over the loaded disk (docs/accuracy-calibration.md)
  bool site_disk_mean = false;
  // --site-weight W: the weight of that site term (fem::checked_site_weight; 1: the cost as before)
  double site_weight = fem::kDefaultSiteWeight;
  // --fit-surface-springs: the volumetric nonlinear fit also fits the surface-layer family
  // (VolumetricSettings::surface_spring_scale, appended as the fourth multiplier;
  // fem::refine_surface_springs)
  bool fit_surface_springs = false;
  // accuracy --volume-term-variants: the volume term per tetrahedron / per node (docs/volumetric-mesh.md)
  bool volume_term_variants = false;
  std::vector<double> forces;  // --forces (N; default 0.2, 0.5, 1.0)
  int level = 1;
  bool quiet = false;
};

/// --kinds, --forces, --nodes, --compression and --surface-subdivisions of `accuracy` and `calibrate` (cmd
/// names the command in errors).
void read_kind_options(const Args& args, Settings& st, const std::string& cmd);
/// A progress line on stderr unless --quiet / --json.
void note(const Settings& s, const std::string& line);

/// Centroid, long and thin axes of a point set.
Frame principal_frame(const MatX3& V);
/// Sites on the +e3 side at fractions t of the half length along e1: the most +e3 node near each.
std::vector<Index> pick_sites(const MatX3& V, const Frame& f, const std::vector<double>& ts);

/// Everything measured on one organ: FEM cases, then every kind (default: all) default and calibrated.
json run_organ(const Organ& o, const Settings& st, json& maps, std::vector<Kind> kinds = {},
               bool convergence = true);
/// The SMRM vessel of the scene against its FEM wall (docs/accuracy.md, "The vessel").
json run_vessel(Scene scene0, const std::string& name, const Settings& st, const fem::Material& mat,
                const fem::VesselMeshSettings& vms, FileLoader& loader);

Organ phantom_organ();
/// The real kidney of the bundled scene kidney_1.0N_nonlinear.json; nullopt (and why) when it cannot be
/// built.
std::optional<Organ> real_kidney(const std::filesystem::path& scenes, FileLoader& loader, std::string& why);
/// The aorta of the TotalSegmentator CT (aorta_totalseg_ct.obj, mm) as a solid organ: its balloon surface of
/// `surface_nodes` nodes, no skeleton (surface and volumetric kinds only), held by the rule of
/// aorta_support_rule; nullopt (and why) when the data file or the meshing layer is missing.
std::optional<Organ> real_aorta(std::string& why, Index surface_nodes = 800);
/// The aorta's supports (docs/accuracy-volumetric.md, "The aorta"): the surface facing away from the load
/// (outward normal within 60 degrees of -e3, a bed along the whole vessel, as the aorta lies on the spine)
/// and the cut cap where the segmentation met the scan's edge (within 1 mm of the lowest point, -z).
fem::SupportRule aorta_support_rule(const Frame& f);

/// One row of the closed-form validation (fem/validation.hpp) as JSON.
json validation_json(const fem::ValidationResult& r);
/// accuracy.md from the run's JSON.
std::string markdown(const json& j);

}  // namespace medspring::cli::accuracy
