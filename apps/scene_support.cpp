#include "scene_support.hpp"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "medspring/core/check.hpp"
#include "medspring/io/centerline_io.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/io/temp_folders.hpp"
#include "medspring/io/volume_io.hpp"
#include "medspring/paper/run_summary.hpp"
#ifdef MEDSPRING_HAVE_BUILDERS
#include "medspring/builders/scene_organ_tree.hpp"
#endif
#ifdef MEDSPRING_HAVE_MESHING
#include "medspring/meshing/balloon.hpp"
#include "medspring/meshing/isosurface.hpp"
#ifdef MEDSPRING_HAVE_FEM
#include "medspring/fem/volumetric.hpp"
#endif
#endif

namespace medspring::cli {

namespace fs = std::filesystem;
using nlohmann::json;

// ---------------------------------------------------------------------------------------------------
// FileLoader

namespace {

SceneFileAccess file_access() {
  SceneFileAccess a;
  a.read_mesh = [](const fs::path& file, LengthUnit unit) {
    return medspring::read_mesh(file, {.unit = unit});
  };
  a.read_centerlines = [](const fs::path& file, LengthUnit unit, const std::string& radius_array) {
    return medspring::read_centerlines(file, unit, radius_array);
  };
  a.read_label_volume = [](const fs::path& file) { return medspring::read_label_volume(file); };
#ifdef MEDSPRING_HAVE_MESHING
  a.isosurface = [](const MaskVolume& mask) { return medspring::isosurface(mask); };
  a.balloon = [](const SurfaceMesh& organ, Index nodes) {
    const BalloonResult r = build_balloon_surface(organ, {.target_nodes = nodes});
    return BalloonSurface{r.mesh, r.report.note_lines()};
  };
#ifdef MEDSPRING_HAVE_FEM
  a.tetrahedralize = [](const SurfaceMesh& organ, Index nodes, MeshSizing sizing) {
    return fem::volumetric_mesh(organ, {.target_nodes = nodes, .sizing = sizing});
  };
#endif
#endif
#ifdef MEDSPRING_HAVE_BUILDERS
  a.tree_surface = [](const CenterlineTree& tree, const SmrmTree& plain, double spacing,
                      std::vector<std::string>& notes) {
    TreeSurface r = blended_tree_surface(tree, plain, spacing);
    notes.push_back(cat("union of ", r.path_tubes, " closed path tubes: ", r.mesh.num_vertices(), " nodes, ",
                        r.closed ? "closed and manifold" : "NOT closed", ", ", r.components,
                        " component(s), ", r.self_intersections, " self-intersecting triangle pairs"));
    for (const auto& n : r.notes) notes.push_back(n);
    for (const auto& w : r.warnings) notes.push_back("warning: " + w);
    return std::move(r.mesh);
  };
  a.organ_tree = [](const OrganTreeRequest& r, std::vector<std::string>& notes) {
    return scene_organ_tree(r, notes);  // `medspring build vessel --mesh F | --segmentation F --branches all`
  };
#endif
  return a;
}

}  // namespace

FileLoader::FileLoader() : CachingSceneLoader(file_access()) {}

// ---------------------------------------------------------------------------------------------------
// Progress

Progress::Progress(bool quiet) : quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0) {}

void Progress::begin(const std::string& label) {
  label_ = label;
  start_ = std::chrono::steady_clock::now();
  last_quarter_ = 0;
  drawn_ = false;
}

void Progress::update(double fraction) {
  if (quiet_) return;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (s < 1.0) return;
  fraction = std::clamp(fraction, 0.0, 1.0);
  if (tty_) {
    const int width = 30;
    const int filled = static_cast<int>(std::round(fraction * width));
    std::fprintf(stderr, "\r%-40.40s [%s%s] %3d%% %5.1f s", label_.c_str(), std::string(filled, '#').c_str(),
                 std::string(width - filled, '.').c_str(), static_cast<int>(std::round(100 * fraction)), s);
    std::fflush(stderr);
    drawn_ = true;
  } else {
    const int quarter = static_cast<int>(fraction * 4);
    if (quarter > last_quarter_ && quarter < 4) {
      std::fprintf(stderr, "%s: %d%%\n", label_.c_str(), 25 * quarter);
      last_quarter_ = quarter;
    }
  }
}

void Progress::end(const std::string& message) {
  if (quiet_) return;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (drawn_) std::fprintf(stderr, "\r%-90s\r", "");
  std::fprintf(stderr, "%s: %s (%.1f s)\n", label_.c_str(), message.c_str(), s);
  std::fflush(stderr);
  drawn_ = false;
}

