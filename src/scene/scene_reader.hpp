// Private to the scene layer: reading one scene JSON value at a path, with every error naming the scene
// and the JSON path ("t.json: model.parameters.k_surf: must be > 0 (got -1)"). Obj records the keys it
// was asked for and reports any other key as unknown.
#pragma once

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/scene/scene.hpp"

namespace medspring::scene_detail {

using json = nlohmann::json;
namespace fs = std::filesystem;

struct Ctx {
  std::string origin;
  fs::path base_dir;
};

[[noreturn]] inline void fail(const Ctx& c, const std::string& path, const std::string& message) {
  throw InvalidInput(cat(c.origin, ": ", path, ": ", message));
}

inline std::string type_name(const json& j) {
  if (j.is_number()) return "a number";
  if (j.is_string()) return "a string";
  if (j.is_boolean()) return "a boolean";
  if (j.is_array()) return "an array";
  if (j.is_object()) return "an object";
  return "null";
}

inline std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

// Readers for one JSON value at a path.
inline double as_number(const Ctx& c, const json& j, const std::string& path) {
  if (!j.is_number()) fail(c, path, cat("must be a number (got ", type_name(j), ")"));
  const double x = j.get<double>();
  if (!std::isfinite(x)) fail(c, path, cat("must be finite (got ", x, ")"));
  return x;
}

inline Index as_index(const Ctx& c, const json& j, const std::string& path) {
  const double x = as_number(c, j, path);
  if (x != std::floor(x) || std::abs(x) > 2e9) fail(c, path, cat("must be an integer (got ", j.dump(), ")"));
  return static_cast<Index>(x);
}

inline bool as_bool(const Ctx& c, const json& j, const std::string& path) {
  if (!j.is_boolean()) fail(c, path, cat("must be true or false (got ", type_name(j), ")"));
  return j.get<bool>();
}

inline std::string as_string(const Ctx& c, const json& j, const std::string& path) {
  if (!j.is_string()) fail(c, path, cat("must be a string (got ", type_name(j), ")"));
  return j.get<std::string>();
}

inline Vec3 as_vec3(const Ctx& c, const json& j, const std::string& path) {
  if (!j.is_array() || j.size() != 3) fail(c, path, "must be an array of 3 numbers");
  return {as_number(c, j[0], path + "[0]"), as_number(c, j[1], path + "[1]"),
          as_number(c, j[2], path + "[2]")};
}

// Runs a reader of declared parameters (params_json.hpp), whose errors name the JSON path, and rethrows
// them with the scene's name in front.
template <class F>
void with_origin(const Ctx& c, F&& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    throw InvalidInput(cat(c.origin, ": ", e.what()));
  }
}

// Runs a parse function of the engine (throwing InvalidInput) and rethrows with the JSON path.
template <class F>
auto with_path(const Ctx& c, const std::string& path, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InvalidInput& e) {
    fail(c, path, e.what());
  }
}

/// One JSON object at a path: keys are read through get(), which records them as known; finish()
/// reports every key that was not read as unknown.
class Obj {
 public:
  Obj(const Ctx& c, const json& j, std::string path) : c_(c), j_(j), path_(std::move(path)) {
    if (!j.is_object())
      fail(c_, path_.empty() ? "(root)" : path_, cat("must be an object (got ", type_name(j), ")"));
  }
  const Ctx& ctx() const { return c_; }
  std::string at(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const json* get(const std::string& key) {
    known_.push_back(key);
    const auto it = j_.find(key);
    return it == j_.end() ? nullptr : &*it;
  }
  bool has(const std::string& key) const { return j_.contains(key); }
  double number(const std::string& key, double fallback) {
    const json* v = get(key);
    return v ? as_number(c_, *v, at(key)) : fallback;
  }
  double positive(const std::string& key, double fallback) {
    const double x = number(key, fallback);
    if (!(x > 0)) fail(c_, at(key), cat("must be > 0 (got ", x, ")"));
    return x;
  }
  double nonnegative(const std::string& key, double fallback) {
    const double x = number(key, fallback);
    if (!(x >= 0)) fail(c_, at(key), cat("must be >= 0 (got ", x, ")"));
    return x;
  }
  Index index(const std::string& key, Index fallback, Index min_value = 0) {
    const json* v = get(key);
    if (!v) return fallback;
    const Index i = as_index(c_, *v, at(key));
    if (i < min_value) fail(c_, at(key), cat("must be >= ", min_value, " (got ", i, ")"));
    return i;
  }
  bool boolean(const std::string& key, bool fallback) {
    const json* v = get(key);
    return v ? as_bool(c_, *v, at(key)) : fallback;
  }
  std::string string(const std::string& key, const std::string& fallback) {
    const json* v = get(key);
    return v ? as_string(c_, *v, at(key)) : fallback;
  }
  /// Throws for the first key that no get() asked for.
  void finish() const {
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      bool ok = false;
      for (const auto& k : known_) ok = ok || k == it.key();
      if (!ok) fail(c_, at(it.key()), cat("unknown key (expected one of: ", join(known_), ")"));
    }
  }

 private:
  const Ctx& c_;
  const json& j_;
  std::string path_;
  std::vector<std::string> known_;
};

// "${MEDSPRING_DATA}/x" -> data folder; relative -> against the scene folder; the file must exist.
inline fs::path resolve_file(const Ctx& c, const json& j, const std::string& path) {
  std::string s = as_string(c, j, path);
  if (s.empty()) fail(c, path, "must not be empty");
  const std::string var = "${MEDSPRING_DATA}";
  for (auto pos = s.find(var); pos != std::string::npos; pos = s.find(var))
    s.replace(pos, var.size(), scene_data_dir().string());
  if (const auto pos = s.find("${"); pos != std::string::npos)
    fail(c, path, cat("unknown variable in '", s, "' (only ${MEDSPRING_DATA} is expanded)"));
  fs::path p(s);
  if (p.is_relative()) p = c.base_dir / p;
  p = p.lexically_normal();
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) {
    if (s.find(scene_data_dir().string()) != std::string::npos)
      fail(c, path, cat("file not found: ", p.string(), " (set MEDSPRING_DATA to the data folder)"));
    fail(c, path, cat("file not found: ", p.string()));
  }
  return p;
}

}  // namespace medspring::scene_detail
