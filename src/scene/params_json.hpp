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
    if (it != j.end())
      read_value(s, *it, path + "." + key, f);
    else if (s.is_required)
      fail(path + "." + key, cat("is required", s.unit.empty() ? "" : cat(" (", s.unit, ")")));
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

namespace params_json_detail {

template <class F>
nlohmann::json value_json(const F& f);

// Whether JSON value j has the form of a field of type F (for choosing a variant's alternative).
template <class F>
bool fits(const nlohmann::json& j) {
  if constexpr (std::is_same_v<F, bool>)
    return j.is_boolean();
  else if constexpr (std::is_arithmetic_v<F>)
    return j.is_number();
  else if constexpr (std::is_enum_v<F> || std::is_same_v<F, std::string>)
    return j.is_string();
  else if constexpr (ParamStruct<F>)
    return j.is_object();
  else if constexpr (ParamOptional<F>)
    return j.is_null() || fits<typename F::value_type>(j);
  else
    return j.is_array();
}

template <class F, class... A>
bool read_alternative(const ParamSpec& s, const nlohmann::json& j, const std::string& path, F& f) {
  bool done = false;
  const auto one = [&]<class X>(X*) {
    if (done || !fits<X>(j)) return;
    X x{};
    read_value(s, j, path, x);
    f = std::move(x);
    done = true;
  };
  (one(static_cast<A*>(nullptr)), ...);
  return done;
}

template <class... A>
bool read_variant(const ParamSpec& s, const nlohmann::json& j, const std::string& path,
                  std::variant<A...>& f) {
  return read_alternative<std::variant<A...>, A...>(s, j, path, f);
}

}  // namespace params_json_detail

/// Every declared field of p as a JSON object (nested structs as objects, enums as names, null for an
/// unset optional).
template <ParamStruct T>
nlohmann::json params_to_json(const T& p) {
  nlohmann::json j = nlohmann::json::object();
  for_each_field(p, [&](const ParamSpec& s, const auto& f) {
    if (!s.derived) j[std::string(s.json_name())] = params_json_detail::value_json(f);
  });
  return j;
}

namespace params_json_detail {

template <class F>
nlohmann::json value_json(const F& f) {
  if constexpr (ParamStruct<F>) {
    return params_to_json(f);
  } else if constexpr (ParamList<F>) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& x : f) a.push_back(params_to_json(x));
    return a;
  } else if constexpr (std::is_enum_v<F>) {
    return enum_text(f);
  } else if constexpr (ParamOptional<F>) {
    return f ? value_json(*f) : nlohmann::json(nullptr);
  } else if constexpr (ParamVariant<F>) {
    return std::visit([](const auto& a) { return value_json(a); }, f);
  } else if constexpr (ParamFixedVector<F>) {
    nlohmann::json a = nlohmann::json::array();
    for (Index k = 0; k < f.size(); ++k) a.push_back(f[k]);
    return a;
  } else {
    return nlohmann::json(f);
  }
}

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
  } else if constexpr (ParamList<F>) {
    if (!j.is_array()) fail(path, cat("must be an array of objects (got ", type_name(j), ")"));
    F out(j.size());
    for (std::size_t k = 0; k < j.size(); ++k) params_from_json(j[k], cat(path, "[", k, "]"), out[k]);
    f = std::move(out);
    return;
  } else if constexpr (ParamVariant<F>) {
    if (!read_variant(s, j, path, f))
      fail(path, cat("must be ", param_type_text<F>(), " (got ", type_name(j), ")"));
    return;
  } else if constexpr (ParamOptional<F>) {
    if (j.is_null()) {
      f.reset();
      return;
    }
    typename F::value_type value{};
    read_value(s, j, path, value);
    f = value;
    return;
  } else if constexpr (std::is_same_v<F, std::string>) {
    if (!j.is_string()) fail(path, cat("must be a string (got ", type_name(j), ")"));
    f = j.get<std::string>();
    return;
  } else if constexpr (ParamFixedVector<F>) {
    const auto n = static_cast<std::size_t>(F::RowsAtCompileTime);
    if (!j.is_array() || j.size() != n) fail(path, cat("must be an array of ", n, " numbers"));
    for (std::size_t k = 0; k < n; ++k) f[static_cast<Index>(k)] = number(j[k], cat(path, "[", k, "]"));
    return;
  } else if constexpr (std::is_same_v<F, std::vector<double>>) {
    if (!j.is_array()) fail(path, cat("must be an array of numbers (got ", type_name(j), ")"));
    std::vector<double> out;
    for (std::size_t k = 0; k < j.size(); ++k) {
      const std::string at = cat(path, "[", k, "]");
      const double x = number(j[k], at);
      if (const std::string e = range_error(s, x); !e.empty()) fail(at, e);
      out.push_back(x);
    }
    f = std::move(out);
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
