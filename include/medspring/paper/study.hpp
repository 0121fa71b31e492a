// The paper's study as a library (ALGORITHMS.md §7): the experiment set, its runs, the timing of Tables I
// and II, and the results as JSON; `medspring paper` and `medspring.paper.run()` (Python) are thin shells
// around run_study(). The report's text is rendered from the results by scripts/paper/report.py (a Jinja2
// template, scripts/paper/report.md.j2): every sentence stating a finding is conditioned on the values.
//
//   CliHost host;                                   // loader, folder runs, progress (see StudyHost)
//   StudyOptions o{.out_dir = staged, .quick = true};
//   const std::string results = run_study(o, host); // JSON text, also written to out_dir/results.json
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "medspring/geometry/polyline.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/scene.hpp"

namespace medspring::paper {

/// One scene run of the study.
struct Experiment {
  std::string file;   // scene file name without .json (and the run's folder name)
  std::string group;  // "kidney" | "vessel" | "tree"
  double force = 0;   // N
  bool nonlinear = true;
  bool local = false;
  bool static_curve = false;
  std::string label;
  bool literal = false;  // the paper's literal constants: Duffing `Absolute` (k' = 0.01 k), D-3
};

/// The experiment set: the kidney at 1.0 and 0.2 N (Fig. 9), the vessel under a light and a strong force
/// with and without local deformation (Fig. 10), linear and nonlinear each; then the paper-literal set
/// (the nonlinear kidney at 1.0 N and the strong nonlinear vessel with Duffing `Absolute`).
const std::vector<Experiment>& experiments();

/// The scene of an experiment: `file`.json of the bundled scenes (folder `scenes_dir`, or its
/// phantom/ sub-folder), with the literal constants applied when asked.
Scene experiment_scene(const Experiment& e, const std::filesystem::path& scenes_dir, bool phantom);

/// What the study needs from its caller: files (VTK readers, CGAL balloon) and runs written to folders.
class StudyHost {
 public:
  virtual ~StudyHost() = default;
  /// The loader of file sources (may be null: phantoms only).
  virtual SceneLoader* loader() = 0;
  /// Runs `built` into `dir` (frames, traces, summary.json); returns the run's summary as JSON text
  /// (the keys of `medspring run`'s summary.json).
  virtual std::string run_to_folder(const BuiltScene& built, const std::filesystem::path& dir,
                                    bool static_curve) = 0;
  /// Writes centerlines as a VTK polyline file (the phantom vessel tree).
  virtual void write_centerlines(const std::filesystem::path& file, const std::vector<Centerline>& lines) = 0;
  /// Progress: a task begins, advances (fraction in [0, 1]), ends with a message.
  virtual void begin(const std::string& /*label*/) {}
  virtual void update(double /*fraction*/) {}
  virtual void end(const std::string& /*message*/) {}
};

struct StudyOptions {
  std::filesystem::path out_dir;      // written into (created); the caller stages and commits it
  bool quick = false;                 // phantoms only, fewer frames and timed updates
  std::filesystem::path scenes_dir;   // the bundled scenes (real ones here, phantoms in phantom/)
  std::filesystem::path data_dir;     // the real anatomy (empty: scene_data_dir())
  bool tree = true;                   // the vessel tree runs (issue 17)
  bool timing = true;                 // Tables I and II
  bool figures = true;                // render key frames and plots (python3 with VTK and matplotlib)
  bool report = true;                 // render report.md from the results (python3 with Jinja2)
  std::filesystem::path scripts_dir;  // scripts/paper (render.py, plots.py, report.py)
  std::string python = "/usr/bin/python3";
  std::string display_prefix;               // e.g. "xvfb-run -a -s '...' " before the rendering command
  std::string accuracy_markdown;            // the accuracy section of the report (apps/accuracy_summary)
  std::string command = "medspring paper";  // how the study was started, for the report
};

/// Runs the study into options.out_dir: scenes/<set>/<name>/ per run, tables.json (Tables I and II, the
/// ordering checks, the per-scene results), results.json (everything the report states), figures/ and
/// report.md when asked. Returns results.json's text. Throws InvalidInput / IoError / Error.
std::string run_study(const StudyOptions& options, StudyHost& host);

/// Renders report.md from results.json with scripts_dir/report.py; throws Error with its last line.
void render_report(const std::filesystem::path& results_json, const std::filesystem::path& report_md,
                   const StudyOptions& options);

/// Runs a shell command with stdout and stderr to `log`; throws Error with the log's last line.
void run_logged(const std::string& what, const std::string& command, const std::filesystem::path& log);

/// A string quoted for /bin/sh.
std::string shell_quote(const std::string& s);

}  // namespace medspring::paper
