// Parameters declared once (core/params.hpp): every declared field of every set round-trips through a
// scene file, is range-checked with its JSON path, can be set from the command line, and the committed
// docs/parameters.md is the generated one.
#include "medspring/core/params.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/scene/parameter_docs.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/scene/scene_tools.hpp"
#include "medspring/scene/study_settings.hpp"
#include "medspring/sim/simulation.hpp"
#include "medspring/tools/contact.hpp"

namespace medspring {
namespace {

const char* kHybrid = R"({"model": {"kind": "hybrid", "source": {"phantom": "kidney"}}, "duration": 10})";

/// Gives every field of p a valid value different from its current one (nested structs included).
template <ParamStruct T>
void perturb(T& p) {
  for_each_field(p, [](const ParamSpec& s, auto& f) {
    using F = std::remove_cvref_t<decltype(f)>;
    if constexpr (ParamStruct<F>) {
      perturb(f);
    } else if constexpr (std::is_same_v<F, bool>) {
      f = !f;
    } else if constexpr (std::is_enum_v<F>) {
      f = static_cast<F>(static_cast<int>(f) ^ 1);  // every declared enum has at least two values
    } else if constexpr (std::is_integral_v<F>) {
      f = range_error(s, f + 1).empty() ? f + 1 : f - 1;
    } else if constexpr (std::is_arithmetic_v<F>) {
      const F up = f * 1.25 + 0.125;
      f = range_error(s, up).empty() ? up : f * 0.5;
    } else if constexpr (ParamOptionalNumber<F>) {
      typename F::value_type x = f.value_or(1);
      x = std::is_integral_v<typename F::value_type> ? x + 1 : x * 1.25 + 0.125;
      f = x;
    } else if constexpr (ParamOptional<F>) {
      f = typename F::value_type(1, 2, 3);
    } else if constexpr (std::is_same_v<F, std::vector<double>>) {
      f = {1.5, 2.5};
    } else if constexpr (std::is_same_v<F, std::string>) {
      f += "x";
    } else {
      f = {1, 3, 4};
    }
    EXPECT_EQ(range_error(s, f), "") << s.name;
  });
}

/// Every field of p as "name=value" lines (fields the program sets, which no file holds, left out).
template <ParamStruct T>
std::string dump(const T& p, const std::string& prefix = "") {
  std::string out;
  for_each_field(p, [&](const ParamSpec& s, const auto& f) {
    using F = std::remove_cvref_t<decltype(f)>;
    if (s.derived) return;
    if constexpr (ParamStruct<F>) {
      out += dump(f, cat(prefix, s.json_name(), "."));
    } else if constexpr (ParamList<F>) {
      for (std::size_t k = 0; k < f.size(); ++k) out += dump(f[k], cat(prefix, s.json_name(), "[", k, "]."));
    } else {
      out += cat(prefix, s.json_name(), "=", param_value_text(f), "\n");
    }
  });
  return out;
}

/// Perturbs every field of p, checks that each line changed, writes the scene and reads it back:
/// the fields read back are the perturbed ones.
template <ParamStruct T>
void expect_round_trip(Scene s, T Scene::*block, T SceneModel::*model_block) {
  T& p = block ? s.*block : s.model.*model_block;
  const std::string defaults = dump(p);
  perturb(p);
  const std::string changed = dump(p);
  std::istringstream a(defaults), b(changed);
  int lines = 0;
  for (std::string la, lb; std::getline(a, la) && std::getline(b, lb); ++lines) EXPECT_NE(la, lb);
  EXPECT_GE(lines, 4);
  const Scene back = parse_scene(scene_to_json(s), ".", "t.json");
  EXPECT_EQ(dump(block ? back.*block : back.model.*model_block), changed);
}

const char* kSurface =
    R"({"model": {"kind": "surface", "source": {"phantom": "kidney"}}, "duration": 10,
        "tools": [{"shape": "sphere", "radius": 8, "path": [{"t": 0, "position": [0, 0, 60]}]}]})";
