// Options several commands share, with the same meaning (apps/commands.cpp, apps/commands_build.cpp).
#pragma once

#include <stdexcept>
#include <string>

#include "cli.hpp"
#include "medspring/core/params.hpp"

namespace medspring::cli {

// An option whose unit, default and help are a declared field's (core/params.hpp): `calibrate --E-kPa`
// is FemCaseSettings::E_kPa (scene/study_settings.hpp, docs/parameters.md).
template <ParamStruct T>
inline OptionSpec declared_option(const char* option, const char* field, const char* value) {
  for (const ParamRow& r : param_rows<T>())
    if (r.name == field)
      return {.name = option,
              .value = value,
              .unit = r.unit,
              .def = r.default_value,
              .help = r.range.empty() ? r.doc : cat(r.doc, "; ", r.range)};
  throw std::logic_error(cat("apps/command_options.hpp: '", field, "' is not a declared field"));
}

inline const OptionSpec kJson{.name = "json", .help = "print the results as JSON on stdout"};
inline const OptionSpec kQuiet{.name = "quiet", .help = "no progress on stderr"};
inline const OptionSpec kForce{.name = "force", .help = "replace a non-empty DIR (refused otherwise)"};
inline OptionSpec out_dir(const std::string& help) {
  return {.name = "out", .value = "DIR", .help = help};
}
inline const OptionSpec kScenes{.name = "scenes",
                                .value = "DIR",
                                .def = "the source tree's scenes/, then <prefix>/share/medspring/scenes",
                                .help = "the bundled scene folder"};
// The volumetric kind's options of `accuracy` and `calibrate` (docs/volumetric.md,
// docs/accuracy-nonlinear.md).
inline const OptionSpec kVolumetricNodes{
    .name = "nodes", .value = "N", .def = "2000", .help = "node count of the volumetric model"};
inline const OptionSpec kCompression{
    .name = "compression",
    .value = "C",
    .def = "32",
    .help = "volumetric kinds: compression stiffening c (units of mu; 0 = off; docs/volumetric.md)"};
inline const OptionSpec kSurfaceSubdivisions{
    .name = "surface-subdivisions",
    .value = "K",
    .def = "0",
    .help =
        "volumetric kinds: the model's surface subdivided K times (0..3) before meshing; scored at the "
        "organ's own surface nodes (docs/accuracy-nonlinear.md, \"The load site\")"};
inline const OptionSpec kInteriorSizing{
    .name = "interior-sizing",
    .value = "volume|surface",
    .def = "volume",
    .help =
        "volumetric kinds: one TetGen volume bound to about --nodes, or a sizing field no finer than the "
        "surface's edges, coarser inside (--nodes: at most; docs/volumetric.md)"};
inline OptionSpec fit_option(const char* def) {
  return {.name = "fit",
          .value = "nonlinear|small-strain",
          .def = def,
          .help =
              "volumetric calibration: the small-strain fit refined with c on the full response, or the "
              "small-strain fit alone (docs/accuracy-nonlinear.md)"};
}
inline const OptionSpec kTrainForce{
    .name = "train-force",
    .value = "F[,F...]",
    .unit = "N",
    .def = "0.5, or the smallest of --forces",
    .help = "the load(s) of the training sites (among the forces); every other case is held out"};
inline const OptionSpec kTrainSites{
    .name = "train-sites",
    .value = "I[,I...]",
    .def = "0,1; --quick: 0",
    .help =
        "the training sites, by index (0..3; --quick: 0..1); every other site is held out (a site left "
        "out of training scores a choice made on the others: docs/accuracy-calibration.md)"};
inline const OptionSpec kSiteReadout{
    .name = "site-readout",
    .value = "node|disk-mean",
    .def = "node",
    .help =
        "the calibration's site term: the contact node, or the mean displacement over the loaded disk "
        "(the FEM's read-out; docs/accuracy-calibration.md)"};
inline const OptionSpec kSiteWeight{
    .name = "site-weight",
    .value = "W",
    .def = "1",
    .help =
        "the weight of the calibration's site term against the surface term (>= 0; "
        "docs/accuracy-calibration.md)"};
inline const OptionSpec kFitSurfaceSprings{
    .name = "fit-surface-springs",
    .help =
        "volumetric calibration: also fit the springs between two surface nodes as a family of their own "
        "(surface_spring_scale; needs --fit nonlinear; docs/accuracy-calibration.md)"};
inline const OptionSpec kUnit{
    .name = "unit", .value = "mm|cm|m", .help = "length unit of the input's coordinates"};
inline const OptionSpec kLabel{
    .name = "label",
    .value = "N",
    .def = "the only non-zero label",
    .help = "the organ's label in the mask (several components: the largest is used)"};
inline const OptionSpec kAtoms40{.name = "atoms", .value = "N", .def = "40", .help = "centerline atoms"};
inline const OptionSpec kPath{
    .name = "path",
    .value = "mst|dijkstra",
    .def = "mst",
    .help =
        "skeleton path: maximum spanning tree of the distance map (D-7) or the penalised "
        "shortest path (TEASAR-style; straighter in flat organs)"};
inline const OptionSpec kBuildOut{
    .name = "out",
    .value = "DIR",
    .help = "output folder, written whole or not at all; a non-empty one needs --force"};
inline const OptionSpec kBuildJson{
    .name = "json",
    .help =
        "print the summary as JSON (counts, valence histogram, Hausdorff and mean "
        "distance to the input in mm, atoms outside, spokes per atom, build time)"};
inline const OptionSpec kMesh{
    .name = "mesh", .value = "FILE", .help = "closed organ surface (.obj .stl .ply .vtp .vtk)"};
inline const OptionSpec kMask{
    .name = "mask", .value = "FILE", .help = "label volume (.nii .nii.gz .mha .mhd .nrrd)"};

/// `medspring build` and its kinds (commands_build.cpp).
CommandSpec build_command();
/// `medspring study`, from the runner's declared switches (cmd_study.cpp, scene/study_switches.hpp).
CommandSpec study_command();

}  // namespace medspring::cli
