// The study runner's command line, declared once: the switches of `medspring study` and of
// `python3 -m medspring.study` (docs/studies.md). The C++ command (apps/cmd_study.cpp: its CLI11 options,
// --help, usage line, bash completion, docs/cli.md and the arguments it passes on to Python) and the
// Python runner (medspring/study/__main__.py: its argparse parser, through the binding
// medspring.study_runner_cli()) are both built from study_runner_cli() below. Adding a switch is one
// entry here plus its use in __main__.py; python/tests/test_study_cli.py fails when a declared switch
// is not read there, or when either side's parser differs from this list.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/core/params.hpp"
#include "medspring/scene/study_settings.hpp"

namespace medspring {

/// What a switch takes.
enum class SwitchType : std::uint8_t {
  Flag,     // no value
  Integer,  // a whole number >= min
  Text,     // any text (a folder, an address)
  Choice,   // one of the '|'-separated words of `value`
};
inline std::string_view to_string(SwitchType t) {
  switch (t) {
    case SwitchType::Flag:
      return "flag";
    case SwitchType::Integer:
      return "integer";
    case SwitchType::Text:
      return "text";
    case SwitchType::Choice:
      return "choice";
  }
  return "?";
}

/// One switch of the study runner.
struct StudySwitch {
  std::string name;  ///< --name; the Python attribute is the name with '-' as '_' (no-report: no_report)
  SwitchType type = SwitchType::Flag;
  std::string value{};  ///< the value as shown ("DIR", "N"); a Choice: its words, "cpu|cuda"
  std::string unit{};   ///< unit of the value, "" for none
  /// Default as shown. An Integer whose def is a number and a Choice get it as their value; otherwise the
  /// runner gets None and decides (--workers: every core).
  std::string def{};
  std::string help{};   ///< one line
  std::string group{};  ///< switches of one group exclude one another ([--scheduler ADDR | --workers N])
  long min = 0;         ///< an Integer's smallest value
  bool required = false;
  bool hidden = false;  ///< for tests only: not in --help, not an option of `medspring study`
};

/// The runner's whole command line.
struct StudyRunnerCli {
  std::string summary;          ///< one line in `medspring --help`
  std::string about;            ///< the paragraph of --help
  std::string positional;       ///< "STUDY"
  std::string positional_help;  ///< what it is
  std::vector<StudySwitch> switches;
};

/// The declaration (one static list).
inline const StudyRunnerCli& study_runner_cli() {
  static const StudyRunnerCli cli = [] {
    std::string declared;  // the declared study settings that --set overrides, from their declaration
    for (const ParamRow& r : param_rows<StudySettings>()) declared += (declared.empty() ? "" : ", ") + r.name;
    return StudyRunnerCli{
        .summary = "parameter studies on Dask: many runs of a scene -> Zarr, CSV, study.md",
        .about =
            "Runs a parameter study (docs/studies.md) on Dask distributed: a base scene, varied parameters\n"
            "(grids, lists, seeded random or Latin-hypercube samples), every run a task on the engine in a\n"
            "worker process; results stream into DIR/results.zarr and DIR/summary.csv, the report is\n"
            "DIR/study.md.",
        .positional = "STUDY",
        .positional_help = "study file (JSON, docs/studies.md)",
        .switches = {
            {.name = "out",
             .type = SwitchType::Text,
             .value = "DIR",
             .help = "the study's folder: new, empty, or this study's with --resume",
             .required = true},
            {.name = "scheduler",
             .type = SwitchType::Text,
             .value = "ADDR",
             .def = "a local cluster",
             .help = "a running dask-scheduler (tcp://HOST:PORT)",
             .group = "where"},
            {.name = "workers",
             .type = SwitchType::Integer,
             .value = "N",
             .def = "every core",
             .help = "local worker processes (0: in this process, without Dask)",
             .group = "where"},
            {.name = "resume", .help = "complete the study already in DIR (redoes only the missing runs)"},
            {.name = "yes",
             .help = cat("run a study with more runs than its max_runs (default ", StudySettings{}.max_runs,
                         ")")},
            {.name = "quiet", .help = "no progress bar"},
            {.name = "no-report", .help = "do not write study.md"},
            {.name = "scaling",
             .type = SwitchType::Integer,
             .value = "RUNS",
             .unit = "runs",
             .def = "0",
             .help =
                 "also time RUNS runs on 1..N local workers (N = --workers or every core) for the report"},
            {.name = "device",
             .type = SwitchType::Choice,
             .value = "cpu|cuda|cpu-batch|auto",
             .def = "cpu",
             .help =
                 "where the runs step: cuda = each task's runs one batch on the GPU engine (docs/gpu.md; "
                 "in this process unless --workers/--scheduler; an error without a GPU), cpu-batch = the "
                 "same batch path on the CPU, auto = cuda where a GPU is usable, else cpu (said on stderr)"},
            {.name = "set",
             .type = SwitchType::Text,
             .value = "P=V[,P=V]",
             .def = "the study file's",
             .help = cat("override a declared study setting: ", declared, " (docs/parameters.md)")},
            {.name = "max-batches",
             .type = SwitchType::Integer,
             .value = "N",
             .help = "stop after N batches, as if interrupted (tests of --resume)",
             .min = 1,
             .hidden = true},
        }};
  }();
  return cli;
}

}  // namespace medspring