const char* kVessel =
    R"({"model": {"kind": "smrm", "source": {"phantom": {"name": "vessel", "path": "straight_x"}}},
        "duration": 10})";

TEST(DeclaredParameters, EveryHybridAndStepFieldRoundTripsThroughASceneFile) {
  Scene s = parse_scene(kHybrid, ".", "t.json");
  const std::string defaults = dump(s.model.hybrid) + dump(s.step);
  perturb(s.model.hybrid);
  perturb(s.step);
  const std::string changed = dump(s.model.hybrid) + dump(s.step);
  // every line differs from the default (a field that perturb could not change would hide a round trip)
  std::istringstream a(defaults), b(changed);
  for (std::string la, lb; std::getline(a, la) && std::getline(b, lb);) EXPECT_NE(la, lb);
  const Scene back = parse_scene(scene_to_json(s), ".", "t.json");
  EXPECT_EQ(dump(back.model.hybrid) + dump(back.step), changed);
}

TEST(DeclaredParameters, EverySurfaceSmrmLocalAndContactFieldRoundTripsThroughASceneFile) {
  const Scene surface = parse_scene(kSurface, ".", "t.json");
  expect_round_trip<SurfaceBodyParams>(surface, nullptr, &SceneModel::surface);
  expect_round_trip<SmrmSettings>(parse_scene(kVessel, ".", "t.json"), nullptr, &SceneModel::smrm);
  expect_round_trip<ContactSettings>(surface, &Scene::contact, nullptr);
  Scene local = surface;
  local.local_k_from_body = false;  // as a file with "k_loc" says
  expect_round_trip<LocalOptions>(local, &Scene::local, nullptr);
}

const char* kVolumetric =
    R"({"model": {"kind": "volumetric", "source": {"phantom": "kidney"}, "material": {"E_kPa": 12, "nu": 0.4}},
        "duration": 10})";

TEST(DeclaredParameters, EveryVolumetricAndRecordFieldRoundTripsThroughASceneFile) {
  const Scene v = parse_scene(kVolumetric, ".", "t.json");
  EXPECT_EQ(v.model.volumetric.E_kPa, 12);  // from "material", not a parameter
  expect_round_trip<VolumetricSettings>(v, nullptr, &SceneModel::volumetric);
  expect_round_trip<SceneRecord>(parse_scene(kHybrid, ".", "t.json"), &Scene::record, nullptr);
  // k_r: null (the default) is the model's choice; a number is kept
  Scene s = v;
  ASSERT_FALSE(s.model.volumetric.return_k.has_value());
  EXPECT_FALSE(parse_scene(scene_to_json(s), ".", "t.json").model.volumetric.return_k.has_value());
  apply_scene_settings(s, "model.parameters.k_r=0.03,model.parameters.nodes=500,record.every=3");
  EXPECT_EQ(s.model.volumetric.return_k, 0.03);
  EXPECT_EQ(s.model.volumetric.mesh_nodes, 500);
  EXPECT_EQ(s.record.every, 3);
  apply_scene_settings(s, "model.parameters.k_r=null");
  EXPECT_FALSE(s.model.volumetric.return_k.has_value());
}

/// The keys of every object in the JSON text's array `list` (and of their `nested` arrays).
std::string written_keys(const std::string& scene_json, const std::string& list) {
  std::string out;
  const auto add = [&](const std::string& key) {
    if (out.find(cat("|", key, "|")) == std::string::npos) out += cat("|", key, "|");
  };
  const std::size_t at = scene_json.find(cat("\"", list, "\": ["));
  for (std::size_t q = scene_json.find('"', at + list.size() + 4); q != std::string::npos;
       q = scene_json.find('"', q + 1)) {
    const std::size_t e = scene_json.find('"', q + 1);
    if (scene_json.compare(e + 1, 1, ":") == 0) add(scene_json.substr(q + 1, e - q - 1));
    q = e;
    if (scene_json.find("\n  }", e) < scene_json.find('"', e + 1)) break;  // the end of the top-level key
  }
  return out;
}

