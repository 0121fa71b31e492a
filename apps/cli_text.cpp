// Text generated from the command declarations (apps/commands.cpp): `medspring --help`,
// `medspring COMMAND --help`, docs/cli.md (`medspring help --markdown`), the bash completion
// (`medspring completion bash`) and the declarations as JSON (`medspring help --json`, for checks).
#include <algorithm>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli.hpp"

namespace medspring::cli {

namespace {

constexpr std::size_t kWidth = 100, kColumn = 26;

std::string option_label(const OptionSpec& o) {
  return "--" + o.name + (o.value.empty() ? "" : " " + o.value);
}

/// "[mm, default 8]", "[default 8080]", "[ms]" or "".
std::string unit_default(const OptionSpec& o) {
  std::string s = o.unit;
  if (!o.def.empty()) s += (s.empty() ? "" : ", ") + std::string("default ") + o.def;
  return s.empty() ? "" : "[" + s + "]";
}

/// `text` wrapped at kWidth, every line after the first indented by `indent` spaces.
std::string wrapped(const std::string& text, std::size_t first_used, std::size_t indent) {
  std::string out, line;
  std::size_t used = first_used;
  std::istringstream words(text);
  for (std::string w; words >> w;) {
    if (!line.empty() && used + line.size() + 1 + w.size() > kWidth) {
      out += line + "\n" + std::string(indent, ' ');
      line.clear();
      used = indent;
    }
    line += (line.empty() ? "" : " ") + w;
  }
  return out + line;
}

void option_lines(const std::vector<OptionSpec>& options, std::ostream& os) {
  for (const auto& o : options) {
    std::string label = "  " + option_label(o);
    label += label.size() + 2 <= kColumn ? std::string(kColumn - label.size(), ' ')
                                         : "\n" + std::string(kColumn, ' ');
    const std::string ud = unit_default(o);
    os << label << wrapped(o.help + (ud.empty() ? "" : " " + ud), kColumn, kColumn) << "\n";
  }
  os << "  -h, --help" << std::string(kColumn - 12, ' ') << "this help\n";
}

std::string md_cell(std::string s) {
  for (std::size_t p = 0; (p = s.find('|', p)) != std::string::npos; p += 2) s.replace(p, 1, "\\|");
  return s;
}

std::string shell_words(const std::vector<std::string>& words) {
  std::string s;
  for (const auto& w : words) s += (s.empty() ? "" : " ") + w;
  return s;
}

/// How the value of an option is completed: "dir", "file", "choices", or "" (a number: nothing).
std::string value_kind(const std::string& value) {
  if (value.find("DIR") != std::string::npos) return "dir";
  if (value.find("FILE") != std::string::npos || value.find("SCENE") != std::string::npos) return "file";
  if (value.find('|') != std::string::npos && std::all_of(value.begin(), value.end(), [](char c) {
        return c == '|' || c == '.' || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
      }))
    return "choices";
  return "";
}

void completion_case(const CommandSpec& c, const std::string& path, std::ostream& opts,
                     std::ostream& values) {
  std::vector<std::string> names;
  for (const auto& o : c.options) {
    names.push_back("--" + o.name);
    if (o.value.empty()) continue;
    const std::string kind = value_kind(o.value);
    values << "    \"" << path << " --" << o.name << "\") ";
    if (kind == "dir")
      values << "COMPREPLY=($(compgen -d -- \"$cur\")) ;;\n";
    else if (kind == "file")
      values << "COMPREPLY=($(compgen -f -- \"$cur\")) ;;\n";
    else if (kind == "choices") {
      std::string w = o.value;
      std::replace(w.begin(), w.end(), '|', ' ');
      values << "COMPREPLY=($(compgen -W \"" << w << "\" -- \"$cur\")) ;;\n";
    } else
      values << "COMPREPLY=() ;;\n";
  }
  names.push_back("--help");
  opts << "    \"" << path << "\") opts=\"" << shell_words(names) << "\""
       << (c.positional.empty() ? "; files=0" : "; files=1") << " ;;\n";
}

nlohmann::json spec_json(const CommandSpec& c) {
  nlohmann::json j = {{"name", c.name},
                      {"summary", c.summary},
                      {"positional", c.positional},
                      {"hidden", c.hidden},
                      {"options", nlohmann::json::array()},
                      {"subcommands", nlohmann::json::array()}};
  for (const auto& o : c.options)
    j["options"].push_back(
        {{"name", o.name}, {"value", o.value}, {"unit", o.unit}, {"default", o.def}, {"help", o.help}});
  for (const auto& s : c.subcommands) j["subcommands"].push_back(spec_json(s));
  return j;
}

}  // namespace

void print_usage(const std::vector<CommandSpec>& specs, std::ostream& os) {
  os << "medspring — real-time soft-tissue simulation (nonlinear mass-spring + simplified medial "
        "representation)\n\n"
        "usage: medspring <command> [options]   (medspring <command> --help for details)\n\n"
        "commands:\n";
  for (const auto& c : specs) {
    if (c.hidden) continue;
    std::string name = c.name;
    name += name.size() < 8 ? std::string(8 - name.size(), ' ') : "";
    os << "  " << name << " " << c.summary << "\n";
  }
}

void print_help(const CommandSpec& spec, const std::string& path, std::ostream& os) {
  os << "usage: " << (spec.usage.empty() ? "medspring " + path + " [options]" : spec.usage) << "\n\n";
  if (!spec.about.empty()) os << spec.about << (spec.about.back() == '\n' ? "" : "\n");
  if (!spec.subcommands.empty()) {
    os << "\nkinds (medspring " << path << " KIND --help lists the options of each):\n";
    for (const auto& s : spec.subcommands)
      os << "  " << s.name << std::string(s.name.size() < 12 ? 12 - s.name.size() : 1, ' ') << s.summary
         << "\n";
  }
  os << "\noptions:\n";
  option_lines(spec.options, os);
}

void print_markdown(const std::vector<CommandSpec>& specs, std::ostream& os) {
  os << "# The medspring command line\n\n"
        "<!-- Generated by `medspring help --markdown` from the declarations in apps/commands.cpp; do not "
        "edit.\n     The test cli_declarations fails when this file differs from the generated one. -->\n\n"
        "Every command and its options, as `medspring COMMAND --help` prints them. Options are refused "
        "when\nunknown or when their value is missing (one line naming the option, exit status 2); a "
        "command exits\nwith 0 on success and 1 on failure. Bash completion: "
        "`share/bash-completion/completions/medspring`\n(installed with the package; in a build tree "
        "`source build/apps/medspring.bash`).\n\n"
        "| command | what it does |\n|---|---|\n";
  for (const auto& c : specs)
    if (!c.hidden)
      os << "| [`" << c.name << "`](#medspring-" << c.name << ") | " << md_cell(c.summary) << " |\n";
  const auto section = [&](const CommandSpec& c, const std::string& path) {
    os << "\n## medspring " << path
       << "\n\n```\nusage: " << (c.usage.empty() ? "medspring " + path + " [options]" : c.usage) << "\n";
    if (!c.about.empty()) os << "\n" << c.about << (c.about.back() == '\n' ? "" : "\n");
    os << "```\n";
    if (!c.subcommands.empty()) {
      os << "\nKinds: ";
      for (std::size_t i = 0; i < c.subcommands.size(); ++i)
        os << (i ? ", " : "") << "[`" << c.subcommands[i].name << "`](#medspring-" << c.name << "-"
           << c.subcommands[i].name << ")";
      os << ".\n";
    }
    if (c.options.empty()) return;
    os << "\n| option | value | unit | default | meaning |\n|---|---|---|---|---|\n";
    for (const auto& o : c.options) {
      os << "| `--" << o.name << "` | ";
      if (!o.value.empty()) os << '`' << md_cell(o.value) << '`';
      os << " | " << o.unit << " | " << md_cell(o.def) << " | " << md_cell(o.help) << " |\n";
    }
  };
  for (const auto& c : specs) {
    if (c.hidden) continue;
    section(c, c.name);
    for (const auto& s : c.subcommands) section(s, c.name + " " + s.name);
  }
}

void print_bash_completion(const std::vector<CommandSpec>& specs, std::ostream& os) {
  std::vector<std::string> commands;
  for (const auto& c : specs)
    if (!c.hidden) commands.push_back(c.name);
  std::ostringstream opts, values, subs;
  for (const auto& c : specs) {
    if (c.hidden) continue;
    completion_case(c, c.name, opts, values);
    if (c.subcommands.empty()) continue;
    std::vector<std::string> names;
    for (const auto& s : c.subcommands) {
      names.push_back(s.name);
      completion_case(s, c.name + " " + s.name, opts, values);
    }
    subs << "    " << c.name << ") subs=\"" << shell_words(names) << "\" ;;\n";
  }
  os << "# bash completion for medspring -*- shell-script -*-\n"
        "# Generated by `medspring completion bash` from the declarations in apps/commands.cpp.\n"
        "_medspring() {\n"
        "  local cur=${COMP_WORDS[COMP_CWORD]} prev= path opts= files=1 subs=\n"
        "  ((COMP_CWORD > 0)) && prev=${COMP_WORDS[COMP_CWORD - 1]}\n"
        "  COMPREPLY=()\n"
        "  if ((COMP_CWORD == 1)); then\n"
        "    COMPREPLY=($(compgen -W \""
     << shell_words(commands)
     << " help --help\" -- \"$cur\"))\n"
        "    return 0\n"
        "  fi\n"
        "  path=${COMP_WORDS[1]}\n"
        "  if [[ $path == help ]]; then\n"
        "    ((COMP_CWORD == 2)) && COMPREPLY=($(compgen -W \""
     << shell_words(commands)
     << "\" -- \"$cur\"))\n"
        "    return 0\n"
        "  fi\n"
        "  case $path in\n"
     << subs.str()
     << "  esac\n"
        "  if [[ -n $subs ]]; then\n"
        "    if ((COMP_CWORD == 2)); then\n"
        "      COMPREPLY=($(compgen -W \"$subs --help\" -- \"$cur\"))\n"
        "      return 0\n"
        "    fi\n"
        "    path=\"$path ${COMP_WORDS[2]}\"\n"
        "  fi\n"
        "  case \"$path $prev\" in\n"
     << values.str()
     << "    *) prev= ;;\n"
        "  esac\n"
        "  [[ -n $prev ]] && return 0\n"
        "  case $path in\n"
     << opts.str()
     << "    *) return 0 ;;\n"
        "  esac\n"
        "  if [[ $cur == -* ]]; then\n"
        "    COMPREPLY=($(compgen -W \"$opts\" -- \"$cur\"))\n"
        "  elif ((files)); then\n"
        "    COMPREPLY=($(compgen -f -- \"$cur\"))\n"
        "  fi\n"
        "  return 0\n"
        "}\n"
        "complete -o filenames -o bashdefault -F _medspring medspring\n";
}

void print_json(const std::vector<CommandSpec>& specs, std::ostream& os) {
  nlohmann::json j = {{"commands", nlohmann::json::array()}};
  for (const auto& c : specs) j["commands"].push_back(spec_json(c));
  os << j.dump(1) << "\n";
}

}  // namespace medspring::cli
