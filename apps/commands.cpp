#include "commands.hpp"

namespace medspring::cli {

const std::vector<Command>& commands() {
  static const std::vector<Command> list = {
      {"bench",
       "usage: medspring bench [--filter TEXT] [--quick] [--samples N] [--json]\n\n"
       "Times one update of every benchmark case (ALGORITHMS.md D-18): 200 warm-up updates, then N timed\n"
       "updates (default 2000), single thread. Prints median, p99 and mean in microseconds, and ns per "
       "spring.\n"
       "  --filter TEXT  only cases whose name contains TEXT\n"
       "  --quick        200 samples, no 1M-node case\n"
       "  --json         {\"results\": [{\"name\", \"median_us\", \"p99_us\", \"mean_us\", \"nodes\", "
       "\"springs\", ...}]}\n"
       "medspring bench --compare [--threads N] [--quick] [--no-bullet] [--json]\n"
       "  MedSpring (1 and N threads, default 2), the plain reference loop and Bullet btSoftBody on the\n"
       "  same tube at 1.2k, 10k, 100k and 1M nodes (--quick: up to 100k), in one run (docs/performance.md)\n"
       "  --sizes LIST   only these tubes (of 1.2k,10k,100k,1M,3M)\n"
       "  --order O      node order of the tube: built (ring by ring), shuffled, rcm (shuffled, then "
       "reordered)\n"
       "medspring bench --scaling --out DIR [--threads N] [--quick] [--no-bullet]\n"
       "  the same from 1.2k to 3M nodes; writes DIR/scaling.json and the log-log plot DIR/scaling.png\n"
       "medspring bench --gpu [--sizes N,N,..] [--batch B] [--cpu-max N] [--no-torch] [--out DIR]\n"
       "                [--device I]\n"
       "  the tube (default 1.2k, 120k, 1M, 16M nodes) on the GPU in fp64 and fp32, B hybrid kidneys in\n"
       "  one batch, bandwidth against the measured copy bandwidth, the CPU engine and a PyTorch step in\n"
       "  the same run (docs/gpu.md); DIR/gpu_bench.json and gpu_bench.png. Exits non-zero without a GPU\n",
       {"json", "quick", "compare", "scaling", "no-bullet", "gpu", "no-torch"},
       cmd_bench},
      {"info",
       "usage: medspring info FILE [--unit mm|cm|m] [--radius-array NAME] [--json]\n"
       "       medspring info --params\n\n"
       "Summarises a mesh (.obj .stl .ply .vtp .vtk), a label volume (.nii .nii.gz .mha .mhd .nrrd) or a\n"
       "centerline (.vtp .vtk polylines with a radius array): counts, bounds in mm, units, validity.\n"
       "  --params  every declared parameter (name, unit, default, range, meaning) as docs/parameters.md\n",
       {"json", "params"},
       cmd_info},
      {"demo",
       "usage: medspring demo [--force N] [--json]\n\n"
       "Presses and releases the bundled models (hybrid kidney phantom, surface tube) and prints the\n"
       "contact displacement under the force, the time to return to rest and the cost per update.\n",
       {"json"},
       cmd_demo},
      {"build",
       "usage: medspring build kidney --mesh FILE [--unit mm|cm|m] [--close-holes N]\n"
       "                              | --mask FILE [--label N]\n"
       "                              [--nodes 458] [--atoms 42] [--path mst|dijkstra]\n"
       "                              --out DIR [--json] [--force]\n"
       "       medspring build centerline --mask FILE [--label N] | --mesh FILE [--unit mm|cm|m]\n"
       "                                  [--atoms 40] [--path mst|dijkstra] --out DIR [--json] [--force]\n"
       "       medspring build vessel --centerline FILE --unit mm|cm|m [--branch N | --branches all]\n"
       "                              | --mesh FILE [--unit mm|cm|m] | --segmentation FILE [--label N]\n"
       "                              [--atoms 40] [--spokes 30] [--k-b K | --wall-e E]\n"
       "                              --out DIR [--json] [--force]\n"
       "       medspring build volumetric --mesh FILE [--unit mm|cm|m] | --mask FILE [--label N]\n"
       "                              [--nodes 2000] [--surface-nodes 458] [--E-kPa 10] [--nu 0.45]\n"
       "                              --out DIR [--json] [--force]\n\n"
       "Builds a simulation model from real anatomy (ALGORITHMS.md §3-4) and writes it as .vtp files.\n"
       "  kidney      the hybrid kidney: balloon surface of exactly --nodes nodes fitted to the organ, the\n"
       "              distance-mapping skeleton of the voxelised organ with --atoms atoms, spokes (D-9),\n"
       "              parameters of §9. Writes surface.vtp, centerline.vtp (radius array\n"
       "              MaximumInscribedSphereRadius), spokes.vtp and summary.json.\n"
       "  centerline  the distance-mapping centerline with radii; ends cut by the volume border are open\n"
       "              (§3.1); an open tube mesh is capped (§3.6). Writes centerline.vtp, curve.vtp,\n"
       "              surface.vtp and summary.json.\n"
       "  vessel      the SMRM vessel (§5, docs/vessels.md): atoms with radii, spokes, the rebuilt surface\n"
       "              and its rest reconstruction error; from a mesh or segmentation the centerline of §3\n"
       "              and spokes marched to the boundary, with the Hausdorff and mean distance of the\n"
       "              rebuilt surface to the input. Bending from the wall (E --wall-e MPa, default 0.5) or\n"
       "              --k-b N/mm (0 = the paper's chain). --branch: the polyline of a centerline file\n"
       "              (default the longest); --branches all: every polyline, merged into a tree where\n"
       "              they share their start (shared junction atoms, one tube per branch; its\n"
       "              vessel.msm is of kind smrm_tree).\n"
       "              --blend [--blend-spacing MM]: one watertight surface instead (the union of the\n"
       "              closed path tubes, bound to the branch atoms; rings MM apart, default the atom\n"
       "              spacing).\n"
       "              Writes surface.vtp, atoms.vtp, spokes.vtp, vessel.msm and summary.json.\n"
       "  volumetric  the volumetric spring organ (issue 23, docs/volumetric.md): the balloon surface of\n"
       "              `build kidney` with --surface-nodes nodes, meshed inside by TetGen to about --nodes\n"
       "              nodes in all; springs on the tetrahedra's edges and a volume term per tetrahedron "
       "from\n"
       "              --E-kPa and --nu. Writes volumetric.msm (the model package with its tetrahedra),\n"
       "              surface.vtp and summary.json.\n"
       "  --mesh FILE        closed organ surface (.obj .stl .ply .vtp .vtk); --unit: its length unit\n"
       "  --close-holes N    close holes of up to N edges first (an open mesh is refused otherwise)\n"
       "  --mask FILE        label volume (.nii .nii.gz .mha .mhd .nrrd); --label: the organ's label\n"
       "                     (default: the only non-zero label). Several components: the largest is used.\n"
       "  --path mst|dijkstra  skeleton path: maximum spanning tree of the distance map (D-7, default) or\n"
       "                     the penalised shortest path (TEASAR-style; straighter in flat organs)\n"
       "  --out DIR          output folder, written whole or not at all; a non-empty one needs --force\n"
       "  --json             print the summary as JSON (counts, valence histogram, Hausdorff and mean\n"
       "                     distance to the input in mm, atoms outside, spokes per atom, build time)\n",
       {"json", "force", "blend"},
       cmd_build},
      {"run",
       "usage: medspring run SCENE --out DIR [--force] [--quiet] [--json] [--static-curve]\n"
       "                     [--checkpoint-every N] [--checkpoint FILE] [--stop-at MS] [--resume FILE]\n\n"
       "Builds the model of a scene file (docs/scenes.md), runs it for the scene's duration and writes to "
       "DIR:\n"
       "  <name>.pvd + frames/<name>_NNNNN.vtp   ParaView series of the displayed surface; point data\n"
       "                                        displacement, displacement_magnitude, local_displacement,\n"
       "                                        local_displacement_magnitude, Normals (mm)\n"
       "  <name>_atoms.pvd                      the centerline atoms (hybrid, smrm)\n"
       "  trace.csv                             every update: force, max displacement, traced nodes/atoms\n"
       "  summary.json, scene.json              results; the scene with every default filled in\n"
       "The folder is written under a temporary name and renamed when complete; a bad scene writes nothing.\n"
       "  --force         replace a non-empty DIR (refused otherwise)\n"
       "  --quiet         no progress on stderr\n"
       "  --json          print the summary as JSON on stdout\n"
       "  --static-curve  also write static_curve.csv: static force-displacement of the first load\n"
       "  --checkpoint-every N  save a checkpoint every N updates (docs/reliability.md): the simulation\n"
       "                  and the traces so far, replaced atomically; default file DIR.mscp beside DIR\n"
       "  --checkpoint FILE     where checkpoints go\n"
       "  --stop-at MS    stop after the update reaching MS (writing a checkpoint and the partial results)\n"
       "  --set P=V[,P=V] set declared parameters of the scene (docs/parameters.md), e.g.\n"
       "                  --set integrator.dt=0.25,model.parameters.k_spoke=0.08\n"
       "  --threads N     threads of the step (1..256; overrides the scene's integrator.threads;\n"
       "                  models below 25 000 springs per thread use fewer, docs/performance.md)\n"
       "  --resume FILE   continue the run saved in FILE (same scene): trace.csv and the summary's results\n"
       "                  are those of an uninterrupted run bit for bit; frames are written from the resume\n"
       "                  point on (earlier ones are in the interrupted run's folder)\n",
       {"force", "quiet", "json", "static-curve"},
       cmd_run},
      {"paper",
       "usage: medspring paper --out DIR [--force] [--quick] [--quiet] [--json] [--scenes DIR]\n\n"
       "Reproduces the paper's experiments and writes one report: the kidney pushed and released (Fig. 9,\n"
       "1.0 N and 0.2 N, linear and nonlinear), the vessel under a light and a strong force with and "
       "without\n"
       "local deformation (Fig. 10 A-F), and the per-update timings of Tables I and II (D-18: 200 warm-up +\n"
       "2000 timed updates per case). Real anatomy from $MEDSPRING_DATA (the HuBMAP kidney, the VMR aorta\n"
       "centerline) plus the procedural phantoms. DIR receives report.md, tables.json, figures/*.png (VTK\n"
       "renders made under xvfb-run, matplotlib plots) and scenes/<name>/ with the .pvd series of every "
       "run.\n"
       "  --quick        phantoms only, fewer timed updates (a smoke test, well under a minute)\n"
       "  --force        replace a non-empty DIR (refused otherwise); DIR is written whole or not at all\n"
       "  --quiet        no progress on stderr\n"
       "  --json         print the tables and per-scene results as JSON on stdout\n"
       "  --scenes DIR   the bundled scene folder (default: the source tree's scenes/, then\n"
       "                 <prefix>/share/medspring/scenes)\n"
       "  --accuracy FILE  the accuracy.json summarised in the report (default: the latest full\n"
       "                 `medspring accuracy` run, kept beside the FEM cache; CalculiX is never run here)\n",
       {"force", "quick", "quiet", "json"},
       cmd_paper},
      {"haptics",
       "usage: medspring haptics SCENE|MODEL --trajectory FILE [--node N] [--k-vc 0.1] [--b-vc 0.01]\n"
       "                        [--f-max 3] [--local] [--linear] [--duration MS] [--out DIR [--force]] "
       "[--json]\n\n"
       "Runs the 1 kHz haptic loop (ALGORITHMS.md §2.5, docs/haptics.md) along a recorded tool path: every 1 "
       "ms\n"
       "tick F = k_vc (x_tool - x_c) + b_vc (v_tool - v_c), saturated to --f-max, acts on the contact node,\n"
       "the model advances 1 ms and -F is the reaction for the device. Reports per-tick compute time "
       "(median,\n"
       "p99, max) and writes force_trace.csv (time, tool, contact, reaction, saturated, compute_us) to DIR.\n"
       "  SCENE|MODEL     a scene file (docs/scenes.md; its loads are ignored) or kidney_phantom | tube |\n"
       "                  vessel_phantom\n"
       "  --trajectory    CSV rows time_ms, x, y, z (mm; optional header, # comments), linear in between\n"
       "  --node N        contact surface node (default: the node nearest the first tool position)\n"
       "  --local         local deformation on the contact patch (eq. 6)\n"
       "  --linear        linear springs (model names only)\n"
       "  --duration MS   run length (default: the last trajectory time)\n"
       "  --tool SHAPE    a rigid tool instead of the node coupling (docs/tools.md): sphere:R,\n"
       "                  capsule:R:L or grasper:R:L:DEG (mm); the tool sits at the device position, the\n"
       "                  device gets the contact reaction (saturated to --f-max); the trajectory may carry\n"
       "                  poses: time_ms, x, y, z[, qw, qx, qy, qz[, opening_deg]]\n"
       "  --friction MU   Coulomb friction of the tool's contact (default 0)\n"
       "  --threads N     threads of the step (1..256; small models use one, docs/performance.md)\n",
       {"json", "force", "local", "linear"},
       cmd_haptics},
      {"export",
       "usage: medspring export --web --out DIR [--force] [--quiet] [--json] [--scenes DIR]\n"
       "       medspring export SCENE... --out DIR [--force] [--quiet] [--json]\n\n"
       "Writes built models as model packages (.msm, docs/model_packages.md): the inputs of the engine's "
       "constructors\n"
       "(rest surface, atoms, spokes or spoke offsets, parameters), so the engine alone -- the browser "
       "page's\n"
       "WebAssembly build, a simulator without VTK/CGAL -- rebuilds the model exactly and can change its\n"
       "tissue parameters. DIR also receives models.json (file, name, kind, sizes, parameters).\n"
       "  --web     the browser page's set: the real kidney (hybrid, 458 + 42) and the real aorta (SMRM 40 "
       "x\n"
       "            30) from $MEDSPRING_DATA (skipped, with a note, where the data is absent), the kidney "
       "and\n"
       "            vessel phantoms and the plain mass-spring tube\n"
       "  SCENE...  the model of each scene file (docs/scenes.md) as <scene name>.msm\n"
       "  --force   replace a non-empty DIR (the folder is written whole or not at all)\n",
       {"json", "force", "quiet", "web"},
       cmd_export},
      {"view",
       "usage: medspring view [--port N] [--models DIR] [--web DIR] [--exit-after S] [--quiet]\n\n"
       "Serves the browser page (docs/web.md) on http://127.0.0.1:N/ and prints the URL: the engine as\n"
       "WebAssembly (web/dist/medspring.mjs, built by web/build.sh), three.js (web/node_modules, npm ci) "
       "and\n"
       "the model packages of DIR (medspring export --web --out DIR). One thread, GET/HEAD only, nothing\n"
       "outside these folders. Stops on Ctrl-C / SIGTERM.\n"
       "  --port N        port (default 8080; 0: any free port, the URL says which)\n"
       "  --models DIR    folder with models.json and the .msm files, served as /models/ (default: "
       "web/models\n"
       "                  if present; without one the page offers the built-in phantoms)\n"
       "  --web DIR       the page folder (default: the source tree's web/, then "
       "<prefix>/share/medspring/web)\n"
       "  --exit-after S  stop after S seconds (tests)\n"
       "  --quiet         no request log on stderr\n",
       {"quiet"},
       cmd_view},
      {"study",
       "usage: medspring study STUDY --out DIR [--scheduler tcp://HOST:PORT | --workers N]\n"
       "                      [--resume] [--yes] [--quiet] [--no-report] [--scaling RUNS]\n\n"
       "Runs a parameter study (docs/studies.md) on Dask distributed: a base scene, varied parameters\n"
       "(grids, lists, seeded random or Latin-hypercube samples), every run a task on the engine in a\n"
       "worker process; results stream into DIR/results.zarr and DIR/summary.csv, the report is\n"
       "DIR/study.md.\n"
       "  --scheduler ADDR  a running dask-scheduler (default: a local cluster of every core)\n"
       "  --workers N       local worker processes (0: in this process, without Dask)\n"
       "  --resume          complete the study already in DIR (redoes only the missing runs)\n"
       "  --yes             run a study with more runs than its max_runs (default 100000)\n"
       "  --scaling RUNS    also time RUNS runs on 1..N local workers for the report\n"
       "Runs the Python package medspring.study (python3 -m medspring.study takes the same arguments).\n",
       {"resume", "yes", "quiet", "no-report"},
       cmd_study},
      {"accuracy",
       "usage: medspring accuracy --out DIR [--force] [--quick] [--quiet] [--json] [--E-kPa 10] [--nu 0.45]\n"
       "                          [--radius 8] [--level 1] [--scenes DIR] [--vessel-E-kPa 500] [--wall-ratio "
       "0.1]\n"
       "                          [--no-vessel | --vessel-only]\n\n"
       "Measures the spring models against an independent FEM reference (CalculiX, compressible "
       "Neo-Hookean,\n"
       "NLGEOM; docs/accuracy.md): first the FEM pipeline against closed forms (uniaxial stretch, "
       "cantilever,\n"
       "Boussinesq) at three refinements, then the kidney phantom and the real kidney under contact-disk "
       "loads\n"
       "of 0.2 / 0.5 / 1.0 N at 4 sites, support opposite the load: contact, RMS and max surface error of "
       "the\n"
       "surface and hybrid models (linear, Duffing, + local), default and calibrated (fitted on two sites "
       "at\n"
       "0.5 N, errors reported on every other case). Writes DIR/accuracy.md, accuracy.json, error_maps.json\n"
       "and figures/*.png (matplotlib). Needs ccx (calculix-ccx) and tetgen; FEM results are cached\n"
       "($MEDSPRING_FEM_CACHE, default ~/.cache/medspring/fem).\n"
       "  --quick        phantom only, 2 sites, 0.5 N, coarse validation (a smoke test)\n"
       "  --E-kPa, --nu  the tissue (Young's modulus in kPa, Poisson ratio < 0.5)\n"
       "  --radius       contact disk radius a, mm\n"
       "  --level        FEM refinement of the tables: 1 (the model's surface), 2, 3 (surface subdivided)\n"
       "  --kinds LIST   model kinds to run: surface,hybrid,volumetric (default all; docs/volumetric.md)\n"
       "  --nodes N      node count of the volumetric model (default 2000)\n"
       "  --forces LIST  contact forces in N (default 0.2,0.5,1.0; training at 0.5 N or the smallest)\n"
       "  --organs LIST  phantom,kidney (default both)\n"
       "  --no-validation  skip the closed-form validation of the FEM pipeline\n"
       "  --vessel-E-kPa the vessel wall (default: the SMRM's wall, 500 kPa); the SMRM of the paper's aorta\n"
       "                 (VMR 0159; --quick: a 12-atom straight phantom) against the wall as a tube of\n"
       "                 tetrahedra, ends clamped, at 5 atoms x 0.05 / 0.5 N: centerline error\n"
       "  --wall-ratio   vessel wall thickness / lumen radius\n"
       "  --no-vessel, --vessel-only  leave the vessel out / run only the vessel\n"
       "  --indentation-only  only the force-indentation of a rigid sphere (issue 18; part of a full run):\n"
       "                 Hertz validation of the FEM contact, then the real kidney: FEM vs the sphere tool\n"
       "  --no-indentation  leave the sphere indentation out of a full run\n",
       {"json", "force", "quick", "quiet", "no-validation", "no-vessel", "vessel-only", "indentation-only",
        "no-indentation"},
       cmd_accuracy},
      {"calibrate",
       "usage: medspring calibrate [--organ phantom|kidney] [--kind hybrid|surface|volumetric] [--linear]\n"
       "                           [--E-kPa 10] [--nodes 2000]\n"
       "                           [--nu 0.45] [--radius 8] [--json] [--quiet]\n\n"
       "Fits the stiffness of each spring family (surface: k, k_r; hybrid: k_surf, k_spoke, k_cl, k_r; k_loc "
       "=\n"
       "k_surf) to the CalculiX FEM response of a tissue (E, nu) on training loads (two sites at 0.5 N), "
       "and\n"
       "reports the error on the held-out loads and sites (docs/accuracy.md). Prints the parameters in "
       "N/mm.\n",
       {"json", "quiet", "linear"},
       cmd_calibrate},
  };
  return list;
}

void extra_usage(std::ostream& os) {
  os << "  haptics  the 1 kHz haptic loop along a recorded tool path: tick times, force trace\n";
  os << "  export   write built models as packages the engine alone (and the web page) rebuilds\n";
  os << "  view     serve the browser page on 127.0.0.1: poke the models with the mouse (docs/web.md)\n";
  os << "  build    build a model from real anatomy: build kidney | centerline | vessel (--help)\n";
  os << "  study    parameter studies on Dask: many runs of a scene -> Zarr, CSV, study.md\n";
  os << "  run      run a scene file (docs/scenes.md): ParaView series, traces, summary\n";
  os << "  accuracy spring models against a CalculiX FEM reference: tables, error maps, calibration\n";
  os << "  calibrate fit spring stiffnesses to a tissue (E, nu) on FEM responses; held-out errors\n";
  os << "  paper    reproduce the paper: Fig. 9, Fig. 10 A-F, Tables I-II -> report.md, figures, "
        "tables.json\n";
}

}  // namespace medspring::cli