TEST(DeclaredParameters, EveryLoadAndToolKeyRoundTripsThroughASceneFile) {
  std::string text = kHybrid;
  text.insert(text.size() - 1, R"(, "loads": [
      {"node": 5, "direction": [0, 0, -2], "magnitude": 0.5, "t_on": 1, "t_ramp": 3, "t_release": 8,
       "ramp_down": true},
      {"point": [1, 2, 3], "direction": "towards_atom", "atom": 4, "magnitude": 1},
      {"ring": 2, "spoke": 3, "direction": "inward_normal", "magnitude": 2, "t_release": null}],
    "tools": [{"shape": "grasper", "radius": 1.5, "length": 12, "opening_deg": 60,
               "path": [{"t": 0, "position": [0, 40, 10], "rotation": [0, 0, 0, 2], "opening_deg": 30},
                        {"t": 10, "position": [0, 30, 10]}]},
              {"shape": "capsule", "radius": 2, "length": 5, "path": [{"t": 0, "position": [1, 2, 3]}]}])");
  const Scene s = parse_scene(text, ".", "t.json");
  const std::string written = scene_to_json(s);
  const Scene b = parse_scene(written, ".", "t.json");
  ASSERT_EQ(b.loads.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const SceneLoad &x = s.loads[k], &y = b.loads[k];
    EXPECT_EQ(x.pick, y.pick);
    EXPECT_EQ(x.node, y.node);
    EXPECT_EQ(x.point, y.point);
    EXPECT_EQ(x.ring, y.ring);
    EXPECT_EQ(x.spoke, y.spoke);
    EXPECT_EQ(x.direction, y.direction);
    EXPECT_EQ(x.vector, y.vector);
    EXPECT_EQ(x.target_atom, y.target_atom);
    EXPECT_EQ(x.magnitude, y.magnitude);
    EXPECT_EQ(x.t_on, y.t_on);
    EXPECT_EQ(x.t_ramp, y.t_ramp);
    EXPECT_EQ(x.t_release, y.t_release);
    EXPECT_EQ(x.ramp_down, y.ramp_down);
  }
  EXPECT_EQ(s.loads[0].vector, Vec3(0, 0, -2));  // as written
  EXPECT_EQ(s.loads[1].target_atom, 4);
  EXPECT_TRUE(std::isinf(s.loads[2].t_release));
  ASSERT_EQ(b.tools.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const SceneTool &x = s.tools[k], &y = b.tools[k];
    EXPECT_EQ(x.tool.kind, y.tool.kind);
    EXPECT_EQ(x.tool.radius, y.tool.radius);
    EXPECT_EQ(x.tool.length, y.tool.length);
    EXPECT_NEAR(x.tool.opening, y.tool.opening, 1e-15);
    ASSERT_EQ(x.path.size(), y.path.size());
    for (std::size_t r = 0; r < x.path.size(); ++r) {
      EXPECT_EQ(x.path[r].t, y.path[r].t);
      EXPECT_EQ(x.path[r].pose.position, y.path[r].pose.position);
      EXPECT_NEAR((x.path[r].pose.rotation.coeffs() - y.path[r].pose.rotation.coeffs()).norm(), 0, 1e-15);
      EXPECT_NEAR(x.path[r].opening, y.path[r].opening, 1e-15);
    }
  }
  EXPECT_NEAR(s.tools[0].tool.opening, std::acos(-1.0) / 3, 1e-15);
  EXPECT_NEAR(s.tools[0].path[0].pose.rotation.z(), 1, 1e-15);  // normalised
  EXPECT_LT(s.tools[0].path[1].opening, 0);                     // not given: the tool's own
  // every declared key is written (path_file is read into keyframes)
  const LoadEntry kConstLoadEntry{};
  const ToolEntry kConstToolEntry{};
  const ToolKeyframeEntry kConstToolKeyframeEntry{};
  const std::string loads = written_keys(written, "loads"), tools = written_keys(written, "tools");
  for_each_field(kConstLoadEntry, [&](const ParamSpec& p, const auto&) {
    EXPECT_NE(loads.find(cat("|", p.json_name(), "|")), std::string::npos) << p.name << " in " << loads;
  });
  for_each_field(kConstToolEntry, [&](const ParamSpec& p, const auto&) {
    if (p.name != "path_file") {
      EXPECT_NE(tools.find(cat("|", p.json_name(), "|")), std::string::npos) << p.name << " in " << tools;
    }
  });
  for_each_field(kConstToolKeyframeEntry, [&](const ParamSpec& p, const auto&) {
    EXPECT_NE(tools.find(cat("|", p.json_name(), "|")), std::string::npos) << p.name << " in " << tools;
  });
}

