// Small helpers shared by the medspring subcommands: argument parsing and error reporting.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace medspring::cli {

/// Parsed command line of one subcommand: positional arguments, --key value options, --flags.
class Args {
 public:
  /// `flags` lists the options that take no value (e.g. "json", "quiet", "force").
  Args(int argc, char** argv, int first, const std::vector<std::string>& flags);
  const std::vector<std::string>& positional() const { return positional_; }
  bool flag(const std::string& name) const;
  std::optional<std::string> get(const std::string& name) const;
  std::string get_or(const std::string& name, const std::string& fallback) const;
  double number(const std::string& name, double fallback) const;
  long integer(const std::string& name, long fallback) const;
  /// Throws InvalidInput naming the first option not in `known` ("unknown option --foo").
  void require_known(const std::vector<std::string>& known) const;

 private:
  std::vector<std::string> positional_;
  std::map<std::string, std::string> options_;
  std::vector<std::string> flags_set_;
};

/// Runs one subcommand body; turns exceptions into one line on stderr and exit code 1 (2 for usage).
int guarded(const std::string& command, int (*body)(const Args&), const Args& args);

}  // namespace medspring::cli
