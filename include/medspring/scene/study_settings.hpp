// The settings of a parameter study file (docs/studies.md), declared once (core/params.hpp): how many
// samples per grid point and how they are drawn, the seed, the runs per Dask task and the run limit.
// The declaration gives the study file's keys and their checks (study_settings_from_json, with the JSON
// path in every error), the file's text (study_settings_json), the Python class StudySettings (properties
// and keyword arguments; medspring.study reads its study files through it), `medspring study --set
// NAME=VALUE` and the table in docs/parameters.md. The varied quantities (`vary`), the base scene, `set`
// and `outputs` are lists and objects, read by medspring/study/spec.py.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "medspring/core/check.hpp"
#include "medspring/core/params.hpp"

namespace medspring {

/// How the sampled quantities of a study (uniform, choice, surface_node, ...) are drawn.
enum class SampleMethod : std::uint8_t {
  Random,          // every value from PCG64 seeded with SeedSequence([seed, run])
  LatinHypercube,  // stratified per grid point and dimension, jittered as Random
};
inline std::string_view to_string(SampleMethod m) {
  return m == SampleMethod::Random ? "random" : "latin_hypercube";
}
inline SampleMethod parse_enum(const std::string& text, SampleMethod*) {
  if (text == "random") return SampleMethod::Random;
  if (text == "latin_hypercube") return SampleMethod::LatinHypercube;
  throw InvalidInput(cat("expected 'random' or 'latin_hypercube' (got '", text, "')"));
}

/// The study file's "samples" object.
struct StudySamples {
  Index count = 1;  // samples per grid point (only with sampled quantities)
  SampleMethod method = SampleMethod::Random;
};
template <ParamOf<StudySamples> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"count", "", "samples per grid point of the sampled quantities (uniform, choice, ...)"}
        .at_least(1),
    s.count);
  v(ParamSpec{"method", "", "random or latin_hypercube (stratified per grid point)"}, s.method);
}

/// The declared settings of a study file (its top-level keys "samples", "seed", "batch", "max_runs").
struct StudySettings {
  StudySamples samples{};
  Index seed = 0;           // of every sampled value: run i draws from SeedSequence([seed, i])
  Index batch = 16;         // runs per Dask task
  Index max_runs = 100000;  // more runs than this need --yes
};
template <ParamOf<StudySettings> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"samples", "", "how the sampled quantities are drawn"}, s.samples);
  v(ParamSpec{"seed", "", "seed of every sampled value (run i: SeedSequence([seed, i]))"}.nonnegative(),
    s.seed);
  v(ParamSpec{"batch", "runs", "runs per Dask task (one task runs them in one worker)"}.at_least(1).at_most(
        100000),
    s.batch);
  v(ParamSpec{"max_runs", "runs", "a study with more runs is refused unless --yes is given"}.nonnegative(),
    s.max_runs);
}

/// One FEM reference case of a calibration (docs/accuracy.md, docs/studies.md): the tissue and the contact
/// load that `medspring calibrate` fits the springs to, the keyword defaults of medspring.fem_reference and
/// the per-case keys of medspring.study.fem (one Dask task per case; support_direction, a vector, is the
/// one case key not declared here). The engine's own checks (fem::validate_material) still apply.
struct FemCaseSettings {
  double E_kPa = 10.0;         // Young's modulus of the tissue
  double nu = 0.45;            // Poisson ratio
  double radius = 8.0;         // contact disk radius, mm
  double support_depth = 5.0;  // points within this depth of the extreme point along the support are fixed
  Index level = 1;             // tetrahedral refinement: 1 the surface as given, 2, 3 subdivided
};
template <ParamOf<FemCaseSettings> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"E_kPa", "kPa", "Young's modulus of the tissue (compressible Neo-Hookean)"}.positive(),
    s.E_kPa);
  v(ParamSpec{"nu", "", "Poisson ratio of the tissue (the engine also needs > -1)"}.at_most(0.5, true), s.nu);
  v(ParamSpec{"radius", "mm", "contact disk radius a"}.positive(), s.radius);
  v(ParamSpec{"support_depth", "mm",
              "surface points within this depth of the extreme point along the support "
              "direction are fixed"}
        .nonnegative(),
    s.support_depth);
  v(ParamSpec{"level", "", "tetrahedral refinement: 1 the surface as given, 2 and 3 subdivided"}
        .at_least(1)
        .at_most(3),
    s.level);
}

/// Reads the declared keys of a study file's JSON object `json_text` (other keys are left to the
/// caller); errors are InvalidInput "ORIGIN: samples.count: must be ...".
StudySettings study_settings_from_json(const std::string& json_text, const std::string& origin);

/// The declared keys as a JSON object (text), every field written.
std::string study_settings_json(const StudySettings& settings);

}  // namespace medspring
