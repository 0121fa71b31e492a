// `medspring build KIND`: from real anatomy (an organ mesh or a segmentation) to simulation models.
//   build kidney      balloon surface + distance-mapping skeleton + spokes = the hybrid kidney (§4)
//   build centerline  the distance-mapping centerline with radii (§3)
//   build vessel      the SMRM vessel (§5) from a centerline file, a mesh or a segmentation
//   build volumetric  the balloon surface of `build kidney` meshed inside by TetGen: the volumetric spring
//                     organ (issue 23, docs/volumetric.md) as a model package with its tetrahedra
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "cases.hpp"
#include "commands.hpp"
#include "medspring/core/check.hpp"
#include "thin_tet_options.hpp"

#ifdef MEDSPRING_HAVE_BUILDERS
#include "medspring/builders/centerline_build.hpp"
#include "medspring/builders/kidney_build.hpp"
#include "medspring/builders/vessel_build.hpp"
#include "medspring/io/data_dir.hpp"
#include "medspring/io/output_folder.hpp"
#include "medspring/io/temp_folders.hpp"
#include "medspring/sim/simulation.hpp"
#ifdef MEDSPRING_HAVE_FEM
#include "medspring/fem/volumetric.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/volumetric_body.hpp"
#endif
#endif

namespace medspring::cli {

/// Benchmark cases that need the builders (real anatomy), appended by `medspring bench`: only those
/// whose name contains `filter` (empty = all) and whose data file exists; their models are built here.
std::vector<bench::BenchCase> builder_bench_cases(const std::string& filter);

#ifdef MEDSPRING_HAVE_BUILDERS

namespace {

namespace fs = std::filesystem;

OrganSource organ_source(const Args& args) {
  OrganSource src;
  const auto mesh = args.get("mesh"), mask = args.get("mask");
  require(mesh.has_value() != mask.has_value(), "give exactly one of --mesh FILE and --mask FILE");
  if (mesh) src.mesh = *mesh;
  if (mask) src.mask = *mask;
  if (args.get("label")) {
    require(mask.has_value(), "option --label: applies to --mask only");
    const long label = args.integer("label", 0);
    require(label >= std::numeric_limits<std::int32_t>::min() &&
                label <= std::numeric_limits<std::int32_t>::max(),
            "option --label: ", label, " is out of range");
    src.label = static_cast<std::int32_t>(label);
  }
  if (auto u = args.get("unit")) {
    require(mesh.has_value(), "option --unit: applies to --mesh only (a volume's spacing is in its file)");
    src.unit = parse_length_unit(*u);
  }
  if (args.get("close-holes")) {
    require(mesh.has_value(), "option --close-holes: applies to --mesh only");
    const long n = args.integer("close-holes", 0);
    require(n >= 3 && n <= 100000, "option --close-holes: must be between 3 and 100000 edges (got ", n, ")");
    src.close_holes = static_cast<Index>(n);
  }
  return src;
}

Index count_option(const Args& args, const std::string& name, long fallback, long min) {
  const long n = args.integer(name, fallback);
  require(n >= min && n <= 1000000, "option --", name, ": must be between ", min, " and 1000000 (got ", n,
          ")");
  return static_cast<Index>(n);
}

/// --path mst|dijkstra: the voxel path of the skeleton (§3.4; mst = D-7, the default).
PathMethod path_option(const Args& args) {
  const std::string m = args.get_or("path", "mst");
  if (m == "mst") return PathMethod::MaximumSpanningTree;
  if (m == "dijkstra") return PathMethod::PenalizedDijkstra;
  throw InvalidInput(cat("option --path: '", m, "' is not mst or dijkstra"));
}

fs::path out_option(const Args& args) {
  const auto out = args.get("out");
  require(out.has_value() && !out->empty(), "option --out DIR is required");
  return *out;
}

nlohmann::json kidney_json(const KidneySummary& s) {
  return {{"input", s.input},
          {"input_kind", s.input_kind},
          {"organ",
           {{"vertices", s.input_vertices},
            {"faces", s.input_faces},
            {"volume_mm3", s.organ_volume_mm3},
            {"diagonal_mm", s.organ_diagonal_mm}}},
          {"nodes", s.nodes},
          {"edges", s.edges},
          {"faces", s.faces},
          {"atoms", s.atoms},
          {"valence_histogram", s.valence_histogram},
          {"valence6_fraction", s.valence6_fraction},
          {"hausdorff_mm", s.hausdorff_mm},
          {"mean_distance_mm", s.mean_distance_mm},
          {"atoms_outside_organ", s.atoms_outside_organ},
          {"atoms_outside_mask", s.atoms_outside_mask},
          {"atoms_outside_model", s.atoms_outside_model},
          {"skeleton_length_mm", s.skeleton_length_mm},
          {"atom_spacing_min_mm", s.atom_spacing_min_mm},
          {"atom_spacing_max_mm", s.atom_spacing_max_mm},
          {"radius_min_mm", s.min_radius_mm},
          {"radius_max_mm", s.max_radius_mm},
          {"voxel_size_mm", s.voxel_size_mm},
          {"object_voxels", s.object_voxels},
          {"surface_springs", s.surface_springs},
          {"centerline_springs", s.centerline_springs},
          {"spokes", s.spokes},
          {"spokes_per_atom_min", s.min_spokes_per_atom},
          {"spokes_per_atom_max", s.max_spokes_per_atom},
          {"surface_nodes_without_spoke", s.surface_nodes_without_spoke},
          {"dt_safe_ms", s.dt_safe_ms},
          {"build_seconds", s.seconds},
          {"surface_seconds", s.seconds_surface},
          {"skeleton_seconds", s.seconds_skeleton},
          {"notes", s.notes},
          {"warnings", s.warnings}};
}

nlohmann::json centerline_json(const CenterlineSummary& s) {
  return {{"input", s.input},
          {"input_kind", s.input_kind},
          {"atoms", s.atoms},
          {"length_mm", s.length_mm},
          {"atom_spacing_min_mm", s.atom_spacing_min_mm},
          {"atom_spacing_max_mm", s.atom_spacing_max_mm},
          {"radius_min_mm", s.min_radius_mm},
          {"radius_max_mm", s.max_radius_mm},
          {"radius_mean_mm", s.mean_radius_mm},
          {"ends", {s.ends[0], s.ends[1]}},
          {"open_end_voxels", s.open_end_sizes},
          {"components", s.components},
          {"object_voxels", s.object_voxels},
          {"voxel_size_mm", s.voxel_size_mm},
          {"atoms_outside_mask", s.atoms_outside_mask},
          {"max_distance_outside_mm", s.max_distance_outside_mm},
          {"max_radius_deviation_mm", s.max_radius_deviation_mm},
          {"build_seconds", s.seconds},
          {"notes", s.notes},
          {"warnings", s.warnings}};
}

/// Writes the files and summary.json atomically, then prints the summary.
template <class WriteFiles>
int finish(const Args& args, const fs::path& out, nlohmann::json summary, const std::string& text,
           const std::vector<std::string>& warnings, WriteFiles&& write_files) {
  for (const auto& w : warnings) std::cerr << "medspring build: warning: " << w << "\n";
  for (const StaleTempFolder& gone : remove_stale_temp_folders(out))
    std::cerr << "medspring: removed " << gone.path.string() << ", left by an interrupted run (process "
              << gone.pid << " is gone)\n";
  write_output_folder(out, args.flag("force"), [&](const fs::path& dir) {
    write_files(dir);
    std::ofstream f(dir / "summary.json");
    f << summary.dump(2) << "\n";
    if (!f) throw IoError(cat((dir / "summary.json").string(), ": cannot write"));
  });
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(out)) files.push_back(e.path().filename().string());
  std::sort(files.begin(), files.end());
  if (args.flag("json")) {
    summary["out"] = fs::absolute(out).string();
    summary["files"] = files;
    std::cout << summary.dump(2) << "\n";
  } else {
    std::cout << text << "wrote " << out.string() << ":";
    for (const auto& f : files) std::cout << " " << f;
    std::cout << "\n";
  }
  return 0;
}

int build_kidney(const Args& args) {
  args.require_known(
      {"json", "force", "mesh", "mask", "label", "unit", "close-holes", "nodes", "atoms", "path", "out"});
  KidneyBuildSettings st;
  st.source = organ_source(args);
  st.nodes = count_option(args, "nodes", 458, 4);
  st.atoms = count_option(args, "atoms", 42, 2);
  st.skeleton.path_method = path_option(args);
  const fs::path out = out_option(args);
  check_output_folder(out, args.flag("force"));
  const KidneyBuild k = build_kidney_model(st);
  return finish(args, out, {{"kidney", kidney_json(k.summary)}}, k.summary.text(), k.summary.warnings,
                [&](const fs::path& dir) { write_kidney_files(dir, k); });
}

int build_centerline_cmd(const Args& args) {
  args.require_known({"json", "force", "mesh", "mask", "label", "unit", "atoms", "path", "out"});
  CenterlineBuildSettings st;
  st.source = organ_source(args);
  st.atoms = count_option(args, "atoms", 40, 2);
  st.skeleton.path_method = path_option(args);
  const fs::path out = out_option(args);
  check_output_folder(out, args.flag("force"));
  const CenterlineBuild c = build_centerline(st);
  return finish(args, out, {{"centerline", centerline_json(c.summary)}}, c.summary.text(), c.summary.warnings,
                [&](const fs::path& dir) { write_centerline_files(dir, c); });
}

nlohmann::json vessel_json(const VesselSummary& s) {
  nlohmann::json j = {{"input", s.input},
                      {"input_kind", s.input_kind},
                      {"atoms", s.atoms},
                      {"branches", s.branches},
                      {"junctions", s.junctions},
                      {"surface_nodes", s.surface_nodes},
                      {"faces", s.faces},
                      {"spokes_per_atom", s.spokes},
                      {"length_mm", s.length_mm},
                      {"radius_min_mm", s.radius_min_mm},
                      {"radius_max_mm", s.radius_max_mm},
                      {"rest_error_mm", s.rest_error_mm},
                      {"kb_min_n_per_mm", s.kb_min},
                      {"kb_max_n_per_mm", s.kb_max},
                      {"max_rho_kappa_rest", s.max_rho_kappa},
                      {"dt_safe_ms", s.dt_safe_ms},
                      {"spokes_without_hit", s.spokes_without_hit},
                      {"build_seconds", s.seconds},
                      {"notes", s.notes},
                      {"warnings", s.warnings}};
  if (s.input_kind == "centerline") {
    j["input_branches"] = s.input_branches;
    j["branch"] = s.branch;
  }
  if (s.blended)
    j["watertight_surface"] = {{"path_tubes", s.path_tubes},
                               {"closed_manifold", s.surface_closed},
                               {"components", s.surface_components},
                               {"self_intersections", s.self_intersections},
                               {"volume_mm3", s.surface_volume_mm3}};
  if (s.has_distance) {
    j["hausdorff_mm"] = s.hausdorff_mm;
    j["mean_distance_mm"] = s.mean_distance_mm;
    j["to_input_max_mm"] = s.to_input_max_mm;
    j["to_input_mean_mm"] = s.to_input_mean_mm;
  }
  if (s.away.measured) {
    const AwayFromEnds& a = s.away;
    j["away_from_cut_ends"] = {{"hausdorff_mm", a.hausdorff_mm},
                               {"mean_distance_mm", a.mean_mm},
                               {"samples", a.samples},
                               {"samples_over_2mm", a.samples_over_2mm},
                               {"nodes", a.nodes},
                               {"nodes_over_2mm", a.nodes_over_2mm},
                               {"nodes_max_mm", a.node_max_mm},
                               {"worst_branch", a.worst_branch},
                               {"worst_atom", a.worst_atom},
                               {"worst_from_cut_mm", a.worst_from_cut_mm},
                               {"worst_point_mm", {a.worst_point.x(), a.worst_point.y(), a.worst_point.z()}},
                               {"worst_direction", a.worst_direction}};
  }
  return j;
}

/// medspring build vessel --centerline F --unit U [--branch N] | --mesh F --unit U | --segmentation F
/// [--label L]  --out DIR [--atoms N] [--spokes M] [--k-b K | --wall-e E] [--json] [--force]
/// (a tree: --branches all [--blend [--blend-spacing MM]] for one watertight surface)
int build_vessel_cmd(const Args& args) {
  args.require_known({"json", "force", "centerline", "branch", "branches", "mesh", "segmentation", "mask",
                      "label", "unit", "atoms", "spokes", "k-b", "wall-e", "out", "blend", "blend-spacing",
                      "no-blend"});
  VesselBuildSettings st;
  const auto line = args.get("centerline"), mesh = args.get("mesh");
  auto seg = args.get("segmentation");
  if (!seg) seg = args.get("mask");
  const int sources = line.has_value() + mesh.has_value() + seg.has_value();
  require(sources == 1, "give exactly one of --centerline FILE, --mesh FILE and --segmentation FILE");
  if (line) {
    st.centerline = *line;
    const auto u = args.get("unit");
    require(u.has_value(), "option --unit: required with --centerline (mm, cm or m: the file does not say)");
    st.centerline_unit = parse_length_unit(*u);
    if (args.get("branch")) st.branch = count_option(args, "branch", 0, 0);
    require(!args.get("label"), "option --label: applies to --segmentation only");
  } else {
    require(!args.get("branch"), "option --branch: applies to --centerline only");
    if (mesh) {
      st.source.mesh = *mesh;
      require(!args.get("label"), "option --label: applies to --segmentation only");
      if (auto u = args.get("unit")) st.source.unit = parse_length_unit(*u);
    } else {
      st.source.mask = *seg;
      require(!args.get("unit"),
              "option --unit: applies to --centerline and --mesh (a volume's spacing is in its "
              "file)");
      if (args.get("label")) {
        const long label = args.integer("label", 0);
        require(label >= std::numeric_limits<std::int32_t>::min() &&
                    label <= std::numeric_limits<std::int32_t>::max(),
                "option --label: ", label, " is out of range");
        st.source.label = static_cast<std::int32_t>(label);
      }
    }
  }
  if (const auto b = args.get("branches")) {  // a tree: every polyline, or the skeleton's every endpoint
    require(*b == "all", "option --branches: '", *b, "' is not 'all' (one branch: --branch N)");
    require(!args.get("branch"), "give at most one of --branch and --branches");
    st.all_branches = true;
  }
  if (args.flag("no-blend")) {  // a tree from a mesh or a mask: the open tubes instead of its default
    require(!args.flag("blend") && !args.get("blend-spacing"), "give at most one of --blend and --no-blend");
    require(st.all_branches && (!st.source.mask.empty() || !st.source.mesh.empty()),
            "option --no-blend: applies to a tree from --mesh or --segmentation (--branches all); a "
            "centerline tree has the tubes by default");
    st.no_blend = true;
  }
  if (args.flag("blend") || args.get("blend-spacing")) {  // the watertight junction surface (a tree)
    require(st.all_branches, "option --blend: applies to a tree (--branches all)");
    st.blend = true;
    if (args.get("blend-spacing")) {
      st.blend_spacing = args.number("blend-spacing", 0.0);
      require(st.blend_spacing > 0 && std::isfinite(st.blend_spacing),
              "option --blend-spacing: must be > 0 mm");
    }
  }
  st.smrm.atoms = count_option(args, "atoms", 40, 3);
  st.smrm.spokes = count_option(args, "spokes", 30, 3);
  require(!(args.get("k-b") && args.get("wall-e")), "give at most one of --k-b and --wall-e");
  if (args.get("k-b")) {
    st.smrm.bending = BendingMode::Constant;
    st.smrm.chain.kb = args.number("k-b", 0.0);
    require(st.smrm.chain.kb >= 0 && std::isfinite(st.smrm.chain.kb), "option --k-b: must be >= 0 N/mm");
  }
  if (args.get("wall-e")) {
    st.smrm.wall.E = args.number("wall-e", st.smrm.wall.E);
    require(st.smrm.wall.E > 0 && std::isfinite(st.smrm.wall.E), "option --wall-e: must be > 0 MPa");
  }
  const fs::path out = out_option(args);
  check_output_folder(out, args.flag("force"));
  const VesselBuild v = build_vessel(st);
  return finish(args, out, {{"vessel", vessel_json(v.summary)}}, v.summary.text(), v.summary.warnings,
                [&](const fs::path& dir) { write_vessel_files(dir, v); });
}

#ifdef MEDSPRING_HAVE_FEM
// The volumetric organ: the balloon surface of --surface-nodes nodes (as `build kidney`), TetGen inside to
// about --nodes nodes in all (docs/volumetric.md), springs and volume terms from --E-kPa / --nu. Writes
// volumetric.msm (kind volumetric: the tetrahedra, the material; no supports, so the surface's return
// springs are on), surface.vtp and summary.json.
int build_volumetric_cmd(const Args& args) {
  args.require_known({"json", "force", "mesh", "mask", "label", "unit", "close-holes", "nodes",
                      "surface-nodes", "interior-sizing", "E-kPa", "nu", "out", "thin-tet",
                      "thin-tet-q-max"});
  KidneyBuildSettings st;
  st.source = organ_source(args);
  st.nodes = count_option(args, "surface-nodes", 458, 4);
  const Index nodes = count_option(args, "nodes", 2000, 10);
  require(nodes >= st.nodes, "option --nodes: ", nodes, " is below the --surface-nodes ", st.nodes);
  VolumetricSettings vs;
  vs.E_kPa = args.number("E-kPa", vs.E_kPa);
  vs.nu = args.number("nu", vs.nu);
  require(std::isfinite(vs.E_kPa) && vs.E_kPa > 0, "option --E-kPa: must be > 0 (got ", vs.E_kPa, ")");
  require(std::isfinite(vs.nu) && vs.nu > -1 && vs.nu < 0.5, "option --nu: must be in (-1, 0.5) (got ", vs.nu,
          ")");
  const fem::MeshSizing sizing = fem::parse_mesh_sizing(args.get_or("interior-sizing", "volume"));
  read_thin_tet_options(args, vs, "build volumetric");  // opt-in thin-tetrahedron terms
  const fs::path out = out_option(args);
  check_output_folder(out, args.flag("force"));
  const auto t0 = std::chrono::steady_clock::now();
  const KidneyBuild k = build_kidney_model(st);
  const SurfaceMesh surface{k.model->rest_surface(), k.model->faces()};
  const VolumetricMesh mesh = fem::volumetric_mesh(surface, {.target_nodes = nodes, .sizing = sizing});
  const auto body = std::make_shared<VolumetricBody>(mesh, vs, "volumetric organ");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const VolumetricStats& vst = body->stats();
  nlohmann::json summary = {{"input", k.summary.input},
                            {"input_kind", k.summary.input_kind},
                            {"nodes", vst.nodes},
                            {"target_nodes", nodes},
                            {"interior_sizing", to_string(sizing)},
                            {"surface_nodes", vst.surface_nodes},
                            {"interior_nodes", vst.interior_nodes},
                            {"tetrahedra", vst.tetrahedra},
                            {"springs", vst.springs},
                            {"volume_mm3", vst.volume_mm3},
                            {"min_tet_volume_mm3", vst.min_tet_volume},
                            {"E_kPa", vs.E_kPa},
                            {"nu", vs.nu},
                            {"thin_tet", to_string(vs.thin_tet)},
                            {"thin_tet_q_max", vs.thin_tet_q_max},
                            {"thin_tets", vst.thin_tets},
                            {"thin_spring_factor", vst.thin_spring_factor},
                            {"build_seconds", seconds}};
  const std::string text = cat("volumetric organ from ", k.summary.input, ": ", vst.nodes, " nodes (",
                               vst.surface_nodes, " on the surface, target ", nodes, "), ", vst.tetrahedra,
                               " tetrahedra, ", vst.springs, " springs, volume ", vst.volume_mm3,
                               " mm^3; E = ", vs.E_kPa, " kPa, nu = ", vs.nu, "; built in ", seconds, " s\n");
  return finish(args, out, {{"volumetric", summary}}, text, k.summary.warnings, [&](const fs::path& dir) {
    save_model_package(dir / "volumetric.msm",
                       package_of(*body, "Volumetric organ",
                                  cat("volumetric spring organ, ", vst.nodes, " nodes, ", vst.tetrahedra,
                                      " tetrahedra, from ", k.summary.input)));
    write_vtp(dir / "surface.vtp", surface);
  });
}
#endif

struct BuildKind {
  const char* name;
  int (*run)(const Args&);
};

const std::vector<BuildKind>& build_kinds() {
  static const std::vector<BuildKind> kinds = {
      {"kidney", build_kidney},
      {"centerline", build_centerline_cmd},
      {"vessel", build_vessel_cmd},
#ifdef MEDSPRING_HAVE_FEM
      {"volumetric", build_volumetric_cmd},
#endif
  };
  return kinds;
}

}  // namespace