TEST(DeclaredParameters, LoadToolRecordAndVolumetricErrorsNameTheJsonPath) {
  const auto error = [](std::string base, const std::string& where, const std::string& what) {
    if (where == "parameters")
      base.insert(base.find(", \"material\""), cat(", \"parameters\": ", what));
    else
      base.insert(base.size() - 1, cat(", \"", where, "\": ", what));
    try {
      parse_scene(base, ".", "t.json");
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  const std::string path = R"("path": [{"t": 0, "position": [0, 0, 1]}])";
  const std::pair<std::string, std::string> cases[] = {
      {error(kVolumetric, "parameters", R"({"nodes": 5})"),
       "t.json: model.parameters.nodes: must be >= 10 (got 5)"},
      {error(kVolumetric, "parameters", R"({"k_r": -1})"),
       "t.json: model.parameters.k_r: must be >= 0 (got -1)"},
      {error(kVolumetric, "parameters", R"({"E_kPa": 3})"),
       "t.json: model.parameters.E_kPa: unknown key (expected one of: nodes, mesh_sizing, density, beta, "
       "k_r, "
       "spring_scale, volume_scale, surface_spring_scale, overlay_compliance, compression, mass_scaling_dt, "
       "min_mass_fraction, "
       "moduli_correction, "
       "duffing, thin_tet, thin_tet_q_max, volume_precision, fixed)"},
      {error(kVolumetric, "parameters", R"({"duffing": {"mode": "cubic"}})"),
       "t.json: model.parameters.duffing.mode: duffing mode: unknown value 'cubic' (expected linear, strain, "
       "absolute or scaled_strain)"},
      {error(kHybrid, "record", R"({"every": 0})"), "t.json: record.every: must be >= 1 (got 0)"},
      {error(kHybrid, "record", R"({"key_times": [1, -1]})"),
       "t.json: record.key_times[1]: must be >= 0 (got -1)"},
      {error(kHybrid, "record", R"({"nodes": 3})"), "t.json: record.nodes: must be an array of node indices"},
      {error(kHybrid, "loads", R"([{"node": 1, "direction": 5, "magnitude": 1}])"),
       "t.json: loads[0].direction: must be 3 numbers or enum (got a number)"},
      {error(kHybrid, "loads", R"([{"node": 1, "direction": "up", "magnitude": 1}])"),
       "t.json: loads[0].direction: unknown direction 'up' (expected [x, y, z], inward_normal or "
       "towards_atom)"},
      {error(kHybrid, "loads", R"([{"point": [1, 2], "direction": [0, 0, 1], "magnitude": 1}])"),
       "t.json: loads[0].point: must be an array of 3 numbers"},
      {error(kHybrid, "loads", R"([{"node": 1, "magnitude": 1}])"),
       "t.json: loads[0].direction: is required"},
      {error(kHybrid, "loads", R"([{"node": 1, "direction": [0, 0, 1], "magnitude": 1, "t_ramp": -2}])"),
       "t.json: loads[0].t_ramp: must be >= 0 (got -2)"},
      {error(kHybrid, "tools", cat(R"([{"shape": "sphere", "radius": 1, "length": -1, )", path, "}]")),
       "t.json: tools[0].length: must be >= 0 (got -1)"},
      {error(kHybrid, "tools", R"([{"shape": "sphere", "radius": 1, "path": [{"position": [0, 0, 1]}]}])"),
       "t.json: tools[0].path[0].t: is required (ms)"},
      {error(kHybrid, "tools",
             R"([{"shape": "grasper", "radius": 1, "length": 3, "path": [{"t": 0, "position": [0, 0, 1],
                  "opening_deg": 200}]}])"),
       "t.json: tools[0].path[0].opening_deg: must be in [0, 180] (got 200)"},
      {error(kHybrid, "tools", R"([{"radius": 1, "path_file": "a.csv"}])"),
       "t.json: tools[0].shape: is required"},
      {error(kHybrid, "tools", R"([{"shape": "sphere", "radius": 1, "path_file": ""}])"),
       "t.json: tools[0].path_file: must not be empty"},
  };
  for (const auto& [got, expected] : cases) EXPECT_EQ(got, expected);
}

