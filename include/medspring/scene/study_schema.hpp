// The lists and objects of a study file (docs/studies.md), declared once: the base scene, `set`, the
// varied quantities (`vary`) and what each run reports (`outputs`, with every metric's unit), beside the
// scalar settings declared in study_settings.hpp. The declaration gives the study file's checks
// (medspring/study/spec.py walks a study file against study_file_keys() through the binding
// medspring.study_file_schema(): unknown and missing keys, types, lower bounds, allowed words and
// "exactly one kind", each error naming the JSON path), the metric list of the runner and the tables
// of docs/parameters.md ("Study file", "Study metrics"). What needs the base scene (a path the scene
// has, a field time within its duration) is checked in spec.py after the scene is read.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/core/params.hpp"

namespace medspring {

/// What a key of a study file holds.
enum class StudyKeyType : std::uint8_t {
  Any,           // any JSON value
  Text,          // a string
  Number,        // a finite number
  Integer,       // a whole number
  Bool,          // true or false
  Word,          // one of `words`
  Object,        // an object whose keys are declared below it ("vary[].grid.num"), or any keys (`open`)
  List,          // a list; its elements are the key "PATH[]"
  Range,         // [low, high], finite numbers with low < high
  IntegerRange,  // [low, high), whole numbers with low < high
  TextOrObject,  // a file name or an inline object
};
inline std::string_view to_string(StudyKeyType t) {
  switch (t) {
    case StudyKeyType::Any:
      return "any";
    case StudyKeyType::Text:
      return "text";
    case StudyKeyType::Number:
      return "number";
    case StudyKeyType::Integer:
      return "integer";
    case StudyKeyType::Bool:
      return "bool";
    case StudyKeyType::Word:
      return "word";
    case StudyKeyType::Object:
      return "object";
    case StudyKeyType::List:
      return "list";
    case StudyKeyType::Range:
      return "range";
    case StudyKeyType::IntegerRange:
      return "integer range";
    case StudyKeyType::TextOrObject:
      return "text or object";
  }
  return "?";
}

/// One key of a study file.
struct StudyKey {
  std::string path;  ///< "vary[].grid.num": "[]" an element of a list; "" the file itself
  StudyKeyType type = StudyKeyType::Any;
  std::string unit{};  ///< of a number (each bound of a range, each element of a list of numbers)
  std::string def{};   ///< default as shown; "" when required or none
  std::string doc{};   ///< one line
  double lo = -std::numeric_limits<double>::infinity();  ///< lower bound of a number or range
  bool lo_open = false;                                  ///< > lo instead of >= lo
  std::vector<std::string> words{};                      ///< a Word: the accepted words
  bool required = false;
  std::string one_of{};    ///< the keys of one group: exactly one of them in their object
  bool non_empty = false;  ///< a List: at least one element
  bool open = false;       ///< an Object: its keys are not declared (any key)

