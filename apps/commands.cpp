// Every medspring command and its options, declared once. CLI11's parser, `medspring COMMAND --help`,
// the bash completion (`medspring completion bash`) and docs/cli.md (`medspring help --markdown`) are
// built from these declarations; the command bodies read them through `Args` (cli.hpp). `build` and its
// kinds are declared in commands_build.cpp; options several commands share in command_options.hpp.
//
// Adding an option (CONTRIBUTING.md): one line in the command's `options` below,
//   {.name = "radius", .value = "R", .unit = "mm", .def = "8", .help = "contact disk radius a"},
// (a flag: no .value), its use in cmd_<name>.cpp (`args.number("radius", 8.0)`, and the name in the
// body's require_known list if it has one), then `medspring help --markdown > docs/cli.md`.
#include "commands.hpp"

#include "command_options.hpp"
#include "medspring/scene/study_settings.hpp"
#include "thin_tet_options.hpp"

namespace medspring::cli {

const std::vector<CommandSpec>& commands() {
  static const std::vector<CommandSpec> list = {
      {.name = "demo",
       .summary = "press and release the bundled phantoms and real anatomy, print what happened",
       .usage = "medspring demo [--force F] [--json]",
       .about =
           "Presses and releases the bundled models (hybrid kidney phantom, surface tube) and prints the\n"
           "contact displacement under the force, the time to return to rest and the cost per update.",
       .options = {{.name = "force", .value = "F", .unit = "N", .def = "1", .help = "the pressing force"},
                   kJson},
       .run = cmd_demo},
      {.name = "bench",
       .summary = "time one update of every model (median, p99; --json for scripts)",
       .usage =
           "medspring bench [--filter TEXT] [--quick] [--samples N] [--json]\n"
           "       medspring bench --compare [--threads N] [--quick] [--no-bullet] [--sizes LIST] [--order "
           "O] "
           "[--json]\n"
           "       medspring bench --scaling --out DIR [--threads N] [--quick] [--no-bullet]\n"
           "       medspring bench --gpu [--sizes N,N,..] [--batch B] [--kidney FILE] [--cpu-max N] "
           "[--no-torch] "
           "[--compact] [--gather LIST] [--models-per-thread LIST] [--packed] [--out DIR] [--device I]",
       .about =
           "Times one update of every benchmark case (ALGORITHMS.md D-18): 200 warm-up updates, then N "
           "timed\n"
           "updates, single thread (the _threads2 case: two). Prints median, p99 and mean in microseconds, "
           "and\n"
           "ns per spring; --json:\n"
           "{\"results\": [{\"name\", \"median_us\", \"p99_us\", \"mean_us\", \"nodes\", \"springs\", "
           "...}]}.\n"
           "--compare: MedSpring (1 and N threads), the plain reference loop and Bullet btSoftBody on the "
           "same\n"
           "tube at 1.2k, 10k, 100k and 1M nodes (--quick: up to 100k), in one run (docs/performance.md).\n"
           "--scaling: the same from 1.2k to 3M nodes; writes DIR/scaling.json and the log-log plot\n"
           "DIR/scaling.png.\n"
           "--gpu: the tube (default 1.2k, 120k, 1M, 16M nodes) on the GPU in fp64 and fp32, B hybrid "
           "kidneys\n"
           "in one batch, bandwidth against the measured copy bandwidth, the CPU engine and a PyTorch step "
           "in\n"
           "the same run (docs/gpu.md); DIR/gpu_bench.json and gpu_bench.png. Exits non-zero without a GPU.\n"
           "Each mode takes only its own options.",
       .options =
           {{.name = "filter", .value = "TEXT", .help = "only cases whose name contains TEXT"},
            {.name = "quick", .help = "200 samples, no 1M-node case (--compare: up to 100k nodes)"},
            {.name = "samples",
             .value = "N",
             .def = "2000; --compare 1000; --quick 200",
             .help = "timed updates per case"},
            {.name = "json", .help = "print the results as JSON on stdout"},
            {.name = "compare", .help = "MedSpring against the plain loop and Bullet on the same tubes"},
            {.name = "scaling", .help = "--compare from 1.2k to 3M nodes, with a log-log plot (needs --out)"},
            {.name = "threads",
             .value = "N",
             .def = "2",
             .help = "--compare/--scaling: threads of the second run"},
            {.name = "no-bullet", .help = "--compare/--scaling: leave Bullet out"},
            {.name = "sizes",
             .value = "LIST",
             .help = "--compare: only these tubes (of 1.2k,10k,100k,1M,3M); --gpu: node counts N,N,.."},
            {.name = "order",
             .value = "built|shuffled|rcm",
             .def = "built",
             .help = "--compare: node order of the tube: ring by ring, shuffled, or shuffled then reordered"},
            {.name = "out",
             .value = "DIR",
             .help = "--scaling/--gpu: folder of the JSON results and the plot"},
            {.name = "gpu", .help = "the GPU benchmark (docs/gpu.md)"},
            {.name = "batch", .value = "B", .help = "--gpu: hybrid kidneys in one batch"},
            {.name = "cpu-max",
             .value = "N",
             .help = "--gpu: largest tube also timed on the CPU engine (nodes)"},
            {.name = "no-torch", .help = "--gpu: leave the PyTorch step out"},
            {.name = "kidney",
             .value = "FILE",
             .help = "--gpu: the batch's hybrid kidney from a model package (.msm) [default: the phantom]"},
            {.name = "compact",
             .help =
                 "--gpu: also time each tube and kidney case with compact parameters (fp64c, grid-compact)"},
            {.name = "gather",
             .value = "LIST",
             .def = "1",
             .help =
                 "--gpu with --compact: the gather batches to time (0 automatic, 1, 2, 4; rows -g2, -gauto)"},
            {.name = "models-per-thread",
             .value = "LIST",
             .help = "--gpu: also time the kidney batch with M models per thread (2, 4; rows grid-m2, "
                     "grid-compact-m2)"},
            {.name = "packed",
             .help = "--gpu: also time each tube and the kidney batch with the packed table (fp64p, "
                     "grid-packed)"},
            {.name = "device", .value = "I", .def = "0", .help = "--gpu: CUDA device index"}},
       .run = cmd_bench},
      {.name = "info",
       .summary = "summarise a mesh, volume or centerline file (counts, bounds, units, validity)",
       .usage = "medspring info FILE [--unit mm|cm|m] [--radius-array NAME] [--json]\n"
                "       medspring info --params",
       .about =
           "Summarises a mesh (.obj .stl .ply .vtp .vtk), a label volume (.nii .nii.gz .mha .mhd .nrrd) or "
           "a\n"
           "centerline (.vtp .vtk polylines with a radius array): counts, bounds in mm, units, validity.",
       .positional = "FILE",
       .options =
           {kUnit,
            {.name = "radius-array", .value = "NAME", .help = "the centerline's radius point array"},
            kJson,
            {.name = "params",
             .help = "every declared parameter (name, unit, default, range, meaning) as docs/parameters.md"}},
       .run = cmd_info},
      {.name = "haptics",
       .summary = "the 1 kHz haptic loop along a recorded tool path: tick times, force trace",
       .usage =
           "medspring haptics SCENE|MODEL --trajectory FILE [--node N] [--k-vc 0.1] [--b-vc 0.01]\n"
           "                        [--f-max 3] [--local] [--linear] [--duration MS] [--out DIR [--force]] "
           "[--json] [--device cpu|cuda]",
       .about =
           "Runs the 1 kHz haptic loop (ALGORITHMS.md §2.5, docs/haptics.md) along a recorded tool path: "
           "every 1 ms\n"
           "tick F = k_vc (x_tool - x_c) + b_vc (v_tool - v_c), saturated to --f-max, acts on the contact "
           "node,\n"
           "the model advances 1 ms and -F is the reaction for the device. Reports per-tick compute time "
           "(median,\n"
           "p99, max) and writes force_trace.csv (time, tool, contact, reaction, saturated, compute_us) to "
           "DIR.\n"
           "SCENE|MODEL is a scene file (docs/scenes.md; its loads are ignored) or kidney_phantom | tube |\n"
           "vessel_phantom.",
       .positional = "SCENE|MODEL",
       .options =
           {{.name = "trajectory",
             .value = "FILE",
             .help = "CSV rows time_ms, x, y, z (mm; optional header, # comments), linear in between"},
            {.name = "node",
             .value = "N",
             .def = "the node nearest the first tool position",
             .help = "contact surface node"},
            {.name = "k-vc", .value = "K", .unit = "N/mm", .def = "0.1", .help = "coupling stiffness"},
            {.name = "b-vc", .value = "B", .unit = "N ms/mm", .def = "0.01", .help = "coupling damping"},
            {.name = "f-max", .value = "F", .unit = "N", .def = "3", .help = "device maximum force"},
            {.name = "local", .help = "local deformation on the contact patch (eq. 6)"},
            {.name = "linear", .help = "linear springs (model names only)"},
            {.name = "duration",
             .value = "MS",
             .unit = "ms",
             .def = "the last trajectory time",
             .help = "run length"},
            {.name = "tool",
             .value = "SHAPE",
             .unit = "mm",
             .help = "a rigid tool instead of the node coupling (docs/tools.md): sphere:R, capsule:R:L or "
                     "grasper:R:L:DEG; the device gets the contact reaction; the trajectory may carry poses "
                     "time_ms, x, y, z[, qw, qx, qy, qz[, opening_deg]]"},
            {.name = "friction", .value = "MU", .def = "0", .help = "Coulomb friction of the tool's contact"},
            {.name = "threads",
             .value = "N",
             .def = "1",
             .help = "threads of the step (1..256; small models use one, docs/performance.md)"},
            {.name = "out", .value = "DIR", .help = "write force_trace.csv to DIR"},
            {.name = "device",
             .value = "D",
             .def = "cpu",
             .help = "cpu, or cuda: the loop on the GPU engine (gpu::HapticLoop, docs/gpu.md; surface and "
                     "hybrid models, no --local/--tool; an error without a GPU)"},
            kForce,
            kJson},
       .run = cmd_haptics},
      {.name = "export",
       .summary = "write built models as packages the engine alone (and the web page) rebuilds",
       .usage = "medspring export --web --out DIR [--force] [--quiet] [--json] [--scenes DIR]\n"
                "       medspring export SCENE... --out DIR [--force] [--quiet] [--json]",
       .about = "Writes built models as model packages (.msm, docs/model_packages.md): the inputs of the "
                "engine's\n"
                "constructors (rest surface, atoms, spokes or spoke offsets, parameters), so the engine "
                "alone -- the\n"
                "browser page's WebAssembly build, a simulator without VTK/CGAL -- rebuilds the model "
                "exactly and can\n"
                "change its tissue parameters. DIR also receives models.json (file, name, kind, sizes, "
                "parameters).\n"
                "SCENE...: the model of each scene file (docs/scenes.md) as <scene name>.msm.",
       .positional = "SCENE",
       .options = {{.name = "web",
                    .help =
                        "the browser page's set: the real kidney (hybrid, 458 + 42) and aorta (SMRM 40 x 30) "
                        "from $MEDSPRING_DATA (skipped, with a note, where absent), the kidney and vessel "
                        "phantoms and the plain mass-spring tube"},
                   out_dir("output folder (written whole or not at all)"),
                   kForce,
                   kQuiet,
                   kJson,
                   kScenes},
       .run = cmd_export},
      {.name = "view",
       .summary = "serve the browser page on 127.0.0.1: poke the models with the mouse (docs/web.md)",
       .usage = "medspring view [--port N] [--models DIR] [--web DIR] [--exit-after S] [--quiet]",
       .about =
           "Serves the browser page (docs/web.md) on http://127.0.0.1:N/ and prints the URL: the engine as\n"
           "WebAssembly (web/dist/medspring.mjs, built by web/build.sh), three.js (web/node_modules, npm ci) "
           "and\n"
           "the model packages of DIR (medspring export --web --out DIR). One thread, GET/HEAD only, "
           "nothing\n"
           "outside these folders. Stops on Ctrl-C / SIGTERM.",
       .options = {{.name = "port",
                    .value = "N",
                    .def = "8080",
                    .help = "port (0: any free port, the URL says which)"},
                   {.name = "models",
                    .value = "DIR",
                    .def = "web/models if present",
                    .help = "folder with models.json and the .msm files, served as /models/ (without one the "
                            "page offers the built-in phantoms)"},
                   {.name = "web",
                    .value = "DIR",
                    .def = "the source tree's web/, then <prefix>/share/medspring/web",
                    .help = "the page folder"},
                   {.name = "exit-after", .value = "S", .unit = "s", .help = "stop after S seconds (tests)"},
                   {.name = "quiet", .help = "no request log on stderr"}},
       .run = cmd_view},
      build_command(),  // commands_build.cpp
      study_command(),  // cmd_study.cpp; the switches declared in scene/study_switches.hpp
      {.name = "run",
       .summary = "run a scene file (docs/scenes.md): ParaView series, traces, summary",
       .usage =
           "medspring run SCENE --out DIR [--force] [--quiet] [--json] [--static-curve]\n"
           "                     [--checkpoint-every N] [--checkpoint FILE] [--stop-at MS] [--resume FILE]\n"
           "                     [--set P=V[,P=V]] [--threads N]",
       .about =
           "Builds the model of a scene file (docs/scenes.md), runs it for the scene's duration and writes "
           "to "
           "DIR:\n"
           "  <name>.pvd + frames/<name>_NNNNN.vtp   ParaView series of the displayed surface; point data\n"
           "                                        displacement, displacement_magnitude, "
           "local_displacement,\n"
           "                                        local_displacement_magnitude, Normals (mm)\n"
           "  <name>_atoms.pvd                      the centerline atoms (hybrid, smrm)\n"
           "  trace.csv                             every update: force, max displacement, traced "
           "nodes/atoms\n"
           "  summary.json, scene.json              results; the scene with every default filled in\n"
           "The folder is written under a temporary name and renamed when complete; a bad scene writes "
           "nothing.",
       .positional = "SCENE",
       .options = {out_dir("output folder"),
                   kForce,
                   kQuiet,
                   {.name = "json", .help = "print the summary as JSON on stdout"},
                   {.name = "static-curve",
                    .help = "also write static_curve.csv: static force-displacement of the first load"},
                   {.name = "checkpoint-every",
                    .value = "N",
                    .help = "save a checkpoint every N updates (docs/reliability.md): the simulation and the "
                            "traces so far, replaced atomically"},
                   {.name = "checkpoint",
                    .value = "FILE",
                    .def = "DIR.mscp beside DIR",
                    .help = "where checkpoints go"},
                   {.name = "stop-at",
                    .value = "MS",
                    .unit = "ms",
                    .help =
                        "stop after the update reaching MS (writing a checkpoint and the partial results)"},
                   {.name = "set",
                    .value = "P=V[,P=V]",
                    .help = "set declared parameters of the scene (docs/parameters.md), e.g. "
                            "--set integrator.dt=0.25,model.parameters.k_spoke=0.08"},
                   {.name = "threads",
                    .value = "N",
                    .def = "the scene's integrator.threads",
                    .help = "threads of the step (1..256; models below 25 000 springs per thread use fewer, "
                            "docs/performance.md)"},
                   {.name = "resume",
                    .value = "FILE",
                    .help =
                        "continue the run saved in FILE (same scene): trace.csv and the summary's results "
                        "are those of an uninterrupted run bit for bit; frames are written from the resume "
                        "point on"}},
       .run = cmd_run},
      {.name = "accuracy",
       .summary = "spring models against a CalculiX FEM reference: tables, error maps, calibration",
       .usage =
           "medspring accuracy --out DIR [--force] [--quick] [--quiet] [--json] [--E-kPa 10] [--nu 0.45]\n"
           "                          [--radius 8] [--level 1] [--scenes DIR] [--vessel-E-kPa 500] "
           "[--wall-ratio 0.1]\n"
           "                          [--no-vessel | --vessel-only]",
       .about =
           "Measures the spring models against an independent FEM reference (CalculiX, compressible "
           "Neo-Hookean,\n"
           "NLGEOM; docs/accuracy.md): first the FEM pipeline against closed forms (uniaxial stretch, "
           "cantilever,\n"
           "Boussinesq) at three refinements, then the kidney phantom and the real kidney under contact-disk "
           "loads\n"
           "of 0.2 / 0.5 / 1.0 N at 4 sites, support opposite the load: contact, RMS and max surface error "
           "of the\n"
           "surface and hybrid models (linear, Duffing, + local), default and calibrated (fitted on two "
           "sites at\n"
           "0.5 N, errors reported on every other case). Writes DIR/accuracy.md, accuracy.json, "
           "error_maps.json\n"
           "and figures/*.png (matplotlib). Needs ccx (calculix-ccx) and tetgen; FEM results are cached\n"
           "($MEDSPRING_FEM_CACHE, default ~/.cache/medspring/fem).",
       .options =
           {out_dir("output folder (written whole or not at all)"),
            kForce,
            {.name = "quick", .help = "phantom only, 2 sites, 0.5 N, coarse validation (a smoke test)"},
            kQuiet,
            kJson,
            declared_option<FemCaseSettings>("E-kPa", "E_kPa", "E"),
            declared_option<FemCaseSettings>("nu", "nu", "NU"),
            declared_option<FemCaseSettings>("radius", "radius", "A"),
            {.name = "level",
             .value = "1|2|3",
             .def = "1",
             .help = "FEM refinement of the tables: 1 (the model's surface), 2, 3 (surface subdivided)"},
            kScenes,
            {.name = "kinds",
             .value = "LIST",
             .def = "all",
             .help = "model kinds to run: surface,hybrid,volumetric (docs/volumetric.md); opt-in: "
                     "volumetric-duffing, volumetric-corrected, volumetric-local (the disk overlay as a site "
                     "family, docs/accuracy-calibration.md), volumetric-static (the quasi-static linear "
                     "response, "
                     "docs/linear-response.md)"},
            kVolumetricNodes,
            kCompression,
            kSurfaceSubdivisions,
            kInteriorSizing,
            fit_option("nonlinear; --quick: small-strain"),
            kTrainForce,
            kTrainSites,
            kSiteReadout,
            kSiteWeight,
            kFitSurfaceSprings,
            thin_tet_option(),
            thin_tet_q_max_option(),
            {.name = "no-validation", .help = "skip the closed-form validation of the FEM pipeline"},
            {.name = "forces",
             .value = "LIST",
             .unit = "N",
             .def = "0.2,0.5,1.0",
             .help = "contact forces (training at 0.5 N or the smallest)"},
            {.name = "organs",
             .value = "LIST",
             .def = "phantom,kidney",
             .help =
                 "organs: a comma list of phantom, kidney, aorta (the aorta: surface and volumetric kinds)"},
            {.name = "vessel-E-kPa",
             .value = "E",
             .unit = "kPa",
             .def = "the SMRM's wall, 500",
             .help = "the vessel wall; the SMRM of the paper's aorta (VMR 0159; --quick: a 12-atom "
                     "phantom) against the wall as a tube of tetrahedra, ends clamped, at 5 atoms x "
                     "0.05 / 0.5 N: centerline error"},
            {.name = "wall-ratio",
             .value = "R",
             .def = "the SMRM's, 0.1",
             .help = "vessel wall thickness / lumen radius"},
            {.name = "no-vessel", .help = "leave the vessel out"},
            {.name = "vessel-only", .help = "run only the vessel"},
            {.name = "indentation-only",
             .help = "only the force-indentation of a rigid sphere (issue 18; part of a full run): Hertz "
                     "validation of the FEM contact, then the real kidney: FEM vs the sphere tool"},
            {.name = "no-indentation", .help = "leave the sphere indentation out of a full run"},
            {.name = "volume-term-variants",
             .help = "volumetric kinds: also the small-strain diagnostic of the volume term per tetrahedron, "
                     "per node and blended (docs/volumetric-mesh.md)"}},
       .run = cmd_accuracy},
      {.name = "calibrate",
       .summary = "fit spring stiffnesses to a tissue (E, nu) on FEM responses; held-out errors",
       .usage = "medspring calibrate [--organ phantom|kidney|aorta] [--kind hybrid|surface|volumetric] "
                "[--linear]\n"
                "                           [--E-kPa 10] [--nodes 2000] [--nu 0.45] [--radius 8] [--json] "
                "[--quiet]",
       .about =
           "Fits the stiffness of each spring family (surface: k, k_r; hybrid: k_surf, k_spoke, k_cl, k_r;\n"
           "k_loc = k_surf) to the CalculiX FEM response of a tissue (E, nu) on training loads (two sites "
           "at\n"
           "0.5 N), and reports the error on the held-out loads and sites (docs/accuracy.md). Prints the\n"
           "parameters in N/mm.",
       .options =
           {{.name = "organ", .value = "phantom|kidney|aorta", .def = "phantom", .help = "the organ"},
            {.name = "kind", .value = "hybrid|surface|volumetric", .def = "hybrid", .help = "the model kind"},
            {.name = "linear", .help = "linear springs (default Duffing)"},
            {.name = "local",
             .help =
                 "--kind volumetric: also the kind with the local overlay of the disk load fitted as a site "
                 "family (overlay compliance a; docs/accuracy-calibration.md); reported beside the kind "
                 "without it, same run"},
            declared_option<FemCaseSettings>("E-kPa", "E_kPa", "E"),
            declared_option<FemCaseSettings>("nu", "nu", "NU"),
            declared_option<FemCaseSettings>("radius", "radius", "A"),
            kVolumetricNodes,
            kCompression,
            kSurfaceSubdivisions,
            kInteriorSizing,
            fit_option("nonlinear"),
            kTrainForce,
            kTrainSites,
            kSiteReadout,
            kSiteWeight,
            kFitSurfaceSprings,
            thin_tet_option(),
            thin_tet_q_max_option(),
            kScenes,
            kJson,
            kQuiet},
       .run = cmd_calibrate},
      {.name = "paper",
       .summary = "reproduce the paper: Fig. 9, Fig. 10 A-F, Tables I-II -> report.md, figures, tables.json",
       .usage = "medspring paper --out DIR [--force] [--quick] [--quiet] [--json] [--scenes DIR] [--accuracy "
                "FILE]",
       .about = "Reproduces the paper's experiments and writes one report: the kidney pushed and released "
                "(Fig. 9,\n"
                "1.0 N and 0.2 N, linear and nonlinear), the vessel under a light and a strong force with "
                "and without\n"
                "local deformation (Fig. 10 A-F), and the per-update timings of Tables I and II (D-18: 200 "
                "warm-up +\n"
                "2000 timed updates per case). Real anatomy from $MEDSPRING_DATA (the HuBMAP kidney, the VMR "
                "aorta\n"
                "centerline) plus the procedural phantoms. DIR receives report.md, tables.json, "
                "figures/*.png (VTK\n"
                "renders made under xvfb-run, matplotlib plots) and scenes/<name>/ with the .pvd series of "
                "every run.",
       .options = {out_dir("the report's folder, written whole or not at all"),
                   {.name = "quick",
                    .help = "phantoms only, fewer timed updates (a smoke test, well under a minute)"},
                   kForce,
                   kQuiet,
                   {.name = "json", .help = "print the tables and per-scene results as JSON on stdout"},
                   kScenes,
                   {.name = "accuracy",
                    .value = "FILE",
                    .def = "the latest full `medspring accuracy` run, kept beside the FEM cache",
                    .help = "the accuracy.json summarised in the report (CalculiX is never run here)"}},
       .run = cmd_paper},
      {.name = "completion",
       .summary = "the bash completion script (the build installs it)",
       .usage = "medspring completion bash [--out FILE]",
       .about =
           "Prints the bash completion script generated from these declarations (the build writes it to\n"
           "build/apps/medspring.bash and installs it as share/bash-completion/completions/medspring).",
       .positional = "SHELL",
       .options = {{.name = "out", .value = "FILE", .def = "stdout", .help = "write the script to FILE"}},
       .run = cmd_completion,
       .hidden = true},
  };
  return list;
}

}  // namespace medspring::cli
