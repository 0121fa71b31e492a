// `medspring study`: parameter studies on Dask distributed (docs/studies.md). The work is done by the
// Python package medspring.study (Dask, Zarr, pandas, tqdm, matplotlib); this command runs it with the
// Python interpreter the package was built for and PYTHONPATH set to the build's (or the install's)
// python folder, passing the arguments on unchanged. Its switches are the runner's, declared once in
// scene/study_switches.hpp for both this command and `python3 -m medspring.study`.
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "command_options.hpp"
#include "commands.hpp"
#include "medspring/core/check.hpp"
#include "medspring/scene/study_switches.hpp"
#include "scene_support.hpp"

#ifndef MEDSPRING_PYTHON_BUILD_DIR
#define MEDSPRING_PYTHON_BUILD_DIR ""
#endif
#ifndef MEDSPRING_PYTHON_EXECUTABLE
#define MEDSPRING_PYTHON_EXECUTABLE "/usr/bin/python3"
#endif

namespace medspring::cli {

namespace fs = std::filesystem;

namespace {

// The folder holding the medspring package: $MEDSPRING_PYTHONPATH, the build tree's, else an install's.
fs::path python_dir() {
  std::vector<fs::path> tried;
  if (const char* env = std::getenv("MEDSPRING_PYTHONPATH"); env != nullptr && *env != 0)
    tried.emplace_back(env);
  if (*MEDSPRING_PYTHON_BUILD_DIR != 0) tried.emplace_back(MEDSPRING_PYTHON_BUILD_DIR);
  const fs::path lib = exe_dir().parent_path() / "lib";
  std::error_code ec;
  if (fs::is_directory(lib, ec))
    for (const auto& e : fs::directory_iterator(lib, ec))
      if (e.path().filename().string().rfind("python3", 0) == 0) tried.push_back(e.path() / "site-packages");
  std::string places;
  for (const auto& p : tried) {
    if (fs::is_regular_file(p / "medspring" / "study" / "__main__.py", ec)) return p;
    places += (places.empty() ? "" : ", ") + p.string();
  }
  throw IoError(cat(
      "the Python package medspring.study was not found (looked in: ", places.empty() ? "nowhere" : places,
      "); build the target medspring_python or set MEDSPRING_PYTHONPATH"));
}

// "medspring study STUDY --out DIR [--scheduler ADDR | --workers N] [--resume] ...", wrapped.
std::string study_usage(const StudyRunnerCli& d) {
  std::vector<std::string> parts;
  std::string open_group;
  for (const StudySwitch& s : d.switches) {
    if (s.hidden) continue;
    std::string word = "--" + s.name + (s.type == SwitchType::Flag ? "" : " " + s.value);
    if (!s.group.empty() && s.group == open_group) {
      parts.back().pop_back();  // "]"
      parts.back() += " | " + word + "]";
      continue;
    }
    open_group = s.group;
    parts.push_back(s.required ? word : "[" + word + "]");
  }
  std::string usage = "medspring study " + d.positional, line = usage;
  const std::string indent(22, ' ');
  for (const std::string& p : parts) {
    if (line.size() + 1 + p.size() > 100) {
      usage += "\n" + indent + p;
      line = indent + p;
    } else {
      usage += " " + p;
      line += " " + p;
    }
  }
  return usage;
}

}  // namespace

CommandSpec study_command() {
  const StudyRunnerCli& d = study_runner_cli();
  CommandSpec c{.name = "study",
                .summary = d.summary,
                .usage = study_usage(d),
                .about = d.about +
                         "\nRuns the Python package medspring.study (python3 -m medspring.study "
                         "takes the same arguments).",
                .positional = d.positional,
                .run = cmd_study};
  for (const StudySwitch& s : d.switches)
    if (!s.hidden)
      c.options.push_back({.name = s.name, .value = s.value, .unit = s.unit, .def = s.def, .help = s.help});
  return c;
}

int cmd_study(const Args& args) {
  std::vector<std::string> argv = {MEDSPRING_PYTHON_EXECUTABLE, "-m", "medspring.study"};
  for (const auto& p : args.positional()) argv.push_back(p);
  for (const StudySwitch& s : study_runner_cli().switches) {  // passed on as given; Python checks them
    if (s.hidden) continue;
    if (s.type == SwitchType::Flag) {
      if (args.flag(s.name)) argv.push_back("--" + s.name);
    } else if (auto v = args.get(s.name)) {
      argv.push_back("--" + s.name);
      argv.push_back(*v);
    }
  }
  const fs::path dir = python_dir();
  std::string path = dir.string();
  if (const char* old = std::getenv("PYTHONPATH"); old != nullptr && *old != 0)
    path += std::string(":") + old;
  ::setenv("PYTHONPATH", path.c_str(), 1);
  std::vector<char*> cargv;
  for (auto& a : argv) cargv.push_back(a.data());
  cargv.push_back(nullptr);
  ::execv(cargv[0], cargv.data());
  throw IoError(cat(argv[0], ": cannot run the Python interpreter (", std::strerror(errno), ")"));
}

}  // namespace medspring::cli