  /// The bound in words (">= 1", "> 0"), "" when none.
  std::string range() const {
    ParamSpec s{};
    s.lo = lo;
    s.lo_open = lo_open;
    return range_text(s, type == StudyKeyType::Integer || type == StudyKeyType::IntegerRange);
  }
};

/// One summary metric a study run reports (`outputs.metrics`; the scene runner's summary, docs/scenes.md).
struct StudyMetric {
  std::string name;  ///< the column of summary.csv and the array of results.zarr
  std::string unit;
  std::string doc;
  bool by_default = true;  ///< reported when outputs.metrics is not given (the tool metrics: by name only)
};

/// Every metric, in the order of summary.csv.
inline const std::vector<StudyMetric>& study_metrics() {
  static const std::vector<StudyMetric> m = {
      {"contact_peak_mm", "mm", "peak |u| of the first load's node"},
      {"contact_hold_mm", "mm",
       "|u| of the first load's node in the last frame before its release (or at the end)"},
      {"max_disp_peak_mm", "mm", "peak over the frames of the largest surface |u|"},
      {"atom_hold_mm", "mm", "|u| of the first traced atom at the first load's release (hybrid kind)"},
      {"local_hold_mm", "mm", "|U| of the local overlay at the first load's node at its release"},
      {"return_ms", "ms",
       "time after the last release until every surface node stays within 1e-3 mm of rest (inf: never)"},
      {"final_max_disp_mm", "mm", "largest surface |u| at the end"},
      {"warnings", "", "numerical trouble counted by the engine (State::warnings)"},
      {"substeps", "", "substeps over the run"},
      {"median_update_us", "us", "median wall time of one update"},
      {"tool_peak_force_N", "N", "peak magnitude of the first tool's reaction force (0 without tools)",
       false},
      {"tool_final_force_N", "N", "the first tool's reaction force at the end (0 without tools)", false},
      {"tool_peak_penetration_mm", "mm", "peak depth of the deepest surface node inside the first tool",
       false},
  };
  return m;
}

/// Every declared key of a study file other than the settings of study_settings.hpp (samples, seed,
/// batch, max_runs), parents before their children.
inline const std::vector<StudyKey>& study_file_keys() {
  static const std::vector<StudyKey> keys = [] {
    using T = StudyKeyType;
    std::vector<std::string> metric_names;
    std::string by_default;
    for (const StudyMetric& m : study_metrics()) {
      metric_names.push_back(m.name);
      if (!m.by_default) by_default += (by_default.empty() ? "" : ", ") + m.name;
    }
    const std::string kind = "kind";  // the group of vary[]'s kinds: exactly one per entry
    return std::vector<StudyKey>{
        {.path = "name",
         .type = T::Text,
         .def = "the file's stem",
         .doc = "the study's name (reports, study.json)"},
        {.path = "description", .type = T::Text, .def = "\"\"", .doc = "one paragraph for the report"},
        {.path = "scene",
         .type = T::TextOrObject,
         .doc =
             "the base scene: a scene file (relative to the study file) or an inline scene (docs/scenes.md)",
         .required = true},
        {.path = "set",
         .type = T::Object,
         .def = "{}",
         .doc = "{parameter path: value} set on every run, applied together, then the scene is checked",
         .open = true},
        {.path = "vary", .type = T::List, .def = "[]", .doc = "the varied quantities, in file order"},
        {.path = "vary[]",
         .type = T::Object,
         .doc = "one varied quantity: its path and exactly one kind; values in the unit of that parameter"},
        {.path = "vary[].path",
         .type = T::Text,
         .doc = "parameter path into the scene with every default filled in (loads[0].magnitude)",
         .required = true},
        {.path = "vary[].values",
         .type = T::List,
         .doc = "listed kind: every value (any JSON: numbers, names, vectors)",
         .one_of = kind,
         .non_empty = true},
        {.path = "vary[].grid",
         .type = T::Object,
         .doc = "listed kind: num values from `from` to `to`",
         .one_of = kind},
        {.path = "vary[].grid.from", .type = T::Number, .doc = "first value", .required = true},
        {.path = "vary[].grid.to", .type = T::Number, .doc = "last value", .required = true},
        {.path = "vary[].grid.num",
         .type = T::Integer,
         .doc = "number of values (an empty grid has no runs)",
         .lo = 1,
         .required = true},
        {.path = "vary[].grid.log",
         .type = T::Bool,
         .def = "false",
         .doc = "geometric spacing (needs from > 0 and to > 0)"},
        {.path = "vary[].uniform",
         .type = T::Range,
         .doc = "sampled kind: uniform in [low, high)",
         .one_of = kind},
        {.path = "vary[].log_uniform",
         .type = T::Range,
         .doc = "sampled kind: log-uniform in [low, high)",
         .lo = 0,
         .lo_open = true,
         .one_of = kind},
        {.path = "vary[].integers",
         .type = T::IntegerRange,
         .doc = "sampled kind: a whole number in [low, high)",
         .one_of = kind},
        {.path = "vary[].choice",
         .type = T::List,
         .doc = "sampled kind: one of these values, uniformly",
         .one_of = kind,
         .non_empty = true},
        {.path = "vary[].surface_node",
         .type = T::Word,
         .doc = "sampled kind: a node of the base model's surface, uniformly",
         .words = {"random"},
         .one_of = kind},
        {.path = "vary[].surface_point",
         .type = T::Word,
         .doc = "sampled kind: a point uniform by area on the base model's rest surface",
         .words = {"random"},
         .one_of = kind},
        {.path = "vary[].unit_vector",
         .type = T::Word,
         .doc = "sampled kind: a direction uniform on the sphere",
         .words = {"random"},
         .one_of = kind},
        {.path = "outputs", .type = T::Object, .def = "{}", .doc = "what each run reports"},
        {.path = "outputs.metrics",
         .type = T::List,
         .def = "every metric but " + by_default,
         .doc = "summary metrics per run (Study metrics below)",
         .non_empty = true},
        {.path = "outputs.metrics[]", .type = T::Word, .doc = "a metric's name", .words = metric_names},
        {.path = "outputs.fields",
         .type = T::Object,
         .def = "none",
         .doc = "the surface displacement of every run at the given times"},
        {.path = "outputs.fields.times",
         .type = T::List,
         .doc = "the times (within the scene's duration)",
         .required = true,
         .non_empty = true},
        {.path = "outputs.fields.times[]", .type = T::Number, .unit = "ms", .doc = "a time", .lo = 0},
        {.path = "outputs.fields.dtype",
         .type = T::Word,
         .def = "float64",
         .doc = "stored precision",
         .words = {"float64", "float32"}},
    };
  }();
  return keys;
}

}  // namespace medspring