TEST(DeclaredParameters, EveryCommittedSceneFileParsesAndItsWrittenFormIsAFixedPoint) {
  int files = 0;
  for (const char* dir : {"scenes", "scenes/phantom", "examples/scenes", "examples/tools"}) {
    const std::filesystem::path folder = std::filesystem::path(MEDSPRING_SOURCE_DIR) / dir;
    if (!std::filesystem::is_directory(folder)) continue;
    for (const auto& f : std::filesystem::directory_iterator(folder)) {
      if (f.path().extension() != ".json") continue;
      Scene s;
      try {
        s = load_scene(f.path());
      } catch (const std::exception& e) {
        if (std::string(e.what()).find("MEDSPRING_DATA") != std::string::npos) continue;  // no data here
        ADD_FAILURE() << e.what();
        continue;
      }
      const std::string written = scene_to_json(s);
      EXPECT_EQ(scene_to_json(parse_scene(written, f.path().parent_path(), "w.json")), written) << f.path();
      ++files;
    }
  }
  EXPECT_GE(files, 8);
}

TEST(DeclaredParameters, SceneFormsKeptBesideTheDeclarations) {
  // "k_b" without "bending" is constant bending; with "bending": "wall" it is refused
  std::string text = kVessel;
  text.insert(text.find("}},") + 1, R"(, "parameters": {"k_b": 0.01})");
  Scene s = parse_scene(text, ".", "t.json");
  EXPECT_EQ(s.model.smrm.bending, BendingMode::Constant);
  EXPECT_EQ(s.model.smrm.chain.kb, 0.01);
  text = kVessel;
  text.insert(text.find("}},") + 1, R"(, "parameters": {"k_b": 0.01, "bending": "wall"})");
  EXPECT_THROW(parse_scene(text, ".", "t.json"), InvalidInput);
  // "local": {} is on; "local": true/false; k_loc given turns the body's stiffness off
  text = kVessel;
  text.insert(text.size() - 1, R"(, "local": {"k_loc": 0.2, "stiffness": "axis_projected"})");
  s = parse_scene(text, ".", "t.json");
  EXPECT_TRUE(s.local.enabled);
  EXPECT_FALSE(s.local_k_from_body);
  EXPECT_FALSE(s.local.use_body_stiffness);
  EXPECT_EQ(s.local.settings.solver.stiffness, LocalStiffness::AxisProjected);
  EXPECT_EQ(parse_scene(scene_to_json(s), ".", "t.json").local.settings.patch.k_loc, 0.2);
  // the grasp angle in degrees (older scenes) and in radians (declared)
  text = kSurface;
  text.insert(text.size() - 1, R"(, "contact": {"grasp_angle_deg": 90, "friction": 0.2})");
  s = parse_scene(text, ".", "t.json");
  EXPECT_NEAR(s.contact.grasp_angle, std::acos(-1.0) / 2, 1e-15);
  EXPECT_EQ(s.contact.friction, 0.2);
  text = kSurface;
  text.insert(text.size() - 1, R"(, "contact": {"dt": 0.1})");
  try {
    parse_scene(text, ".", "t.json");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("t.json: contact.dt: unknown key"), std::string::npos) << e.what();
  }
  text = kSurface;
  text.insert(text.size() - 1, R"(, "contact": {"kappa": 5})");
  try {
    parse_scene(text, ".", "t.json");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("t.json: contact.kappa: must be in (0, 4] (got 5)"),
              std::string::npos)
        << e.what();
  }
}

