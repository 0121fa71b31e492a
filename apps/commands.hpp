// The registry of medspring subcommands. Each command lives in its own cmd_<name>.cpp; its options are
// declared once in commands.cpp (CONTRIBUTING.md, "Add a command-line option").
#pragma once

#include <string>
#include <vector>

#include "cli.hpp"

namespace medspring::cli {

/// Every command with its declared options, in the order `medspring --help` lists them.
const std::vector<CommandSpec>& commands();

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
int cmd_completion(const Args& args);  // cmd_completion.cpp

}  // namespace medspring::cli
