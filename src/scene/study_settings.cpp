// The declared settings of a study file (scene/study_settings.hpp) from and to JSON.
#include "medspring/scene/study_settings.hpp"

#include <nlohmann/json.hpp>

#include "params_json.hpp"

namespace medspring {

StudySettings study_settings_from_json(const std::string& json_text, const std::string& origin) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    throw InvalidInput(cat(origin, ": invalid JSON (", e.what(), ")"));
  }
  if (!doc.is_object()) throw InvalidInput(cat(origin, ": a study must be a JSON object"));
  StudySettings s;
  nlohmann::json declared = nlohmann::json::object();  // the declared keys; the others are the caller's
  for_each_field(s, [&](const ParamSpec& spec, const auto&) {
    const std::string key(spec.json_name());
    if (doc.contains(key)) declared[key] = doc[key];
  });
  try {
    params_from_json(declared, "", s);  // errors ".samples.count: ..."
  } catch (const InvalidInput& e) {
    const std::string what = e.what();
    throw InvalidInput(cat(origin, ": ", what.rfind('.', 0) == 0 ? what.substr(1) : what));
  }
  return s;
}

std::string study_settings_json(const StudySettings& settings) {
  return params_to_json(settings).dump();
}

}  // namespace medspring
