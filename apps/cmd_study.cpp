// `medspring study`: parameter studies on Dask distributed (docs/studies.md). The work is done by the
// Python package medspring.study (Dask, Zarr, pandas, tqdm, matplotlib); this command runs it with the
// Python interpreter the package was built for and PYTHONPATH set to the build's (or the install's)
// python folder, passing the arguments on unchanged.
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.hpp"
#include "medspring/core/check.hpp"
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

}  // namespace

int cmd_study(const Args& args) {
  args.require_known(
      {"out", "scheduler", "workers", "resume", "yes", "quiet", "no-report", "scaling", "device", "set"});
  std::vector<std::string> argv = {MEDSPRING_PYTHON_EXECUTABLE, "-m", "medspring.study"};
  for (const auto& p : args.positional()) argv.push_back(p);
  for (const char* key : {"out", "scheduler", "workers", "scaling", "device", "set"})
    if (auto v = args.get(key)) {
      argv.push_back(std::string("--") + key);
      argv.push_back(*v);
    }
  for (const char* flag : {"resume", "yes", "quiet", "no-report"})
    if (args.flag(flag)) argv.push_back(std::string("--") + flag);
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