void Progress::note(const std::string& line) {
  if (quiet_) return;
  std::fprintf(stderr, "%s\n", line.c_str());
  std::fflush(stderr);
}

// ---------------------------------------------------------------------------------------------------
// Output folders

void check_output_folder(const fs::path& dir, bool force) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) return;
  if (!fs::is_directory(dir, ec))
    throw InvalidInput(cat("--out ", dir.string(), ": exists and is not a folder"));
  if (!force && !fs::is_empty(dir, ec))
    throw InvalidInput(
        cat("--out ", dir.string(), ": folder exists and is not empty (use --force to replace it)"));
}

namespace {

fs::path normalized_target(const fs::path& p) {
  fs::path a = fs::absolute(p).lexically_normal();
  if (a.filename().empty()) a = a.parent_path();
  return a;
}

}  // namespace

StagedOutput::StagedOutput(fs::path target, bool force) : target_(normalized_target(target)), force_(force) {
  check_output_folder(target_, force_);
  const fs::path parent = target_.parent_path();
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec)
    throw IoError(cat("--out ", target_.string(), ": cannot create ", parent.string(), ": ", ec.message()));
  // Folders left by an interrupted run (its process is gone) are removed, and named on stderr.
  for (const StaleTempFolder& gone : remove_stale_temp_folders(target_))
    std::fprintf(stderr, "medspring: removed %s, left by an interrupted run (process %ld is gone)\n",
                 gone.path.string().c_str(), gone.pid);
  stage_ = temp_folder_for(target_, static_cast<long>(getpid()));
  fs::remove_all(stage_, ec);
  fs::create_directory(stage_, ec);
  if (ec)
    throw IoError(cat("--out ", target_.string(), ": cannot create ", stage_.string(), ": ", ec.message()));
}

StagedOutput::~StagedOutput() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(stage_, ec);
}

void StagedOutput::commit() {
  check_output_folder(target_, force_);
  try {
    move_folder_into_place(stage_, target_, static_cast<long>(getpid()));
  } catch (const IoError& e) {
    throw IoError(cat("--out ", e.what()));
  }
  committed_ = true;
}

// ---------------------------------------------------------------------------------------------------
// One scene run written to a folder

