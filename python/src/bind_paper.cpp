// The paper's study from Python (src/paper, docs/paper.md): medspring.paper.run() calls _paper_run, which
// runs paper::run_study with a host of this module: the scene file loader of bind_scene.cpp and runs that
// write summary.json (no .vtp frames: the rendered figures are `medspring paper`'s).
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "bind_common.hpp"
#include "medspring/paper/run_summary.hpp"
#include "medspring/paper/study.hpp"
#include "medspring/scene/runner.hpp"
#ifdef MEDSPRING_PYTHON_WITH_IO
#include "medspring/io/centerline_io.hpp"
#endif

#ifndef MEDSPRING_PYTHON_SCENES_DIR
#define MEDSPRING_PYTHON_SCENES_DIR "scenes"
#endif
#ifndef MEDSPRING_PYTHON_PAPER_SCRIPTS_DIR
#define MEDSPRING_PYTHON_PAPER_SCRIPTS_DIR "scripts/paper"
#endif

namespace medspring::python {

std::unique_ptr<SceneLoader> make_file_loader();  // bind_scene.cpp
void bind_paper(py::module_& m);

namespace {

namespace fs = std::filesystem;

class PythonHost final : public paper::StudyHost {
 public:
  SceneLoader* loader() override { return loader_.get(); }
  std::string run_to_folder(const BuiltScene& built, const fs::path& dir, bool static_curve) override {
    fs::create_directories(dir);
    const SceneResult r = run_scene(built);
    paper::SummaryExtras x;
    if (static_curve && !built.loads.empty()) x.static_curve = static_response(built);
    const std::string text = paper::run_summary_json(built, r, x);
    std::ofstream out(dir / "summary.json", std::ios::binary);
    out << text << "\n";
    if (!out) throw IoError(cat((dir / "summary.json").string(), ": cannot write"));
    return text;
  }
  void write_centerlines(const fs::path& file, const std::vector<Centerline>& lines) override {
#ifdef MEDSPRING_PYTHON_WITH_IO
    medspring::write_centerlines(file, lines);
#else
    (void)lines;
    throw InvalidInput(cat(file.string(), ": the vessel tree needs the io layer (VTK) in this build"));
#endif
  }

 private:
  std::unique_ptr<SceneLoader> loader_ = make_file_loader();
};

}  // namespace

void bind_paper(py::module_& m) {
  m.attr("paper_scenes_dir") = std::string(MEDSPRING_PYTHON_SCENES_DIR);
  m.attr("paper_scripts_dir") = std::string(MEDSPRING_PYTHON_PAPER_SCRIPTS_DIR);
  m.def(
      "_paper_run",
      [](const fs::path& out, bool quick, const fs::path& scenes, const fs::path& data, bool tree,
         bool timing, bool report, const std::string& python, const fs::path& scripts,
         const std::string& accuracy_markdown) {
        std::error_code ec;
        if (fs::exists(out, ec) && !(fs::is_directory(out, ec) && fs::is_empty(out, ec)))
          throw InvalidInput(cat("out: ", out.string(), " exists and is not an empty folder"));
        paper::StudyOptions o;
        o.out_dir = fs::absolute(out);
        o.quick = quick;
        o.scenes_dir = scenes;
        o.data_dir = data;
        o.tree = tree;
        o.timing = timing;
        o.figures = false;
        o.report = report;
        o.python = python;
        o.scripts_dir = scripts;
        o.accuracy_markdown = accuracy_markdown;
        o.command = quick ? "medspring.paper.run(quick=True)" : "medspring.paper.run()";
        PythonHost host;
        py::gil_scoped_release release;
        return paper::run_study(o, host);
      },
      py::arg("out"), py::arg("quick"), py::arg("scenes"), py::arg("data"), py::arg("tree"),
      py::arg("timing"), py::arg("report"), py::arg("python"), py::arg("scripts"),
      py::arg("accuracy_markdown"), "The paper's study (use medspring.paper.run): results.json's text.");
}

}  // namespace medspring::python
