// Parameters declared once (issue 22). A parameter struct declares its fields beside its definition:
//
//   struct HybridSettings { double k_spoke = 0.05; ... };                 // the default lives here
//   template <ParamOf<HybridSettings> S, class V> void for_each_field(S& s, V&& v) {  // S: T or const T
//     v(ParamSpec{"k_spoke", "N/mm", "spokes (D-9)"}.positive(), s.k_spoke);
//     ...
//   }
//
// and everything else derives from that one list: JSON read/write with path-named errors
// (scene/params_json.hpp), validation (validate_params), Python properties and keyword arguments
// (python/src/bind_params.hpp), CLI options (set_param), the tables of docs/parameters.md and
// `medspring info --params` (param_rows, params_markdown). Field types: double, integers, bool,
// enums (with to_string(E) and parse_enum(text, E*) found by argument-dependent lookup),
// std::vector<Index> (node lists), std::vector<double> (lists of numbers), std::optional<double>
// (null = the program's choice), std::string, Vec3 / Vec4 (fixed arrays of numbers), nested parameter
// structs (their fields get a "name." prefix) and std::vector of parameter structs (lists of objects,
// "name[]." in tables, "name[k]." in errors). A field declared .required() must be given in a file.
#pragma once

#include <cmath>
#include <concepts>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "medspring/core/check.hpp"

namespace medspring {

/// Name, unit, valid range and one-line doc of one parameter. The default is the struct's own.
struct ParamSpec {
  std::string_view name;  // JSON key, Python property and keyword, CLI option
  std::string_view unit;  // "N/mm", "ms", ...; "" for dimensionless, flags and enums
  std::string_view doc;   // one line
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;  // (lo, ... instead of [lo, ...
  std::string_view key{};                 // JSON key where it differs from name (older scene files)
  bool derived = false;                   // set by the program (not a scene key, not a CLI option)
  bool is_required = false;               // a file must give it (no default)
  bool unit_in_errors = false;            // range errors say the unit: "must be >= 0 N (got -1)"

  constexpr ParamSpec positive() const { return with_lo(0, true); }
  constexpr ParamSpec nonnegative() const { return with_lo(0, false); }
  constexpr ParamSpec at_least(double v) const { return with_lo(v, false); }
  constexpr ParamSpec greater_than(double v) const { return with_lo(v, true); }
  constexpr ParamSpec at_most(double v, bool open = false) const {
    ParamSpec s = *this;
    s.hi = v;
    s.hi_open = open;
    return s;
  }
  constexpr ParamSpec json_key(std::string_view k) const {
    ParamSpec s = *this;
    s.key = k;
    return s;
  }
  /// A field the program sets from the model (e.g. the contact's dt): not read from or written to scene
  /// files, refused by set_param; still validated, listed and a Python property.
  constexpr ParamSpec set_by_program() const {
    ParamSpec s = *this;
    s.derived = true;
    return s;
  }
  /// A key a file must give (tables say "required"; JSON readers refuse its absence).
  constexpr ParamSpec required() const {
    ParamSpec s = *this;
    s.is_required = true;
    return s;
  }
  constexpr ParamSpec unit_in_messages() const {
    ParamSpec s = *this;
    s.unit_in_errors = true;
    return s;
  }
  constexpr std::string_view json_name() const { return key.empty() ? name : key; }
  constexpr bool has_lo() const { return lo > -std::numeric_limits<double>::infinity(); }
  constexpr bool has_hi() const { return hi < std::numeric_limits<double>::infinity(); }

