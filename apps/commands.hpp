// The registry of medspring subcommands. Each command lives in its own cmd_<name>.cpp.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "cli.hpp"

namespace medspring::cli {

struct Command {
  std::string name;
  std::string help;                // full --help text
  std::vector<std::string> flags;  // options that take no value
  int (*run)(const Args&);
};

const std::vector<Command>& commands();
/// Lines for commands registered beyond the built-in three (usage text).
void extra_usage(std::ostream& os);

// Built-in commands
int cmd_bench(const Args& args);
int cmd_info(const Args& args);
int cmd_demo(const Args& args);
int cmd_build(const Args& args);    // cmd_build.cpp
int cmd_run(const Args& args);      // cmd_run.cpp
int cmd_paper(const Args& args);    // cmd_paper.cpp
int cmd_haptics(const Args& args);  // cmd_haptics.cpp
int cmd_export(const Args& args);   // cmd_export.cpp
int cmd_view(const Args& args);     // cmd_view.cpp
int cmd_study(const Args& args);    // cmd_study.cpp
int cmd_accuracy(const Args& args);
int cmd_calibrate(const Args& args);

}  // namespace medspring::cli
