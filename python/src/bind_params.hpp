// Python properties of a declared parameter struct (core/params.hpp): one read-write property per
// declared field, named and documented by its declaration. With settings_helpers (bind_common.hpp) the
// struct also takes every field as a keyword argument: HybridSettings(k_spoke=0.08, spokes_per_atom=6).
#pragma once

#include <deque>
#include <string>
#include <type_traits>

#include "bind_common.hpp"
#include "medspring/core/params.hpp"

namespace medspring::python {

/// The doc string of a field: "spokes between surface nodes and atoms (D-9); N/mm; > 0; default 0.05".
template <class F>
std::string param_doc(const ParamSpec& s, const F& default_value) {
  std::string d(s.doc);
  if (!s.unit.empty()) d += cat("; ", s.unit);
  const std::string r = range_text(s, std::is_integral_v<F>);
  if (!r.empty()) d += "; " + r;
  const std::string v = param_value_text(default_value);
  if (!v.empty()) d += "; default " + v;
  return d + ".";
}

/// Adds a property per declared field of T. Nested structs are returned by reference (settings.duffing.eta
/// = 2 changes settings), node lists by copy (assign a new list); enums accept their names.
template <ParamStruct T, class... Extra>
void def_params(py::class_<T, Extra...>& cls) {
  static std::deque<std::string> docs;  // pybind11 keeps the pointers
  const T proto{};
  py::list specs;
  for_each_field(proto, [&](const ParamSpec& spec, const auto& def) {
    py::dict d;
    d["name"] = std::string(spec.name);
    d["key"] = std::string(spec.json_name());  // the scene file's key
    d["unit"] = std::string(spec.unit);
    d["doc"] = std::string(spec.doc);
    d["lo"] = spec.lo;
    d["hi"] = spec.hi;
    d["lo_open"] = spec.lo_open;
    d["hi_open"] = spec.hi_open;
    d["derived"] = spec.derived;  // set by the program, not a scene key
    specs.append(d);
    using F = std::remove_cvref_t<decltype(def)>;
    const std::string name(spec.name);
    docs.push_back(param_doc(spec, def));
    const char* doc = docs.back().c_str();
    auto get_field = [name](py::object self) {
      T& t = self.cast<T&>();
      py::object out;
      for_each_field(t, [&](const ParamSpec& s, auto& f) {
        using G = std::remove_cvref_t<decltype(f)>;
        if (s.name != name) return;
        if constexpr (ParamStruct<G>)
          out = py::cast(&f, py::return_value_policy::reference_internal, self);
        else
          out = py::cast(f);
      });
      return out;
    };
    auto set_field = [name](T& t, py::handle v) {
      for_each_field(t, [&](const ParamSpec& s, auto& f) {
        using G = std::remove_cvref_t<decltype(f)>;
        if (s.name != name) return;
        if constexpr (std::is_enum_v<G>) {
          f = enum_arg<G>(v, name.c_str());
        } else {
          try {
            f = v.cast<G>();
          } catch (const py::cast_error&) {  // as def_readwrite: a wrong type is a TypeError
            throw py::type_error(
                cat(name, ": expected ", param_type_text<G>(), "; got ", describe_object(v)));
          }
        }
      });
    };
    (void)sizeof(F);
    cls.def_property(name.c_str(), get_field, set_field, doc);
  });
  cls.attr("_params") = py::tuple(specs);  // the declarations, in order (tests, tools)
  cls.def(
      "set_text", [](T& t, const std::string& name, const std::string& text) { set_param(t, name, text); },
      py::arg("name"), py::arg("text"),
      "Sets the field `name` (a nested one as 'duffing.eta') from text, as the command line's --set does: "
      "its type and range checked, InvalidInput naming it otherwise.");
  cls.def(
      "_param_text",
      [](const T& t, const std::string& name) {
        std::string out;
        for_each_field(t, [&](const ParamSpec& s, const auto& f) {
          if (s.name == name) out = param_value_text(f);
        });
        return out;
      },
      py::arg("name"), "A field's value as a scene file writes it (enums by their scene names).");
}

}  // namespace medspring::python