 private:
  constexpr ParamSpec with_lo(double v, bool open) const {
    ParamSpec s = *this;
    s.lo = v;
    s.lo_open = open;
    return s;
  }
};

/// Constrains a declaration to one struct, const or not:
///   template <ParamOf<HybridSettings> S, class V> void for_each_field(S& s, V&& v) { ... }
template <class S, class T>
concept ParamOf = std::same_as<std::remove_const_t<S>, T>;

namespace params_detail {
struct NoOp {
  template <class T>
  void operator()(const ParamSpec&, T&) const {}
};
}  // namespace params_detail

/// A struct with a for_each_field declaration.
template <class T>
concept ParamStruct = requires(T& t) {
  for_each_field(t, params_detail::NoOp{});
};

namespace params_detail {
template <class T>
struct is_optional : std::false_type {};
template <class T>
struct is_optional<std::optional<T>> : std::true_type {};
template <class T>
struct fixed_vector : std::false_type {};
template <int N>
struct fixed_vector<Eigen::Matrix<double, N, 1>> : std::true_type {};
template <class T>
struct is_variant : std::false_type {};
template <class... A>
struct is_variant<std::variant<A...>> : std::true_type {};
}  // namespace params_detail

/// std::variant of field types: the first alternative whose JSON form (number, string, array, object)
/// matches the value is read ("direction": [0, 0, 1] or "inward_normal").
template <class T>
concept ParamVariant = params_detail::is_variant<T>::value;

/// std::optional<number>: null (absent) = the program's choice.
template <class T>
concept ParamOptional = params_detail::is_optional<T>::value;
template <class T>
concept ParamOptionalNumber = ParamOptional<T> && std::is_arithmetic_v<typename T::value_type>;
/// Vec3, Vec4: an array of a fixed count of numbers.
template <class T>
concept ParamFixedVector = params_detail::fixed_vector<T>::value;
/// std::vector of declared structs: a list of objects.
template <class T>
concept ParamList = requires {
  typename T::value_type;
}
&&std::same_as<T, std::vector<typename T::value_type>>&& ParamStruct<typename T::value_type>;

/// The name of an enum value in scene files, tables and CLI options: param_enum_name(e) where one is
/// declared beside the enum (argument-dependent lookup; for enums whose to_string is a display name),
/// else to_string(e). parse_enum(text, (E*)nullptr) reads it back.
template <class E>
std::string enum_text(E e) {
  if constexpr (requires { param_enum_name(e); })
    return std::string(param_enum_name(e));
  else
    return std::string(to_string(e));
}

template <class T>
concept ParamEnum = std::is_enum_v<T> && requires(T e, const std::string& s) {
  { enum_text(e) } -> std::convertible_to<std::string>;
  { parse_enum(s, static_cast<T*>(nullptr)) } -> std::same_as<T>;
};

/// The range of a spec in words: "> 0", ">= 1", "(0, 1]", "" when unbounded.
inline std::string range_text(const ParamSpec& s, bool integer) {
  const auto num = [](double x) { return cat(x); };
  if (s.has_lo() && s.has_hi()) {
    if (integer && !s.lo_open && !s.hi_open) return cat(num(s.lo), "..", num(s.hi));
    return cat(s.lo_open ? "(" : "[", num(s.lo), ", ", num(s.hi), s.hi_open ? ")" : "]");
  }
  if (s.has_lo()) return cat(s.lo_open ? "> " : ">= ", num(s.lo));
  if (s.has_hi()) return cat(s.hi_open ? "< " : "<= ", num(s.hi));
  return "";
}

/// "" when x is within the spec's range, else the message without the field's name:
/// "must be > 0 (got -1)", "must be in (0, 1] (got 2)", "must be an integer in 1..256 (got 0)".
template <class T>
std::string range_error(const ParamSpec& s, T x) {
  if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
    const double v = static_cast<double>(x);
    const bool ok = std::isfinite(v) && (!s.has_lo() || (s.lo_open ? v > s.lo : v >= s.lo)) &&
                    (!s.has_hi() || (s.hi_open ? v < s.hi : v <= s.hi));
    if (ok) return "";
    constexpr bool integer = std::is_integral_v<T>;
    if (!std::isfinite(v)) return cat("must be finite (got ", x, ")");
    const std::string unit = s.unit_in_errors && !s.unit.empty() ? cat(" ", s.unit) : "";
    if (s.has_lo() && s.has_hi())
      return cat(integer ? "must be an integer in " : "must be in ", range_text(s, integer), unit, " (got ",
                 x, ")");
    return cat("must be ", range_text(s, integer), unit, " (got ", x, ")");
  } else if constexpr (std::is_same_v<T, std::vector<Index>>) {
    for (std::size_t k = 0; k < x.size(); ++k)
      if (x[k] < 0) return cat("[", k, "]: must be >= 0 (got ", x[k], ")");
    return "";
  } else if constexpr (std::is_same_v<T, std::vector<double>>) {
    for (std::size_t k = 0; k < x.size(); ++k)
      if (std::string e = range_error(s, x[k]); !e.empty()) return cat("[", k, "]: ", e);
    return "";
  } else if constexpr (ParamOptional<T>) {
    return x ? range_error(s, *x) : "";
  } else if constexpr (ParamVariant<T>) {
    return std::visit([&](const auto& a) { return range_error(s, a); }, x);
  } else if constexpr (ParamFixedVector<T>) {
    for (Index k = 0; k < x.size(); ++k)
      if (!std::isfinite(x[k])) return cat("[", k, "]: must be finite (got ", x[k], ")");
    return "";
  } else {
    (void)s;
    (void)x;
    return "";
  }
}