TEST(DeclaredParameters, EveryHybridFieldRoundTripsThroughAModelPackage) {
  HybridSettings h;
  const std::string defaults = dump(h);
  perturb(h);
  ASSERT_NE(dump(h), defaults);
  const HybridKidney kidney = hybrid_kidney_phantom(h);
  const ModelPackage back = decode_model_package(encode_model_package(package_of(kidney, "k")), "k.msm");
  EXPECT_EQ(dump(back.hybrid), dump(h));
  EXPECT_EQ(back.hybrid.nonlinear, h.nonlinear);
}

TEST(DeclaredParameters, EverySurfaceAndSmrmFieldRoundTripsThroughAModelPackage) {
  // version 5 (model_package.hpp): the surface and SMRM settings are stored by their declarations too
  SurfaceBodyParams sp;
  const std::string surface_defaults = dump(sp);
  perturb(sp);
  ASSERT_NE(dump(sp), surface_defaults);
  const SurfaceBody surface(tube(6, 8, 2.5, 3.0), sp, "tube", GridLayout{6, 8});
  const ModelPackage a = decode_model_package(encode_model_package(package_of(surface)), "s.msm");
  EXPECT_EQ(dump(a.surface_params), dump(sp));

  SmrmSettings vs;
  vs.atoms = 12;
  const std::string smrm_defaults = dump(vs);
  perturb(vs);
  vs.chain.nonlinear = !vs.chain.nonlinear;  // the model's "nonlinear" key, stored beside the declaration
  ASSERT_NE(dump(vs), smrm_defaults);
  const SmrmVessel vessel = smrm_phantom(VesselPath::Arc, CrossSectionShape::Elliptical, vs);
  const ModelPackage b = decode_model_package(encode_model_package(package_of(vessel)), "v.msm");
  EXPECT_EQ(dump(b.smrm), dump(vs));
  EXPECT_EQ(b.smrm.atoms, 12);
  EXPECT_EQ(b.smrm.chain.nonlinear, vs.chain.nonlinear);
}