namespace {

void write_text(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
  if (!out) throw IoError(cat(file.string(), ": cannot write"));
}

std::string padded(Index i) {
  std::ostringstream os;
  os << std::setw(5) << std::setfill('0') << i;
  return os.str();
}

std::string safe_name(const std::string& s) {
  std::string out;
  for (char ch : s)
    out += (std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-') ? ch : '_';
  return out.empty() ? "scene" : out;
}

}  // namespace

json describe_built(const BuiltScene& b) {
  return json::parse(paper::describe_built_json(b));
}

json run_scene_to_folder(const BuiltScene& b, const fs::path& dir, Progress& progress,
                         const SceneRunOptions& o) {
  const std::string name = safe_name(b.scene.name);
  fs::create_directories(dir);
  if (b.scene.record.frames) fs::create_directories(dir / "frames");
  const Index S = b.body->num_surface_nodes();
  const Index A = static_cast<Index>(b.atoms_rest.rows());
  SurfaceMesh mesh;
  mesh.F = b.body->faces();
  const MatX3& S0 = b.body->rest_surface();
  MatX3 Ul(S, 3), atoms(A, 3);
  std::vector<std::pair<double, std::string>> series, atom_series;
  json frames = json::array();
  std::vector<std::vector<Index>> chain;
  if (A >= 2) {
    chain.emplace_back();
    for (Index a = 0; a < A; ++a) chain[0].push_back(a);
  }

  RunHooks hooks;
  hooks.on_frame = [&](const Simulation& sim, const RecordedFrame& f) {
    mesh.V = sim.surface();
    const MatX3 U = sim.surface() - S0;
    Ul.setZero();
    const auto& nodes = sim.local_nodes();
    for (std::size_t r = 0; r < nodes.size(); ++r)
      Ul.row(nodes[r]) = sim.local_displacement().row(static_cast<Index>(r));
    const std::string file = cat("frames/", name, "_", padded(f.index), ".vtp");
    write_vtp(dir / file, mesh,
              {{"displacement", U},
               {"displacement_magnitude", U.rowwise().norm()},
               {"local_displacement", Ul},
               {"local_displacement_magnitude", Ul.rowwise().norm()},
               {"Normals", sim.normals()}});
    series.emplace_back(f.time, file);
    json fr = {{"index", f.index}, {"time_ms", f.time}, {"file", file}};
    if (A >= 2) {
      atoms = sim.state().x.middleRows(b.atom_dof_begin, A);
      const MatX3 Ua = atoms - b.atoms_rest;
      const std::string afile = cat("frames/", name, "_atoms_", padded(f.index), ".vtp");
      write_polyline_vtp(dir / afile, atoms, chain,
                         {{"displacement", Ua}, {"displacement_magnitude", Ua.rowwise().norm()}});
      atom_series.emplace_back(f.time, afile);
      fr["atoms_file"] = afile;
    }
    frames.push_back(fr);
  };
  hooks.on_progress = [&](double x) { progress.update(x); };
  hooks.checkpoint_every = o.checkpoint_every;
  hooks.resume = o.resume;
  hooks.stop_at = o.stop_at;
  if (!o.checkpoint.empty())
    hooks.on_checkpoint = [&](const Checkpoint& c) {
      write_file_atomically(o.checkpoint, encode_checkpoint(c), "checkpoint");
    };
  const SceneResult r = run_scene(b, hooks);
  if (!series.empty()) write_pvd(dir / (name + ".pvd"), series);
  if (!atom_series.empty()) write_pvd(dir / (name + "_atoms.pvd"), atom_series);

  // trace.csv: one row per frame
  {
    std::ostringstream os;
    os.precision(9);
    os << "time_ms,force_N,max_disp_mm,local_contact_mm,energy_mJ";
    for (Index n : b.trace_nodes) os << ",node_" << n << "_mm";
    for (Index a : b.trace_atoms) os << ",atom_" << a << "_mm";
    for (std::size_t k = 0; k < r.trace.tools.size(); ++k)  // docs/tools.md
      for (const char* c :
           {"fx_N", "fy_N", "fz_N", "tx_Nmm", "ty_Nmm", "tz_Nmm", "area_mm2", "penetration_mm", "grasp_N"})
        os << ",tool" << k << "_" << c;
    os << "\n";
    const SceneTrace& t = r.trace;
    for (Index q = 0; q < t.size(); ++q) {
      os << t.time[q] << "," << t.force[q] << "," << t.max_disp[q] << "," << t.local_contact[q] << ","
         << t.energy[q];
      for (const auto& v : t.node_disp) os << "," << v[q];
      for (const auto& v : t.atom_disp) os << "," << v[q];
      for (const SceneTrace::ToolTrace& u : t.tools)
        for (const auto* v : {&u.fx, &u.fy, &u.fz, &u.tx, &u.ty, &u.tz, &u.area, &u.penetration, &u.grasp})
          os << "," << (*v)[static_cast<std::size_t>(q)];
      os << "\n";
    }
    write_text(dir / "trace.csv", os.str());
  }
  paper::SummaryExtras x;
  if (o.static_curve && !b.loads.empty()) {
    std::ostringstream os;
    os.precision(9);
    os << "force_N,contact_mm,max_disp_mm\n";
    x.static_curve = static_response(b, o.curve_points);
    for (const StaticPoint& p : x.static_curve)
      os << p.force << "," << p.contact_mm << "," << p.max_mm << "\n";
    write_text(dir / "static_curve.csv", os.str());
  }
  write_text(dir / "scene.json", scene_to_json(b.scene) + "\n");
  x.frames_json = frames.dump();
  if (!series.empty()) x.pvd = name + ".pvd";
  if (!atom_series.empty()) x.atoms_pvd = name + "_atoms.pvd";
  if (!o.checkpoint.empty()) x.checkpoint = o.checkpoint.string();
  if (o.resume) x.resumed_from_ms = o.resume->state.t;
  const json summary = json::parse(paper::run_summary_json(b, r, x));
  write_text(dir / "summary.json", summary.dump(2) + "\n");
  return summary;
}

std::filesystem::path exe_dir() {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path(".") : p.parent_path();
}

std::filesystem::path find_folder(const std::optional<std::string>& given, const char* compiled,
                                  const std::string& share, const std::string& what,
                                  const std::string& probe) {
  std::vector<std::filesystem::path> tries;
  if (given) tries.emplace_back(*given);
  tries.emplace_back(compiled);
  tries.push_back(exe_dir() / ".." / "share" / "medspring" / share);
  for (const auto& t : tries) {
    std::error_code ec;
    if (std::filesystem::exists(t / probe, ec)) return std::filesystem::absolute(t).lexically_normal();
  }
  std::string list;
  for (const auto& t : tries) list += (list.empty() ? "" : ", ") + t.string();
  throw IoError(cat("cannot find the ", what, " (looked for ", probe, " in ", list, ")"));
}

}  // namespace medspring::cli