/// Throws InvalidInput "prefix.name: must be ..." for the first field out of its range (nested
/// structs included).
template <ParamStruct T>
void validate_params(const T& p, const std::string& prefix) {
  for_each_field(p, [&](const ParamSpec& s, const auto& f) {
    using F = std::remove_cvref_t<decltype(f)>;
    const std::string path = prefix.empty() ? std::string(s.name) : cat(prefix, ".", s.name);
    if constexpr (ParamStruct<F>) {
      validate_params(f, path);
    } else if constexpr (ParamList<F>) {
      for (std::size_t k = 0; k < f.size(); ++k) validate_params(f[k], cat(path, "[", k, "]"));
    } else {
      const std::string e = range_error(s, f);
      if (!e.empty()) throw InvalidInput(cat(path, e[0] == '[' ? "" : ": ", e));
    }
  });
}

/// A field's value as text: 0.05, true, strain, [1, 2].
template <class F>
std::string param_value_text(const F& f) {
  if constexpr (std::is_same_v<F, bool>) {
    return f ? "true" : "false";
  } else if constexpr (std::is_enum_v<F>) {
    return enum_text(f);
  } else if constexpr (std::is_arithmetic_v<F>) {
    return cat(f);
  } else if constexpr (std::is_same_v<F, std::vector<Index>> || std::is_same_v<F, std::vector<double>>) {
    std::string s = "[";
    for (std::size_t k = 0; k < f.size(); ++k) s += (k ? ", " : "") + cat(f[k]);
    return s + "]";
  } else if constexpr (ParamOptional<F>) {
    return f ? param_value_text(*f) : "null";
  } else if constexpr (ParamVariant<F>) {
    return std::visit([](const auto& a) { return param_value_text(a); }, f);
  } else if constexpr (ParamFixedVector<F>) {
    std::string s = "[";
    for (Index k = 0; k < f.size(); ++k) s += (k ? ", " : "") + cat(f[k]);
    return s + "]";
  } else if constexpr (std::is_same_v<F, std::string>) {
    return f.empty() ? "\"\"" : f;
  } else if constexpr (ParamList<F>) {
    return f.empty() ? "[]" : cat("[", f.size(), " objects]");
  } else {
    return "";
  }
}

template <class F>
std::string param_type_text();

namespace params_detail {
template <class... A>
std::string variant_type_text(const std::variant<A...>*) {
  std::string s;
  ((s += (s.empty() ? "" : " or ") + param_type_text<A>()), ...);
  return s;
}
}  // namespace params_detail

/// A field's type in words for tables and errors.
template <class F>
std::string param_type_text() {
  if constexpr (std::is_same_v<F, bool>)
    return "bool";
  else if constexpr (std::is_enum_v<F>)
    return "enum";
  else if constexpr (std::is_integral_v<F>)
    return "integer";
  else if constexpr (std::is_arithmetic_v<F>)
    return "number";
  else if constexpr (std::is_same_v<F, std::vector<Index>>)
    return "node list";
  else if constexpr (std::is_same_v<F, std::vector<double>>)
    return "number list";
  else if constexpr (ParamOptional<F>)
    return cat(param_type_text<typename F::value_type>(), " or null");
  else if constexpr (ParamFixedVector<F>)
    return cat(F::RowsAtCompileTime, " numbers");
  else if constexpr (std::is_same_v<F, std::string>)
    return "text";
  else if constexpr (ParamList<F>)
    return "object list";
  else if constexpr (ParamVariant<F>)
    return params_detail::variant_type_text(static_cast<const F*>(nullptr));
  else
    return "object";
}

/// One row of a parameter table: nested fields flattened as "duffing.eta".
struct ParamRow {
  std::string name, type, unit, default_value, range, doc;
};

