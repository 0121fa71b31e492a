// JSON read/write of declared parameter structs (core/params.hpp), private to the scene layer.
//   params_from_json(j, "model.parameters", settings);  // every key checked, errors name the path
//   json j = params_to_json(settings);
#pragma once

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "medspring/core/params.hpp"

namespace medspring {

namespace params_json_detail {

inline std::string type_name(const nlohmann::json& j) {
  if (j.is_number()) return "a number";
  if (j.is_string()) return "a string";
  if (j.is_boolean()) return "a boolean";
  if (j.is_array()) return "an array";
  if (j.is_object()) return "an object";
  return "null";
}

[[noreturn]] inline void fail(const std::string& path, const std::string& message) {
  throw InvalidInput(cat(path, ": ", message));
}

inline double number(const nlohmann::json& j, const std::string& path) {
  if (!j.is_number()) fail(path, cat("must be a number (got ", type_name(j), ")"));
  const double x = j.get<double>();
  if (!std::isfinite(x)) fail(path, cat("must be finite (got ", x, ")"));
  return x;
}

inline Index integer(const nlohmann::json& j, const std::string& path) {
  const double x = number(j, path);
  if (x != std::floor(x) || std::abs(x) > 2e9) fail(path, cat("must be an integer (got ", j.dump(), ")"));
  return static_cast<Index>(x);
}

template <class F>
void read_value(const ParamSpec& s, const nlohmann::json& j, const std::string& path, F& f);

}  // namespace params_json_detail

/// Reads the keys of object j (at `path`, for errors) into p: absent keys keep p's values; unknown
/// keys, wrong types and values out of range throw InvalidInput "path.key: ...".
template <ParamStruct T>
void params_from_json(const nlohmann::json& j, const std::string& path, T& p) {
  using namespace params_json_detail;
  if (!j.is_object()) fail(path, cat("must be an object (got ", type_name(j), ")"));
  std::vector<std::string> known;
  for_each_field(p, [&](const ParamSpec& s, auto& f) {
    if (s.derived) return;  // set by the program: an unknown key in a file
    const std::string key(s.json_name());
    known.push_back(key);
    const auto it = j.find(key);
    if (it != j.end()) read_value(s, *it, path + "." + key, f);
  });
  for (auto it = j.begin(); it != j.end(); ++it) {
    bool ok = false;
    for (const std::string& k : known) ok = ok || k == it.key();
    if (!ok) {
      std::string names;
      for (const std::string& k : known) names += (names.empty() ? "" : ", ") + k;
      fail(path + "." + it.key(), cat("unknown key (expected one of: ", names, ")"));
    }
  }
}

/// Every declared field of p as a JSON object (nested structs as objects, enums as names).
template <ParamStruct T>
nlohmann::json params_to_json(const T& p) {
  nlohmann::json j = nlohmann::json::object();
  for_each_field(p, [&](const ParamSpec& s, const auto& f) {
    using F = std::remove_cvref_t<decltype(f)>;
    if (s.derived) return;
    const std::string key(s.json_name());
    if constexpr (ParamStruct<F>)
      j[key] = params_to_json(f);
    else if constexpr (std::is_enum_v<F>)
      j[key] = enum_text(f);
    else
      j[key] = f;
  });
  return j;
}

namespace params_json_detail {

template <class F>
void read_value(const ParamSpec& s, const nlohmann::json& j, const std::string& path, F& f) {
  if constexpr (ParamStruct<F>) {
    params_from_json(j, path, f);
    return;
  } else if constexpr (std::is_same_v<F, bool>) {
    if (!j.is_boolean()) fail(path, cat("must be true or false (got ", type_name(j), ")"));
    f = j.get<bool>();
    return;
  } else if constexpr (std::is_enum_v<F>) {
    if (!j.is_string()) fail(path, cat("must be a string (got ", type_name(j), ")"));
    try {
      f = parse_enum(j.get<std::string>(), static_cast<F*>(nullptr));
    } catch (const InvalidInput& e) {
      fail(path, e.what());
    }
    return;
  } else if constexpr (std::is_same_v<F, std::vector<Index>>) {
    if (!j.is_array()) fail(path, "must be an array of node indices");
    std::vector<Index> out;
    for (std::size_t k = 0; k < j.size(); ++k) {
      const Index i = integer(j[k], cat(path, "[", k, "]"));
      if (i < 0) fail(cat(path, "[", k, "]"), cat("must be >= 0 (got ", i, ")"));
      out.push_back(i);
    }
    f = std::move(out);
    return;
  } else {
    static_assert(std::is_arithmetic_v<F>, "unsupported parameter type");
    F value{};
    if constexpr (std::is_integral_v<F>)
      value = static_cast<F>(integer(j, path));
    else
      value = static_cast<F>(number(j, path));
    const std::string e = range_error(s, value);
    if (!e.empty()) fail(path, e);
    f = value;
  }
}

}  // namespace params_json_detail

}  // namespace medspring
