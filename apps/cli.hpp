// The medspring command line: options declared once per command (apps/commands.cpp), parsed by CLI11;
// --help, the bash completion and docs/cli.md are generated from the same declarations.
#pragma once

#include <map>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "medspring/core/error.hpp"

namespace medspring::cli {

/// One option of a command, declared once. `medspring CMD --help`, the parser, the bash completion and
/// docs/cli.md are built from it (CONTRIBUTING.md, "Add a command-line option").
struct OptionSpec {
  std::string name{};   ///< long name without the dashes: "out" is --out
  std::string value{};  ///< its value as shown ("DIR", "N", "mm|cm|m"); empty: a flag, which takes no value
  std::string unit{};   ///< unit of the value ("mm", "ms", "N", "kPa"); empty: none
  std::string def{};    ///< default as shown in --help ("8080", "the scene's"); empty: none
  std::string help{};   ///< what it does, one line
};

class Args;

/// A command (or a subcommand such as `build kidney`) and its options.
struct CommandSpec {
  std::string name{};
  std::string summary{};     ///< one line in `medspring --help`
  std::string usage{};       ///< the lines after "usage: " in --help
  std::string about{};       ///< what it does, paragraphs of --help
  std::string positional{};  ///< what the positional arguments are ("SCENE", "FILE"); empty: none taken
  std::vector<OptionSpec> options{};
  std::vector<CommandSpec> subcommands{};  ///< `build kidney|centerline|vessel`
  /// The body. Null in a subcommand: the parent's body runs with the subcommand's name as the first
  /// positional argument and the subcommand's options.
  int (*run)(const Args&) = nullptr;
  bool hidden = false;  ///< not listed in `medspring --help` (e.g. `completion`)
};

/// A command-line mistake (unknown option, missing or malformed value): one line, exit status 2.
class UsageError : public InvalidInput {
 public:
  using InvalidInput::InvalidInput;
};

/// The parsed command line of one (sub)command, read by the command's body: positional arguments,
/// --key value options, --flags. Backed by CLI11's parse results (an option not declared for the
/// command reads as not given).
class Args {
 public:
  Args(std::string command, std::set<std::string> declared, std::vector<std::string> positional,
       std::map<std::string, std::string> values, std::set<std::string> flags);
  const std::vector<std::string>& positional() const { return positional_; }
  bool flag(const std::string& name) const;
  std::optional<std::string> get(const std::string& name) const;
  std::string get_or(const std::string& name, const std::string& fallback) const;
  /// The option as a number / integer (a malformed value is a UsageError naming the option).
  double number(const std::string& name, double fallback) const;
  long integer(const std::string& name, long fallback) const;
  /// Refuses (UsageError) an option given on the command line that is not in `known` (for commands with
  /// modes, e.g. bench --compare); every name of `known` must be declared in apps/commands.cpp.
  void require_known(const std::vector<std::string>& known) const;
  const std::string& command() const { return command_; }  ///< "run", "build kidney"

 private:
  void check_declared(const std::string& name) const;
  std::string command_;
  std::set<std::string> declared_;
  std::vector<std::string> positional_;
  std::map<std::string, std::string> values_;
  std::set<std::string> flags_;
};

/// Runs one subcommand body; turns exceptions into one line on stderr and exit code 1 (2 for usage).
int guarded(const std::string& command, int (*body)(const Args&), const Args& args);

/// The whole command: parses argv against `specs` with CLI11 and runs the chosen command.
/// 0 success, 1 failure, 2 a usage error (one line naming the option).
int main(const std::vector<CommandSpec>& specs, int argc, char** argv);

// Text generated from the declarations (cli_text.cpp).
void print_usage(const std::vector<CommandSpec>& specs, std::ostream& os);  ///< `medspring --help`
/// `medspring CMD [SUB] --help`: usage, what it does, every option with its value, unit and default.
void print_help(const CommandSpec& spec, const std::string& path, std::ostream& os);
void print_markdown(const std::vector<CommandSpec>& specs, std::ostream& os);  ///< docs/cli.md
void print_bash_completion(const std::vector<CommandSpec>& specs, std::ostream& os);
void print_json(const std::vector<CommandSpec>& specs, std::ostream& os);  ///< the declarations

}  // namespace medspring::cli