TEST(DeclaredParameters, EveryStudySettingRoundTripsThroughAStudyFile) {
  StudySettings s;
  const std::string defaults = dump(s);
  perturb(s);
  std::istringstream a(defaults), b(dump(s));
  int lines = 0;
  for (std::string la, lb; std::getline(a, la) && std::getline(b, lb); ++lines) EXPECT_NE(la, lb);
  EXPECT_EQ(lines, 5);
  const StudySettings back = study_settings_from_json(study_settings_json(s), "s.json");
  EXPECT_EQ(dump(back), dump(s));
  // the study file's other keys are the caller's (medspring/study/spec.py); absent keys keep defaults
  const StudySettings partial = study_settings_from_json(
      R"({"scene": "k.json", "vary": [], "seed": 19, "samples": {"count": 8}})", "s.json");
  EXPECT_EQ(partial.seed, 19);
  EXPECT_EQ(partial.samples.count, 8);
  EXPECT_EQ(partial.samples.method, SampleMethod::Random);
  EXPECT_EQ(partial.batch, StudySettings{}.batch);
  const auto refused = [](const std::string& text, const std::string& message) {
    try {
      study_settings_from_json(text, "s.json");
      ADD_FAILURE() << text << " accepted";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(std::string(e.what()), message);
    }
  };
  refused(R"({"batch": 0})", "s.json: batch: must be an integer in 1..100000 (got 0)");
  refused(R"({"seed": -1})", "s.json: seed: must be >= 0 (got -1)");
  refused(R"({"samples": {"count": 0}})", "s.json: samples.count: must be >= 1 (got 0)");
  refused(R"({"samples": {"method": "sobol"}})",
          "s.json: samples.method: expected 'random' or 'latin_hypercube' (got 'sobol')");
  refused(R"({"samples": {"cnt": 3}})", "s.json: samples.cnt: unknown key (expected one of: count, method)");
  refused(R"({"max_runs": 1.5})", "s.json: max_runs: must be an integer (got 1.5)");
  // --set (medspring study STUDY --set samples.method=latin_hypercube)
  set_param(s, "samples.method", "latin_hypercube");
  EXPECT_EQ(s.samples.method, SampleMethod::LatinHypercube);
  EXPECT_THROW(set_param(s, "batch", "0"), InvalidInput);
}

TEST(DeclaredParameters, EveryBoundedFieldRejectsAValueOutOfRangeNamingItsPath) {
  int checked = 0;
  const auto check = [&](const std::string& block, const std::string& name, const std::string& type,
                         const ParamSpec& s) {
    const ParamRow r{name, type, "", "", "", ""};
    if (!s.has_lo() || r.type == "node list") return;
    const double bad = s.lo - 1;
    std::string text = kHybrid;
    const std::string value = r.type == "integer" ? cat(static_cast<long>(bad)) : cat(bad);
    std::string key = r.name, obj = cat("{\"", key, "\": ", value, "}");
    if (const auto dot = key.find('.'); dot != std::string::npos)
      obj = cat("{\"", key.substr(0, dot), "\": {\"", key.substr(dot + 1), "\": ", value, "}}");
    if (block == "integrator")
      text.insert(text.size() - 1, cat(", \"integrator\": ", obj));
    else
      text.insert(text.find("}}") + 1, cat(", \"parameters\": ", obj));
    try {
      parse_scene(text, ".", "t.json");
      ADD_FAILURE() << r.name << " = " << value << " accepted";
    } catch (const InvalidInput& e) {
      const std::string path = block == "integrator" ? "integrator." : "model.parameters.";
      EXPECT_NE(std::string(e.what()).find(cat("t.json: ", path, r.name, ": must be")), std::string::npos)
          << e.what();
    }
    ++checked;
  };
  const auto each = [&](const std::string& block, auto settings) {
    for_each_field(settings, [&](const ParamSpec& s, const auto& f) {
      using F = std::remove_cvref_t<decltype(f)>;
      if constexpr (ParamStruct<F>) {
        for_each_field(f, [&](const ParamSpec& s2, const auto& g) {
          using G = std::remove_cvref_t<decltype(g)>;
          if constexpr (std::is_arithmetic_v<G> && !std::is_same_v<G, bool>)
            check(block, cat(s.json_name(), ".", s2.json_name()), param_type_text<G>(), s2);
        });
      } else if constexpr (std::is_arithmetic_v<F> && !std::is_same_v<F, bool>) {
        check(block, std::string(s.json_name()), param_type_text<F>(), s);
      }
    });
  };
  each("model.parameters", HybridSettings{});
  each("integrator", StepSettings{});
  EXPECT_GE(checked, 20);
}