int cmd_build(const Args& args) {
  std::string names;
  for (const auto& k : build_kinds()) names += names.empty() ? k.name : cat(", ", k.name);
  require(args.positional().size() == 1, "build: expected one kind (", names,
          "), see medspring build --help");
  for (const auto& k : build_kinds())
    if (args.positional()[0] == k.name) return k.run(args);
  throw InvalidInput(cat("build: unknown kind '", args.positional()[0], "' (known: ", names, ")"));
}

std::vector<bench::BenchCase> builder_bench_cases(const std::string& filter) {
  std::vector<bench::BenchCase> cases;
  const std::string name = "kidney_real_hybrid_500_explicit_nonlinear";
  const fs::path file = data_dir() / "kidney_left_hubmap_vhm.obj";
  if ((!filter.empty() && name.find(filter) == std::string::npos) || !fs::exists(file)) return cases;
  // The real kidney (458 + 42), built once here (a few seconds, untimed); one update = Simulation::update
  // (loads -> step -> map -> normals, D-18) with 1 N held on the surface node nearest to the middle atom.
  auto kidney = std::shared_ptr<const HybridKidney>(
      build_kidney_model({.source = {.mesh = file, .unit = LengthUnit::Metre}}).model);
  bench::BenchCase b;
  b.name = name;
  b.group = "kidney";
  b.nodes = kidney->model().num_nodes();
  b.springs = kidney->model().num_springs();
  b.setup = [kidney] {
    auto sim = std::make_shared<Simulation>(kidney);
    const Vec3 mid = kidney->model().x0.row(kidney->atom_dof(kidney->num_atoms() / 2)).transpose();
    const Index c = nearest_node(kidney->rest_surface(), mid);
    const Vec3 dir = (mid - kidney->rest_surface().row(c).transpose()).normalized();
    sim->set_loads({{.node = c, .force = 1.0 * dir, .t_ramp = 20}});
    return std::function<void()>([sim] { sim->update(); });
  };
  cases.push_back(std::move(b));
  return cases;
}

#else  // built without the builders layer (MEDSPRING_WITH_CGAL=OFF)

int cmd_build(const Args&) {
  throw InvalidInput("build: this medspring was built without the builders layer (needs CGAL and VTK)");
}

std::vector<bench::BenchCase> builder_bench_cases(const std::string&) {
  return {};
}

#endif

}  // namespace medspring::cli
