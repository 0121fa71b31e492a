// What `medspring run` and `medspring paper` share: the file loader of scenes (VTK readers, CGAL
// balloon), staged output folders, progress on stderr, and writing one scene run to a folder
// (.vtp frames + .pvd series, traces, summary).
#pragma once

#include <chrono>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "medspring/scene/build.hpp"
#include "medspring/scene/file_loader.hpp"
#include "medspring/scene/runner.hpp"

namespace medspring::cli {

/// The scene loader of the command (scene/file_loader.hpp) on the io layer (VTK readers) and, when
/// built, the meshing layer (CGAL balloon, isosurfaces) and the fem layer (TetGen). Meshes and balloon
/// surfaces are cached per file, unit and node count, so the paper's four kidney scenes remesh once.
class FileLoader final : public CachingSceneLoader {
 public:
  FileLoader();
};

/// Progress on stderr: a bar when stderr is a terminal and the task has run for more than a second,
/// plain "label: 50%" lines every 25 % otherwise (tasks over a second), nothing when quiet.
class Progress {
 public:
  explicit Progress(bool quiet);
  void begin(const std::string& label);
  void update(double fraction);
  /// Ends the task with a line "label: <message> (x.x s)".
  void end(const std::string& message);
  /// A line of its own (not quiet).
  void note(const std::string& line);
  bool quiet() const { return quiet_; }

 private:
  bool quiet_, tty_;
  std::string label_;
  std::chrono::steady_clock::time_point start_;
  int last_quarter_ = 0;
  bool drawn_ = false;
};

/// An output folder written under a temporary name beside it and renamed into place by commit().
/// An existing non-empty folder is refused unless `force`; without commit() (an exception) the
/// temporary folder is removed and an existing folder is left as it was.
class StagedOutput {
 public:
  StagedOutput(std::filesystem::path target, bool force);
  ~StagedOutput();
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;
  /// The folder to write into now.
  const std::filesystem::path& dir() const { return stage_; }
  const std::filesystem::path& target() const { return target_; }
  /// Moves the finished folder to the target (replacing an old one when forced).
  void commit();

 private:
  std::filesystem::path target_, stage_;
  bool force_, committed_ = false;
};

/// Throws InvalidInput unless `dir` is absent, an empty folder, or (with force) any folder.
void check_output_folder(const std::filesystem::path& dir, bool force);

/// Writes one run of a built scene into `dir` (created): frames/<name>_NNNNN.vtp for every recorded
/// frame (point data: displacement, displacement_magnitude, local_displacement,
/// local_displacement_magnitude, Normals), <name>.pvd, trace.csv, static_curve.csv (when asked),
/// scene.json (the scene with every default filled in) and summary.json. Returns the summary.
struct SceneRunOptions {
  bool static_curve = false;  // also the static force-displacement curve of the first load
  int curve_points = 21;
  long checkpoint_every = 0;                                 // updates between checkpoints (0: none)
  std::filesystem::path checkpoint;                          // where they go (replaced atomically each time)
  const Checkpoint* resume = nullptr;                        // continue a run from its checkpoint
  double stop_at = std::numeric_limits<double>::infinity();  // ms: stop early (with a checkpoint)
};
nlohmann::json run_scene_to_folder(const BuiltScene& built, const std::filesystem::path& dir,
                                   Progress& progress, const SceneRunOptions& options = {});

/// The folder of the running executable.
std::filesystem::path exe_dir();

/// A resource folder holding `probe`: `given` (a command-line option), else the compiled-in source
/// folder, else <exe>/../share/medspring/<share>. IoError listing the places tried when none has it.
std::filesystem::path find_folder(const std::optional<std::string>& given, const char* compiled,
                                  const std::string& share, const std::string& what,
                                  const std::string& probe);

/// A JSON description of a built model (kind, counts, notes) for summaries.
nlohmann::json describe_built(const BuiltScene& built);

}  // namespace medspring::cli
