// Tables of the declared parameter sets (scene/parameter_docs.hpp). A new set: one entry below.
#include "medspring/scene/parameter_docs.hpp"

#include <algorithm>

#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/physics/spring_law.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/scene/scene_tools.hpp"
#include "medspring/scene/study_schema.hpp"
#include "medspring/scene/study_settings.hpp"
#include "medspring/sim/simulation.hpp"
#include "medspring/tools/contact.hpp"

namespace medspring {

namespace {

// The declared keys of a study file's lists and objects as table rows (scene/study_schema.hpp).
std::vector<ParamRow> study_key_rows() {
  std::vector<ParamRow> rows;
  for (const StudyKey& k : study_file_keys()) {
    std::string range = k.range();
    if (k.type == StudyKeyType::Word)
      range = k.words.size() > 3 ? "a metric of the next table" : [&] {
        std::string w;
        for (const auto& x : k.words) w += (w.empty() ? "" : ", ") + x;
        return w;
      }();
    if (k.type == StudyKeyType::Range || k.type == StudyKeyType::IntegerRange)
      range = cat("low < high", range.empty() ? "" : cat("; each ", range));
    if (k.non_empty) range = "non-empty";
    if (!k.one_of.empty()) range += cat(range.empty() ? "" : "; ", "one ", k.one_of, " per entry");
    rows.push_back(
        {k.path, std::string(to_string(k.type)), k.unit, k.required ? "required" : k.def, range, k.doc});
  }
  return rows;
}

std::vector<ParamRow> study_metric_rows() {
  std::vector<ParamRow> rows;
  for (const StudyMetric& m : study_metrics())
    rows.push_back({m.name, "number", m.unit, m.by_default ? "reported" : "by name", "", m.doc});
  return rows;
}

}  // namespace

std::vector<ParamSet> parameter_sets() {
  return {
      {"Hybrid kidney", "HybridSettings", "`model.parameters` (kind `hybrid`)",
       "include/medspring/models/hybrid_kidney.hpp", param_rows<HybridSettings>()},
      {"Duffing spring law", "DuffingSettings", "`duffing` inside `model.parameters` (every kind)",
       "include/medspring/physics/spring_law.hpp", param_rows<DuffingSettings>()},
      {"Surface model", "SurfaceBodyParams", "`model.parameters` (kind `surface`)",
       "include/medspring/physics/model.hpp", param_rows<SurfaceBodyParams>()},
      {"Volumetric model", "VolumetricSettings", "`model.parameters` (kind `volumetric`)",
       "include/medspring/models/volumetric_body.hpp", param_rows<VolumetricSettings>()},
      {"SMRM vessel", "SmrmSettings", "`model.parameters` (kind `smrm`)",
       "include/medspring/models/smrm_vessel.hpp", param_rows<SmrmSettings>()},
      {"Step settings", "StepSettings", "`integrator`", "include/medspring/physics/integrators.hpp",
       param_rows<StepSettings>()},
      {"Local deformation", "LocalOptions", "`local`", "include/medspring/sim/simulation.hpp",
       param_rows<LocalOptions>()},
      {"Loads", "LoadEntry",
       "each entry of `loads`: exactly one of `node`, `point`, or `ring` + `spoke`; `atom` only with "
       "`towards_atom`",
       "include/medspring/scene/scene.hpp", param_rows<LoadEntry>()},
      {"Recording", "SceneRecord", "`record`", "include/medspring/scene/scene.hpp",
       param_rows<SceneRecord>()},
      {"Tools", "ToolEntry",
       "each entry of `tools` ([tools.md](tools.md)): exactly one of `path` (`path[]` is each keyframe) or "
       "`path_file`",
       "include/medspring/scene/scene_tools.hpp", param_rows<ToolEntry>()},
      {"Tool contact", "ContactSettings", "`contact` (with `tools`)", "include/medspring/tools/contact.hpp",
       param_rows<ContactSettings>()},
      {"Parameter study", "StudySettings",
       "the top-level keys of a study file ([studies.md](studies.md)); `medspring study STUDY --set "
       "NAME=VALUE`",
       "include/medspring/scene/study_settings.hpp", param_rows<StudySettings>()},
      {"Study file", "study_file_keys()",
       "the lists and objects of a study file ([studies.md](studies.md)): `vary[]` is each entry of the "
       "list `vary`, `vary[].grid.num` the key `num` of its object `grid`",
       "include/medspring/scene/study_schema.hpp", study_key_rows()},
      {"Study metrics", "study_metrics()",
       "`outputs.metrics` of a study file; the columns of summary.csv ([studies.md](studies.md))",
       "include/medspring/scene/study_schema.hpp", study_metric_rows()},
      {"FEM calibration case", "FemCaseSettings",
       "`medspring calibrate --E-kPa --nu --radius`; the keyword arguments of `medspring.fem_reference` "
       "and the keys of a case of `medspring.study.fem` ([studies.md](studies.md))",
       "include/medspring/scene/study_settings.hpp", param_rows<FemCaseSettings>()},
  };
}

std::string parameter_tables_markdown() {
  std::string s =
      "# Parameters\n\n"
      "<!-- Generated by `medspring info --params`; do not edit. The test scene_params_tests\n"
      "     (CommittedDocsTableIsTheGeneratedOne) fails when this file differs from the declarations.\n"
      "     Regenerate: medspring info --params > docs/parameters.md -->\n\n"
      "Every parameter below is declared once, beside its struct (`for_each_field`, "
      "[core/params.hpp](../include/medspring/core/params.hpp)). The same declaration gives the scene "
      "file's keys ([scenes.md](scenes.md)), their checks, the Python properties and keyword arguments, "
      "and this page. The name is the JSON key; in Python the property of the same name (`integrator` "
      "for the key `method`). A nested name `duffing.eta` is the key `eta` of the object `duffing`. Numbers "
      "and names can also be set on the command line: `medspring run SCENE --set integrator.dt=0.25`. A list "
      "of objects `tools[]` is each entry of the list `tools`; `required` keys have no default.\n\n"
      "Read by hand besides the sets below ([scenes.md](scenes.md)): the model's kind, source and material, "
      "and the scene's name, description and duration.\n";
  for (ParamSet p : parameter_sets()) {
    for (ParamRow& r : p.rows) {  // a '|' would end the table cell
      std::string doc;
      for (char c : r.doc) doc += c == '|' ? std::string("\\|") : std::string(1, c);
      r.doc = doc;
    }
    s += cat("\n## ", p.title, "\n\n`", p.struct_name, "`, declared in [", p.declared_in, "](../",
             p.declared_in, "); in a file: ", p.scene_path, ".\n\n");
    s += params_markdown(p.rows);
  }
  return s;
}

void set_scene_parameter(Scene& scene, const std::string& path, const std::string& value) {
  const auto starts = [&](const std::string& prefix) { return path.rfind(prefix, 0) == 0; };
  std::string name;
  try {
    if (starts("integrator.")) {
      name = path.substr(11);
      set_param(scene.step, name == "integrator" ? "method" : name, value);
    } else if (starts("model.parameters.") && scene.model.kind == ModelKind::Hybrid) {
      name = path.substr(17);
      set_param(scene.model.hybrid, name, value);
    } else if (starts("model.parameters.") && scene.model.kind == ModelKind::Surface) {
      name = path.substr(17);
      set_param(scene.model.surface, name, value);
    } else if (starts("model.parameters.") && scene.model.kind == ModelKind::Smrm) {
      name = path.substr(17);
      set_param(scene.model.smrm, name, value);
      if (name == "k_b") scene.model.smrm.bending = BendingMode::Constant;  // as in a scene file
    } else if (starts("model.parameters.") && scene.model.kind == ModelKind::Volumetric) {
      name = path.substr(17);
      set_param(scene.model.volumetric, name, value);
    } else if (starts("record.")) {
      name = path.substr(7);
      set_param(scene.record, name, value);
    } else if (starts("local.")) {
      name = path.substr(6);
      set_param(scene.local, name, value);
      if (name == "k_loc") scene.local_k_from_body = scene.local.use_body_stiffness = false;
    } else if (starts("contact.")) {
      name = path.substr(8);
      set_param(scene.contact, name, value);
    } else {
      throw InvalidInput(
          "not a declared parameter of this scene (integrator.NAME, local.NAME, contact.NAME, record.NAME, "
          "or model.parameters.NAME; see docs/parameters.md)");
    }
  } catch (const InvalidInput& e) {
    std::string what = e.what();
    if (!name.empty() && what.rfind(name + ": ", 0) == 0) what = what.substr(name.size() + 2);
    throw InvalidInput(cat("--set ", path, ": ", what));
  }
}

void apply_scene_settings(Scene& scene, const std::string& assignments) {
  std::size_t start = 0;
  while (start <= assignments.size()) {
    const std::size_t end = std::min(assignments.find(',', start), assignments.size());
    const std::string item = assignments.substr(start, end - start);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InvalidInput(cat("--set: expected PATH=VALUE (got '", item, "')"));
    set_scene_parameter(scene, item.substr(0, eq), item.substr(eq + 1));
    start = end + 1;
  }
}

}  // namespace medspring