template <ParamStruct T>
void collect_param_rows(const T& p, const std::string& prefix, std::vector<ParamRow>& out) {
  for_each_field(p, [&](const ParamSpec& s, const auto& f) {
    using F = std::remove_cvref_t<decltype(f)>;
    const std::string name = prefix + std::string(s.json_name());
    if constexpr (ParamStruct<F>) {
      collect_param_rows(f, name + ".", out);
    } else if constexpr (ParamList<F>) {  // the list, then the keys of each entry ("tools[].radius")
      out.push_back({name + "[]", param_type_text<F>(), "", s.is_required ? "required" : param_value_text(f),
                     "", std::string(s.doc)});
      collect_param_rows(typename F::value_type{}, name + "[].", out);
    } else {
      constexpr bool integer = std::is_integral_v<F> || std::is_same_v<F, std::vector<Index>>;
      out.push_back({name, param_type_text<F>(), std::string(s.unit),
                     s.is_required ? "required" : param_value_text(f), range_text(s, integer),
                     cat(s.doc, s.derived ? " (set by the program from the model; not a scene key)" : "")});
    }
  });
}

/// The rows of T's parameters at their defaults (T{}).
template <ParamStruct T>
std::vector<ParamRow> param_rows(const T& p = T{}) {
  std::vector<ParamRow> out;
  collect_param_rows(p, "", out);
  return out;
}

/// A Markdown table of the rows (docs/parameters.md).
inline std::string params_markdown(const std::vector<ParamRow>& rows) {
  std::string s = "| name | type | unit | default | range | meaning |\n|---|---|---|---|---|---|\n";
  for (const ParamRow& r : rows)
    s += cat("| `", r.name, "` | ", r.type, " | ", r.unit, " | ", r.default_value, " | ", r.range, " | ",
             r.doc, " |\n");
  return s;
}

/// Reads a number (an integer for integral F) from command-line text; throws InvalidInput "name: ...".
template <class F>
void set_param_number(const std::string& name, const std::string& text, F& value) {
  std::size_t used = 0;
  double x = 0;
  try {
    x = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty())
    throw InvalidInput(cat(name, ": must be a number (got '", text, "')"));
  if constexpr (std::is_integral_v<F>) {
    if (x != std::floor(x) || std::abs(x) > 2e9)
      throw InvalidInput(cat(name, ": must be an integer (got '", text, "')"));
  }
  value = static_cast<F>(x);
}

/// Sets the field named `name` ("k_spoke", "duffing.eta"; JSON names) from text, checking its type
/// and range. Throws InvalidInput "name: ..." for an unknown name or a bad value. For CLI options.
template <ParamStruct T>
void set_param(T& p, const std::string& name, const std::string& text) {
  bool found = false;
  std::string names;
  for_each_field(p, [&](const ParamSpec& s, auto& f) {
    using F = std::remove_cvref_t<decltype(f)>;
    const std::string key(s.json_name());
    names += (names.empty() ? "" : ", ") + key;
    if constexpr (ParamStruct<F>) {
      if (!found && name.rfind(key + ".", 0) == 0) {
        set_param(f, name.substr(key.size() + 1), text);
        found = true;
      }
    } else {
      if (found || name != key) return;
      found = true;
      if (s.derived) throw InvalidInput(cat(name, ": is set by the program from the model"));
      F value{};
      if constexpr (std::is_same_v<F, bool>) {
        if (text != "true" && text != "false")
          throw InvalidInput(cat(name, ": must be true or false (got '", text, "')"));
        value = text == "true";
      } else if constexpr (std::is_enum_v<F>) {
        try {
          value = parse_enum(text, static_cast<F*>(nullptr));
        } catch (const InvalidInput& e) {
          throw InvalidInput(cat(name, ": ", e.what()));
        }
      } else if constexpr (ParamOptionalNumber<F>) {
        if (text == "null") {
          value.reset();
        } else {
          typename F::value_type inner{};
          set_param_number(name, text, inner);
          value = inner;
        }
      } else if constexpr (std::is_arithmetic_v<F>) {
        set_param_number(name, text, value);
      } else {
        throw InvalidInput(cat(name, ": cannot be set from the command line (use a scene file)"));
      }
      const std::string e = range_error(s, value);
      if (!e.empty()) throw InvalidInput(cat(name, ": ", e));
      f = value;
    }
  });
  if (!found) throw InvalidInput(cat("unknown parameter '", name, "' (expected one of: ", names, ")"));
}

}  // namespace medspring
