// `medspring export`: built models as model packages (models/model_package.hpp) that the engine alone
// rebuilds: the browser page (WebAssembly) loads them, so does any simulator without VTK/CGAL.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/io/centerline_io.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/smrm_tree.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/scene.hpp"
#include "scene_support.hpp"
#ifdef MEDSPRING_HAVE_BUILDERS
#include "medspring/builders/vessel_build.hpp"
#endif

namespace medspring::cli {

namespace {

namespace fs = std::filesystem;

struct Entry {
  std::string file, name, description;
  ModelPackage package;
};

// Builds the model of a scene (file readers, balloon, skeleton) and packages it.
Entry from_scene(const fs::path& scene_file, const std::string& file, const std::string& name,
                 const std::string& description, FileLoader& loader, Progress& progress) {
  const Scene scene = load_scene(scene_file);
  progress.begin(cat("build ", name));
  const BuiltScene built = build_scene(scene, &loader);
  progress.end(cat(built.body->kind(), ", ", built.body->num_surface_nodes(), " surface nodes, ",
                   built.body->model().num_nodes(), " masses"));
  return {file, name, description, package_of(*built.body, name, description)};
}

nlohmann::json describe(const Entry& e, std::size_t bytes) {
  const BodyPtr body = make_body(e.package);
  const TissueParams t = tissue_params(e.package);
  return {
      {"file", e.file},
      {"name", e.name},
      {"kind", e.package.kind},
      {"description", e.description},
      {"surface_nodes", body->num_surface_nodes()},
      {"masses", body->model().num_nodes()},
      {"springs", body->model().num_springs()},
      {"bytes", bytes},
      {"params", {{"k", t.k}, {"eta", t.eta}, {"kr", t.kr}, {"beta", t.beta}, {"nonlinear", t.nonlinear}}}};
}

}  // namespace

int cmd_export(const Args& args) {
  args.require_known({"out", "force", "quiet", "json", "web", "scenes"});
  const auto out = args.get("out");
  if (!out || out->empty()) throw InvalidInput("--out DIR is required (see medspring export --help)");
  const bool web = args.flag("web"), json = args.flag("json"), force = args.flag("force");
  if (web == !args.positional().empty())
    throw InvalidInput("give either --web or one or more SCENE files (see medspring export --help)");
  Progress progress(args.flag("quiet") || json);
  check_output_folder(*out, force);

  FileLoader loader;
  std::vector<Entry> entries;
  std::vector<std::string> notes;
  if (web) {
    const fs::path scenes =
        find_folder(args.get("scenes"), MEDSPRING_SOURCE_SCENES_DIR, "scenes", "bundled scenes", "phantom");
    const fs::path data = scene_data_dir();
    std::error_code ec;
    if (fs::exists(data / "kidney_left_hubmap_vhm.obj", ec) &&
        fs::exists(data / "vmr-0159-aorta-centerline.vtp", ec)) {
      entries.push_back(from_scene(scenes / "kidney_0.2N_nonlinear.json", "kidney.msm", "Real kidney",
                                   "HuBMAP left kidney: hybrid model, 458-node balloon surface + 42 skeleton "
                                   "atoms tied by spokes, nonlinear springs",
                                   loader, progress));
      entries.push_back(from_scene(scenes / "vessel_light_nonlinear.json", "aorta.msm", "Real aorta",
                                   "VMR 0159 aorta (arch and descending aorta): SMRM vessel, 40 atoms x 30 "
                                   "spokes rebuilt from the centerline and its radii",
                                   loader, progress));
      {  // the whole VMR 0159 tree: its 4 polylines merged into branches (docs/vessels.md)
        const std::string name = "Real aorta tree", file = "aorta_tree.msm";
        progress.begin(cat("build ", name));
        const auto tree = std::make_shared<SmrmTree>(merge_centerlines(
            read_centerlines(data / "vmr-0159-aorta-centerline.vtp", LengthUnit::Centimetre)));
        const std::string description =
            cat("VMR 0159 aorta with its branches: SMRM vessel tree, ", tree->num_branches(), " branches, ",
                tree->num_junctions(), " junctions, ", tree->num_atoms(),
                " atoms (shared at the junctions), one 30-spoke tube per branch, wall bending");
        progress.end(cat(tree->kind(), ", ", tree->num_surface_nodes(), " surface nodes, ", tree->num_atoms(),
                         " masses"));
        entries.push_back({file, name, description, package_of(*tree, name, description)});
      }
#ifdef MEDSPRING_HAVE_BUILDERS
      {  // the same tree with one watertight surface (the union of its path tubes, docs/vessels.md)
        const std::string name = "Real aorta tree (watertight)", file = "aorta_tree_blended.msm";
        progress.begin(cat("build ", name));
        TreeSurface ts;
        const auto tree =
            make_blended_tree(merge_centerlines(read_centerlines(data / "vmr-0159-aorta-centerline.vtp",
                                                                 LengthUnit::Centimetre)),
                              SmrmTreeSettings{}, 0.0, &ts);
        const std::string description =
            cat("VMR 0159 aorta with its branches: SMRM vessel tree, ", tree->num_branches(), " branches, ",
                tree->num_atoms(), " atoms, one watertight surface (the union of ", ts.path_tubes,
                " closed path tubes, ", tree->num_surface_nodes(), " nodes), wall bending");
        progress.end(cat(tree->kind(), ", ", tree->num_surface_nodes(), " surface nodes (watertight), ",
                         tree->num_atoms(), " masses"));
        entries.push_back({file, name, description, package_of(*tree, name, description)});
      }
#endif
    } else {
      notes.push_back(
          cat("the real anatomy was not found in ", data.string(), " (set MEDSPRING_DATA): phantoms only"));
    }
    entries.push_back(from_scene(scenes / "phantom" / "kidney_0.2N_nonlinear.json", "kidney_phantom.msm",
                                 "Kidney phantom", "Procedural kidney (§4.1): hybrid, 458 surface + 42 atoms",
                                 loader, progress));
    entries.push_back(from_scene(scenes / "phantom" / "vessel_light_nonlinear.json", "vessel_phantom.msm",
                                 "Vessel phantom", "Straight procedural vessel: SMRM, 40 atoms x 30 spokes",
                                 loader, progress));
    const SurfaceBody tube_body(tube(40, 30, 2.5, 3.0), SurfaceBodyParams{}, "tube", GridLayout{40, 30});
    entries.push_back(
        {"tube.msm", "Mass-spring tube",
         "Plain surface mass-spring tube: 40 rings x 30 nodes, every node simulated",
         package_of(tube_body, "Mass-spring tube",
                    "Plain surface mass-spring tube: 40 rings x 30 nodes, every node simulated")});
  } else {
    for (const std::string& s : args.positional()) {
      const std::string stem = fs::path(s).stem().string();
      entries.push_back(from_scene(s, stem + ".msm", stem,
                                   cat("built from scene ", fs::path(s).filename().string()), loader,
                                   progress));
    }
  }

  StagedOutput stage(*out, force);
  nlohmann::json index = nlohmann::json::array();
  for (const Entry& e : entries) {
    const std::string bytes = encode_model_package(e.package);
    write_file_atomically(stage.dir() / e.file, bytes, "model package");
    // What was written is what a reader rebuilds: decode it again before committing the folder.
    const ModelPackage back = decode_model_package(bytes, e.file);
    if (!check_fingerprint(back, *make_body(back)))
      throw InvalidInput(cat(e.file, ": the package does not rebuild the model it was made from"));
    index.push_back(describe(e, bytes.size()));
  }
  nlohmann::json j = {
      {"format", "MSPRMODL"}, {"version", kModelPackageVersion}, {"models", index}, {"notes", notes}};
  {
    const std::string text = j.dump(2) + "\n";
    write_file_atomically(stage.dir() / "models.json", text, "model list");
  }
  stage.commit();
  if (json) {
    j["out"] = stage.target().string();
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  for (const auto& n : notes) std::printf("note: %s\n", n.c_str());
  for (const auto& m : index)
    std::printf("  %-20s %-7s %5ld surface nodes, %5ld masses, %7ld bytes  %s\n",
                m["file"].get<std::string>().c_str(), m["kind"].get<std::string>().c_str(),
                m["surface_nodes"].get<long>(), m["masses"].get<long>(), m["bytes"].get<long>(),
                m["name"].get<std::string>().c_str());
  std::printf("wrote %s (%zu models + models.json)\n", stage.target().string().c_str(), index.size());
  return 0;
}

}  // namespace medspring::cli
