#include "cli.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <new>
#include <stdexcept>

#include "medspring/core/check.hpp"

namespace medspring::cli {

Args::Args(std::string command, std::set<std::string> declared, std::vector<std::string> positional,
           std::map<std::string, std::string> values, std::set<std::string> flags)
    : command_(std::move(command)),
      declared_(std::move(declared)),
      positional_(std::move(positional)),
      values_(std::move(values)),
      flags_(std::move(flags)) {}

void Args::check_declared(const std::string& name) const {
  if (!declared_.count(name))
    throw std::logic_error(cat("internal: `medspring ", command_, "` reads the option --", name,
                               ", which is not declared for it in apps/commands.cpp (CONTRIBUTING.md, "
                               "\"Add a command-line option\")"));
}

// A name not declared for this command cannot have been given: get/flag say so (shared helpers such as
// build's organ_source read options of several kinds). require_known checks the declarations.
bool Args::flag(const std::string& name) const {
  return flags_.count(name) > 0;
}

std::optional<std::string> Args::get(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::string Args::get_or(const std::string& name, const std::string& fallback) const {
  return get(name).value_or(fallback);
}

double Args::number(const std::string& name, double fallback) const {
  const auto v = get(name);
  if (!v) return fallback;
  char* end = nullptr;
  const double x = std::strtod(v->c_str(), &end);
  if (end == v->c_str() || *end != '\0')
    throw UsageError(cat("option --", name, ": '", *v, "' is not a number"));
  return x;
}

long Args::integer(const std::string& name, long fallback) const {
  const auto v = get(name);
  if (!v) return fallback;
  char* end = nullptr;
  const long x = std::strtol(v->c_str(), &end, 10);
  if (end == v->c_str() || *end != '\0')
    throw UsageError(cat("option --", name, ": '", *v, "' is not an integer"));
  return x;
}

void Args::require_known(const std::vector<std::string>& known) const {
  for (const auto& k : known) check_declared(k);
  const auto refuse = [&](const std::string& k) {
    if (std::find(known.begin(), known.end(), k) == known.end())
      throw UsageError(cat("option --", k, " does not apply here (see medspring ", command_, " --help)"));
  };
  for (const auto& [k, v] : values_) refuse(k);
  for (const auto& k : flags_) refuse(k);
}

int guarded(const std::string& command, int (*body)(const Args&), const Args& args) {
  try {
    return body(args);
  } catch (const std::bad_alloc&) {
    std::cerr << "medspring " << command
              << ": error: out of memory: the model or data is too large for this machine's memory\n";
    return 1;
  } catch (const UsageError& e) {
    std::cerr << "medspring " << command << ": error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "medspring " << command << ": error: " << e.what() << "\n";
    return 1;
  }
}

namespace {

bool is_help(const char* a) {
  return !std::strcmp(a, "--help") || !std::strcmp(a, "-h");
}

const CommandSpec* find_spec(const std::vector<CommandSpec>& specs, const std::string& name) {
  for (const auto& s : specs)
    if (s.name == name) return &s;
  return nullptr;
}

/// The option storage of one CLI11 (sub)app: every declared option, the positional arguments.
struct Declared {
  const CommandSpec* spec = nullptr;
  CLI::App* app = nullptr;
  std::vector<std::pair<const OptionSpec*, CLI::Option*>> options;
  std::vector<std::string> positional;
};

void declare(Declared& d, CLI::App* app, const CommandSpec& spec) {
  d.spec = &spec;
  d.app = app;
  for (const auto& o : spec.options) {
    CLI::Option* opt = o.value.empty() ? app->add_flag("--" + o.name, o.help)
                                       : app->add_option("--" + o.name, o.help)
                                             ->type_name(o.value)
                                             ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    d.options.emplace_back(&o, opt);
  }
  if (!spec.positional.empty()) app->add_option(spec.positional, d.positional, "positional arguments");
}

Args args_of(const Declared& d, const std::string& path, std::vector<std::string> positional) {
  std::set<std::string> declared, flags;
  std::map<std::string, std::string> values;
  for (const auto& [o, opt] : d.options) {
    declared.insert(o->name);
    if (opt->count() == 0) continue;
    if (o->value.empty())
      flags.insert(o->name);
    else
      values[o->name] = opt->results().back();
  }
  positional.insert(positional.end(), d.positional.begin(), d.positional.end());
  return Args(path, std::move(declared), std::move(positional), std::move(values), std::move(flags));
}

/// CLI11's message as one line naming the option.
std::string usage_message(const CLI::ParseError& e) {
  const std::string what = e.what();
  if (dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr) {
    const auto colon = what.find(": ");
    std::string rest = colon == std::string::npos ? what : what.substr(colon + 2);
    std::vector<std::string> extras;
    for (std::size_t p = 0; p < rest.size();) {
      const auto q = std::min(rest.find(' ', p), rest.size());
      if (q > p) extras.push_back(rest.substr(p, q - p));
      p = q + 1;
    }
    for (const auto& x : extras)
      if (x.size() > 1 && x[0] == '-') return cat("unknown option ", x.substr(0, x.find('=')));
    if (!extras.empty()) return cat("unexpected argument '", extras.front(), "'");
  }
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) != nullptr) {
    // "--out: 1 required DIR missing"
    const auto colon = what.find(':');
    if (colon != std::string::npos && what.rfind("--", 0) == 0 && what.find("missing") != std::string::npos) {
      const auto req = what.find("required ");
      std::string value =
          req == std::string::npos ? "" : what.substr(req + 9, what.rfind(" missing") - (req + 9));
      return cat("option ", what.substr(0, colon), " needs a value",
                 value.empty() ? "" : cat(" (", value, ")"));
    }
  }
  return what;
}

}  // namespace

