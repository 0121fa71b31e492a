// `medspring paper --out DIR`: the paper's study (src/paper, include/medspring/paper/study.hpp) run into a
// staged folder that replaces DIR only when complete. This file is the shell: options, the accuracy
// summary, the checks of the figure tool chain, and the study's host (VTK readers and .vtp writers of
// scene_support, progress on stderr).
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "accuracy_summary.hpp"
#include "commands.hpp"
#include "medspring/core/check.hpp"
#include "medspring/io/centerline_io.hpp"
#include "medspring/paper/study.hpp"
#include "scene_support.hpp"

#ifndef MEDSPRING_SOURCE_SCENES_DIR
#define MEDSPRING_SOURCE_SCENES_DIR "scenes"
#endif
#ifndef MEDSPRING_SOURCE_PAPER_SCRIPTS_DIR
#define MEDSPRING_SOURCE_PAPER_SCRIPTS_DIR "scripts/paper"
#endif

namespace medspring::cli {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::optional<fs::path> which(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (!path) return std::nullopt;
  std::stringstream ss(path);
  std::string dir;
  while (std::getline(ss, dir, ':')) {
    const fs::path p = fs::path(dir.empty() ? "." : dir) / program;
    if (access(p.c_str(), X_OK) == 0) return p;
  }
  return std::nullopt;
}

/// The study's host in the CLI: the VTK readers and CGAL balloon of FileLoader, runs written by
/// run_scene_to_folder, progress on stderr.
class CliHost final : public paper::StudyHost {
 public:
  explicit CliHost(Progress& progress) : progress_(progress) {}
  SceneLoader* loader() override { return &loader_; }
  std::string run_to_folder(const BuiltScene& built, const fs::path& dir, bool static_curve) override {
    SceneRunOptions o;
    o.static_curve = static_curve;
    return run_scene_to_folder(built, dir, progress_, o).dump();
  }
  void write_centerlines(const fs::path& file, const std::vector<Centerline>& lines) override {
    medspring::write_centerlines(file, lines);
  }
  void begin(const std::string& label) override { progress_.begin(label); }
  void update(double fraction) override { progress_.update(fraction); }
  void end(const std::string& message) override { progress_.end(message); }

 private:
  Progress& progress_;
  FileLoader loader_;
};

/// Accuracy against the FEM: read from a previous `medspring accuracy` run (--accuracy FILE, else the
/// latest one kept beside the FEM cache), never run here (it takes minutes); a bad file is refused now.
std::string accuracy_section(const std::optional<std::string>& given) {
  const fs::path file = given && !given->empty() ? fs::path(*given) : latest_accuracy_path();
  std::error_code ec;
  if (fs::is_regular_file(file, ec)) {
    try {
      return accuracy_summary_markdown(json::parse(std::ifstream(file)), cat("`", file.string(), "`"));
    } catch (const json::exception& e) {
      if (given)
        throw InvalidInput(cat("--accuracy: ", file.string(), ": not an accuracy.json (", e.what(), ")"));
      return cat("## Accuracy against the FEM reference\n\nThe latest `medspring accuracy` run (",
                 file.string(), ") could not be read (", e.what(), ").\n\n");
    }
  }
  if (given) throw InvalidInput(cat("--accuracy: ", file.string(), ": no such file"));
  return cat("## Accuracy against the FEM reference\n\nNo `medspring accuracy` run was found (",
             file.string(),
             "); run `medspring accuracy --out DIR` (CalculiX, ~15 min) and the next report "
             "summarises it here.\n\n");
}

}  // namespace

int cmd_paper(const Args& args) {
  args.require_known({"out", "force", "quick", "quiet", "json", "scenes", "accuracy"});
  if (!args.positional().empty())
    throw InvalidInput(cat("unexpected argument '", args.positional()[0], "' (see medspring paper --help)"));
  const auto out_arg = args.get("out");
  if (!out_arg || out_arg->empty()) throw InvalidInput("--out DIR is required (see medspring paper --help)");
  const bool force = args.flag("force"), quick = args.flag("quick"), as_json = args.flag("json");
  Progress progress(args.flag("quiet") || as_json);
  check_output_folder(*out_arg, force);

  paper::StudyOptions o;
  o.quick = quick;
  o.command = quick ? "medspring paper --quick" : "medspring paper";
  o.accuracy_markdown = accuracy_section(args.get("accuracy"));
  // Resources, data and the figure tool chain, checked before anything runs.
  o.scenes_dir =
      find_folder(args.get("scenes"), MEDSPRING_SOURCE_SCENES_DIR, "scenes", "bundled scenes", "phantom");
  o.scripts_dir =
      find_folder(std::nullopt, MEDSPRING_SOURCE_PAPER_SCRIPTS_DIR, "scripts", "figure scripts", "report.py");
  const char* py_env = std::getenv("MEDSPRING_PYTHON");
  o.python = py_env && *py_env ? py_env : "/usr/bin/python3";
  if (const auto xvfb = which("xvfb-run"))
    o.display_prefix =
        paper::shell_quote(xvfb->string()) + " -a -s " + paper::shell_quote("-screen 0 1280x960x24") + " ";
  else if (!std::getenv("DISPLAY"))
    throw InvalidInput(
        "rendering the figures needs xvfb-run (Debian: apt-get install xvfb xauth) or a DISPLAY");
  {
    const fs::path log = fs::temp_directory_path() / cat("medspring-paper-check-", getpid(), ".log");
    try {
      paper::run_logged(
          "figures and report: python3 with VTK, matplotlib and Jinja2 (Debian: python3-vtk9 "
          "python3-matplotlib python3-jinja2)",
          paper::shell_quote(o.python) + " -c " + paper::shell_quote("import vtk, matplotlib, jinja2"), log);
    } catch (...) {
      std::error_code ec;
      fs::remove(log, ec);
      throw;
    }
    std::error_code ec;
    fs::remove(log, ec);
  }

  StagedOutput stage(*out_arg, force);
  o.out_dir = stage.dir();
  CliHost host(progress);
  const json results = json::parse(paper::run_study(o, host));
  stage.commit();
  const json& tables = results["tables"];
  if (as_json) {
    json scenes = json::array();
    for (const auto& r : results["runs"])
      if (!r["literal"].get<bool>()) scenes.push_back(r["summary"]);
    const json j = {{"out", stage.target().string()},
                    {"seconds", results["meta"]["seconds"]},
                    {"tables", tables},
                    {"scenes", scenes},
                    {"results", stage.target() / "results.json"}};
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  std::printf("report: %s (%.1f s)\n", (stage.target() / "report.md").string().c_str(),
              results["meta"]["seconds"].get<double>());
  auto line = [&](const char* label, const json& cell) {
    const double ms = cell["measured_median_ms"].get<double>();
    std::printf("  %-34s %8.4f ms  (%.1f us)\n", label, ms, 1000 * ms);
  };
  line("Table I  mass-spring linear", tables["table1"]["mass_spring"]["linear"]);
  line("Table I  mass-spring nonlinear", tables["table1"]["mass_spring"]["nonlinear"]);
  line("Table I  SMRM linear", tables["table1"]["smrm"]["linear"]);
  line("Table I  SMRM nonlinear", tables["table1"]["smrm"]["nonlinear"]);
  line("Table II mass-spring with local", tables["table2"]["mass_spring"]["with_local"]);
  line("Table II SMRM with local", tables["table2"]["smrm"]["with_local"]);
  return 0;
}

}  // namespace medspring::cli
