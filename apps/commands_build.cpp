// `medspring build KIND` and its options, declared once (split from commands.cpp; see its header comment).
#include "command_options.hpp"
#include "commands.hpp"
#include "thin_tet_options.hpp"

namespace medspring::cli {

namespace {
const OptionSpec kCloseHoles{
    .name = "close-holes",
    .value = "N",
    .help = "close holes of up to N edges first (an open mesh is refused otherwise)"};
}  // namespace

CommandSpec build_command() {
  return {
      .name = "build",
      .summary = "build a model from real anatomy: build kidney | centerline | vessel | volumetric (--help)",
      .usage =
          "medspring build kidney|centerline|vessel|volumetric [options]   (medspring build KIND --help)",
      .about =
          "Builds a simulation model from real anatomy (ALGORITHMS.md §3-4) and writes it as .vtp files.",
      .subcommands =
          {{.name = "kidney",
            .summary = "the hybrid kidney: balloon surface, distance-mapping skeleton, spokes (D-9)",
            .usage = "medspring build kidney --mesh FILE [--unit mm|cm|m] [--close-holes N]\n"
                     "                              | --mask FILE [--label N]\n"
                     "                              [--nodes 458] [--atoms 42] [--path mst|dijkstra]\n"
                     "                              --out DIR [--json] [--force]",
            .about = "The hybrid kidney: balloon surface of exactly --nodes nodes fitted to the organ, the\n"
                     "distance-mapping skeleton of the voxelised organ with --atoms atoms, spokes (D-9),\n"
                     "parameters of §9. Writes surface.vtp, centerline.vtp (radius array\n"
                     "MaximumInscribedSphereRadius), spokes.vtp and summary.json.",
            .options = {kMesh,
                        kUnit,
                        kCloseHoles,
                        kMask,
                        kLabel,
                        {.name = "nodes", .value = "N", .def = "458", .help = "surface nodes"},
                        {.name = "atoms", .value = "N", .def = "42", .help = "centerline atoms"},
                        kPath,
                        kBuildOut,
                        kBuildJson,
                        kForce}},
           {.name = "centerline",
            .summary = "the distance-mapping centerline with radii",
            .usage =
                "medspring build centerline --mask FILE [--label N] | --mesh FILE [--unit mm|cm|m]\n"
                "                                  [--atoms 40] [--path mst|dijkstra] --out DIR [--json] "
                "[--force]",
            .about = "The distance-mapping centerline with radii; ends cut by the volume border are open "
                     "(§3.1);\n"
                     "an open tube mesh is capped (§3.6). Writes centerline.vtp, curve.vtp, surface.vtp and\n"
                     "summary.json.",
            .options = {kMask, kLabel, kMesh, kUnit, kAtoms40, kPath, kBuildOut, kBuildJson, kForce}},
           {.name = "vessel",
            .summary = "the SMRM vessel (§5, docs/vessels.md): atoms, spokes, the rebuilt surface",
            .usage =
                "medspring build vessel --centerline FILE --unit mm|cm|m [--branch N]\n"
                "                              | --mesh FILE [--unit mm|cm|m] | --segmentation FILE "
                "[--label "
                "N]\n"
                "                              [--branches all [--blend [--blend-spacing MM] | --no-blend]]\n"
                "                              [--atoms 40] [--spokes 30] [--k-b K | --wall-e E]\n"
                "                              --out DIR [--json] [--force]",
            .about = "The SMRM vessel (§5, docs/vessels.md): atoms with radii, spokes, the rebuilt surface "
                     "and its rest\n"
                     "reconstruction error; from a mesh or segmentation the centerline of §3 and spokes "
                     "marched to the\n"
                     "boundary, with the Hausdorff and mean distance of the rebuilt surface to the input. "
                     "With\n"
                     "--branches all: a vessel tree (every polyline of the file; from a mesh or "
                     "segmentation the\n"
                     "skeleton of every endpoint, junctions where the paths meet). Writes surface.vtp, "
                     "atoms.vtp,\n"
                     "spokes.vtp, vessel.msm and summary.json.",
            .options =
                {{.name = "centerline",
                  .value = "FILE",
                  .help = "centerline polylines (.vtp .vtk) with a radius array; needs --unit"},
                 {.name = "branch",
                  .value = "N",
                  .def = "the longest",
                  .help = "the polyline of the centerline file to use"},
                 {.name = "branches",
                  .value = "all",
                  .help = "every polyline, merged into a tree where they share their start (shared "
                          "junction atoms, one tube per branch; its vessel.msm is of kind smrm_tree); with "
                          "--mesh or --segmentation: the tree skeleton of every endpoint, junctions where "
                          "the paths meet"},
                 {.name = "blend",
                  .help = "with --branches all: one watertight surface (the union of the closed path tubes, "
                          "bound to the branch atoms; the default of a tree from --mesh or --segmentation, "
                          "there fitted to the input's wall)"},
                 {.name = "no-blend",
                  .help = "a tree from --mesh or --segmentation: one open tube per branch (the skeleton's "
                          "circles) instead of the watertight surface"},
                 {.name = "blend-spacing",
                  .value = "MM",
                  .unit = "mm",
                  .def = "the atom spacing",
                  .help = "--blend: distance of the surface's rings"},
                 kMesh,
                 {.name = "segmentation", .value = "FILE", .help = "label volume of the vessel"},
                 {.name = "mask", .value = "FILE", .help = "same as --segmentation"},
                 kLabel,
                 kUnit,
                 kAtoms40,
                 {.name = "spokes", .value = "N", .def = "30", .help = "spokes per atom"},
                 {.name = "k-b",
                  .value = "K",
                  .unit = "N/mm",
                  .help = "bending stiffness of the chain (0 = the paper's chain)"},
                 {.name = "wall-e",
                  .value = "E",
                  .unit = "MPa",
                  .def = "0.5",
                  .help = "bending from the wall's Young's modulus"},
                 kBuildOut,
                 kBuildJson,
                 kForce}},
           {.name = "volumetric",
            .summary = "the volumetric spring organ (issue 23, docs/volumetric.md): tetrahedra inside the "
                       "balloon surface",
            .usage = "medspring build volumetric --mesh FILE [--unit mm|cm|m] [--close-holes N]\n"
                     "                              | --mask FILE [--label N]\n"
                     "                              [--nodes 2000] [--surface-nodes 458] [--E-kPa 10] "
                     "[--nu 0.45]\n"
                     "                              [--interior-sizing volume|surface]\n"
                     "                              [--thin-tet off|scale_springs|clip] "
                     "[--thin-tet-q-max 0.3]\n"
                     "                              --out DIR [--json] [--force]",
            .about =
                "The volumetric spring organ: the balloon surface of `build kidney` with --surface-nodes\n"
                "nodes, meshed inside by TetGen to about --nodes nodes in all; springs on the\n"
                "tetrahedra's edges and a volume term per tetrahedron from --E-kPa and --nu. Writes\n"
                "volumetric.msm (the model package with its tetrahedra), surface.vtp and summary.json.\n"
                "Needs the fem layer (TetGen).",
            .options =
                {kMesh,
                 kUnit,
                 kCloseHoles,
                 kMask,
                 kLabel,
                 {.name = "nodes", .value = "N", .def = "2000", .help = "nodes in all (surface + interior)"},
                 {.name = "surface-nodes", .value = "N", .def = "458", .help = "surface nodes"},
                 kInteriorSizing,
                 thin_tet_option(),
                 thin_tet_q_max_option(),
                 {.name = "E-kPa",
                  .value = "E",
                  .unit = "kPa",
                  .def = "10",
                  .help = "the tissue's Young's modulus"},
                 {.name = "nu", .value = "NU", .def = "0.45", .help = "the tissue's Poisson ratio (< 0.5)"},
                 kBuildOut,
                 kBuildJson,
                 kForce}}},
      .run = cmd_build};
}

}  // namespace medspring::cli