TEST(DeclaredParameters, UnknownKeysAndWrongTypesAreNamed) {
  std::string text = kHybrid;
  text.insert(text.find("}}") + 1, R"(, "parameters": {"k_spokes": 1})");
  try {
    parse_scene(text, ".", "t.json");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("model.parameters.k_spokes: unknown key (expected one of: mass,"),
              std::string::npos)
        << e.what();
  }
  text = kHybrid;
  text.insert(text.size() - 1, R"(, "integrator": {"substep": 1})");
  try {
    parse_scene(text, ".", "t.json");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("t.json: integrator.substep: must be true or false"),
              std::string::npos)
        << e.what();
  }
}

TEST(DeclaredParameters, CommandLineSettingsUseTheDeclarations) {
  Scene s = parse_scene(kHybrid, ".", "t.json");
  apply_scene_settings(
      s,
      "integrator.dt=0.25,model.parameters.k_spoke=0.08,model.parameters.duffing.mode=absolute,"
      "integrator.method=implicit_euler,model.parameters.spokes_per_atom=6");
  EXPECT_EQ(s.step.dt, 0.25);
  EXPECT_EQ(s.model.hybrid.k_spoke, 0.08);
  EXPECT_EQ(s.model.hybrid.duffing.mode, DuffingMode::Absolute);
  EXPECT_EQ(s.step.integrator, Integrator::ImplicitEuler);
  EXPECT_EQ(s.model.hybrid.spokes_per_atom, 6);
  const auto error = [&](const std::string& a) {
    try {
      apply_scene_settings(s, a);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error("integrator.safety=2"), "--set integrator.safety: must be in (0, 1] (got 2)");
  EXPECT_EQ(error("model.parameters.spokes_per_atom=1.5"),
            "--set model.parameters.spokes_per_atom: must be an integer (got '1.5')");
  EXPECT_NE(error("integrator.dtt=1").find("unknown parameter 'dtt'"), std::string::npos);
  EXPECT_NE(error("dt").find("expected PATH=VALUE"), std::string::npos);
  apply_scene_settings(
      s, "local.patch_nodes=12,local.stiffness=linearized,contact.friction=0.3,local.k_loc=0.1");
  EXPECT_EQ(s.local.settings.patch.count, 12);
  EXPECT_EQ(s.local.settings.solver.stiffness, LocalStiffness::Linearized);
  EXPECT_EQ(s.contact.friction, 0.3);
  EXPECT_FALSE(s.local_k_from_body);
  EXPECT_EQ(error("contact.dt=1"), "--set contact.dt: is set by the program from the model");
  EXPECT_EQ(error("local.half_width=0"), "--set local.half_width: must be >= 1 (got 0)");
  Scene v = parse_scene(kVessel, ".", "t.json");
  apply_scene_settings(v, "model.parameters.k_cl=0.3,model.parameters.frame_anchor=one_end");
  EXPECT_EQ(v.model.smrm.chain.k, 0.3);
  EXPECT_EQ(v.model.smrm.frames.anchor, FrameAnchor::OneEnd);
}

TEST(DeclaredParameters, ValidationNamesTheField) {
  StepSettings s;
  s.threads = 0;
  try {
    validate_params(s, "step");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "step.threads: must be an integer in 1..256 (got 0)");
  }
  HybridSettings h;
  h.fixed = {2, -1};
  try {
    validate_params(h, "hybrid");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "hybrid.fixed[1]: must be >= 0 (got -1)");
  }
}

TEST(DeclaredParameters, CommittedDocsTableIsTheGeneratedOne) {
  const char* file = MEDSPRING_SOURCE_DIR "/docs/parameters.md";
  if (std::getenv("MEDSPRING_WRITE_PARAMETERS_MD"))
    std::ofstream(file, std::ios::binary) << parameter_tables_markdown();
  std::ifstream in(file, std::ios::binary);
  ASSERT_TRUE(in) << "docs/parameters.md missing";
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), parameter_tables_markdown())
      << "docs/parameters.md is stale: regenerate with  medspring info --params > docs/parameters.md";
}

}  // namespace
}  // namespace medspring