int main(const std::vector<CommandSpec>& specs, int argc, char** argv) {
  if (argc < 2) {
    print_usage(specs, std::cerr);
    return 2;
  }
  const std::string first = argv[1];
  if (is_help(argv[1])) {
    print_usage(specs, std::cout);
    return 0;
  }
  if (first == "help") {  // medspring help [COMMAND [SUB]] | --markdown | --json
    if (argc == 2) {
      print_usage(specs, std::cout);
      return 0;
    }
    const std::string what = argv[2];
    if (what == "--markdown") {
      print_markdown(specs, std::cout);
      return 0;
    }
    if (what == "--json") {
      print_json(specs, std::cout);
      return 0;
    }
    const CommandSpec* s = find_spec(specs, what);
    std::string path = what;
    if (s != nullptr && argc > 3)
      for (const auto& sub : s->subcommands)
        if (sub.name == argv[3]) {
          s = &sub;
          path = cat(what, " ", sub.name);
        }
    if (s == nullptr) {
      std::cerr << "medspring help: error: unknown command '" << what << "' (see medspring --help)\n";
      return 2;
    }
    print_help(*s, path, std::cout);
    return 0;
  }
  const CommandSpec* spec = find_spec(specs, first);
  if (spec == nullptr) {
    std::cerr << "medspring: error: " << (first.rfind("-", 0) == 0 ? "unknown option " : "unknown command ")
              << (first.rfind("-", 0) == 0 ? first : "'" + first + "'") << " (see medspring --help)\n";
    return 2;
  }

  // A command with subcommands (build kidney|centerline|vessel): the kind comes first.
  if (!spec->subcommands.empty()) {
    std::string names;
    for (const auto& s : spec->subcommands) names += (names.empty() ? "" : "|") + s.name;
    if (argc > 2 && is_help(argv[2])) {
      print_help(*spec, spec->name, std::cout);
      return 0;
    }
    if (argc > 2 && argv[2][0] == '-') {  // the hand-written parser took options before the kind
      std::cerr << "medspring " << spec->name << ": error: the kind comes first: write medspring "
                << spec->name << " " << names << " " << argv[2] << " ... (see medspring " << spec->name
                << " --help)\n";
      return 2;
    }
    bool known = false;
    for (const auto& s : spec->subcommands) known = known || (argc > 2 && s.name == argv[2]);
    if (!known) {  // no kind, or an unknown one: the body says which kinds exist
      std::vector<std::string> pos;
      if (argc > 2) pos.emplace_back(argv[2]);
      return guarded(spec->name, spec->run, Args(spec->name, {}, pos, {}, {}));
    }
  }

  CLI::App app(spec->summary, spec->name);
  Declared top;
  declare(top, &app, *spec);
  std::vector<Declared> subs(spec->subcommands.size());
  for (std::size_t i = 0; i < spec->subcommands.size(); ++i)
    declare(subs[i], app.add_subcommand(spec->subcommands[i].name, spec->subcommands[i].summary),
            spec->subcommands[i]);
  const Declared* chosen = &top;
  std::string path = spec->name;
  const auto find_chosen = [&] {
    for (const auto& d : subs)
      if (d.app->parsed()) {
        chosen = &d;
        path = cat(spec->name, " ", d.spec->name);
      }
  };
  try {
    app.parse(argc - 1, argv + 1);
  } catch (const CLI::CallForHelp&) {
    find_chosen();
    print_help(*chosen->spec, path, std::cout);
    return 0;
  } catch (const CLI::ParseError& e) {
    find_chosen();
    std::cerr << "medspring " << path << ": error: " << usage_message(e) << " (see medspring " << path
              << " --help)\n";
    return 2;
  }
  find_chosen();
  int (*run)(const Args&) = chosen->spec->run != nullptr ? chosen->spec->run : spec->run;
  std::vector<std::string> pos;
  if (chosen != &top) pos.push_back(chosen->spec->name);
  return guarded(spec->name, run, args_of(*chosen, path, std::move(pos)));
}

}  // namespace medspring::cli
