#include "cli.hpp"

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <new>

#include "medspring/core/check.hpp"

namespace medspring::cli {

Args::Args(int argc, char** argv, int first, const std::vector<std::string>& flags) {
  for (int i = first; i < argc; ++i) {
    std::string a = argv[i];
    if (a.rfind("--", 0) == 0 && a.size() > 2) {
      std::string key = a.substr(2), value;
      if (const auto eq = key.find('='); eq != std::string::npos) {
        value = key.substr(eq + 1);
        key = key.substr(0, eq);
        options_[key] = value;
      } else if (std::find(flags.begin(), flags.end(), key) != flags.end()) {
        flags_set_.push_back(key);
      } else {
        if (i + 1 >= argc) throw InvalidInput(cat("option --", key, ": needs a value"));
        options_[key] = argv[++i];
      }
    } else {
      positional_.push_back(a);
    }
  }
}

bool Args::flag(const std::string& name) const {
  return std::find(flags_set_.begin(), flags_set_.end(), name) != flags_set_.end();
}

std::optional<std::string> Args::get(const std::string& name) const {
  auto it = options_.find(name);
  if (it == options_.end()) return std::nullopt;
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
    throw InvalidInput(cat("option --", name, ": '", *v, "' is not a number"));
  return x;
}

long Args::integer(const std::string& name, long fallback) const {
  const auto v = get(name);
  if (!v) return fallback;
  char* end = nullptr;
  const long x = std::strtol(v->c_str(), &end, 10);
  if (end == v->c_str() || *end != '\0')
    throw InvalidInput(cat("option --", name, ": '", *v, "' is not an integer"));
  return x;
}

void Args::require_known(const std::vector<std::string>& known) const {
  for (const auto& [k, v] : options_)
    if (std::find(known.begin(), known.end(), k) == known.end())
      throw InvalidInput(cat("unknown option --", k));
  for (const auto& k : flags_set_)
    if (std::find(known.begin(), known.end(), k) == known.end())
      throw InvalidInput(cat("unknown option --", k));
}

int guarded(const std::string& command, int (*body)(const Args&), const Args& args) {
  try {
    return body(args);
  } catch (const std::bad_alloc&) {
    std::cerr << "medspring " << command
              << ": error: out of memory: the model or data is too large for this machine's memory\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "medspring " << command << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace medspring::cli
