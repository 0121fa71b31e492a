// Scene files: JSON -> Scene, with every error naming the scene and the JSON path (docs/scenes.md).
#include "medspring/scene/scene.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "medspring/core/check.hpp"
#include "medspring/medial/frames.hpp"
#include "medspring/physics/parallel.hpp"
#include "params_json.hpp"
#include "scene_reader.hpp"

#ifndef MEDSPRING_SCENE_DEFAULT_DATA_DIR
#define MEDSPRING_SCENE_DEFAULT_DATA_DIR "../shared/data"
#endif

namespace medspring {

using json = nlohmann::json;
namespace fs = std::filesystem;

ModelKind parse_model_kind(const std::string& text) {
  if (text == "surface") return ModelKind::Surface;
  if (text == "hybrid") return ModelKind::Hybrid;
  if (text == "smrm") return ModelKind::Smrm;
  if (text == "volumetric") return ModelKind::Volumetric;
  throw InvalidInput(cat("unknown model kind '", text, "' (expected surface, hybrid, smrm or volumetric)"));
}

std::string to_string(NamedDirection d) {
  return d == NamedDirection::InwardNormal ? "inward_normal" : "towards_atom";
}

NamedDirection parse_enum(const std::string& text, NamedDirection*) {
  if (text == "inward_normal") return NamedDirection::InwardNormal;
  if (text == "towards_atom") return NamedDirection::TowardsAtom;
  throw InvalidInput(
      cat("unknown direction '", text, "' (expected [x, y, z], inward_normal or towards_atom)"));
}

std::string to_string(ModelKind kind) {
  switch (kind) {
    case ModelKind::Surface:
      return "surface";
    case ModelKind::Hybrid:
      return "hybrid";
    case ModelKind::Smrm:
      return "smrm";
    case ModelKind::Volumetric:
      return "volumetric";
  }
  return "?";
}

fs::path scene_data_dir() {
  if (const char* env = std::getenv("MEDSPRING_DATA"); env != nullptr && *env != '\0') return fs::path(env);
  return fs::path(MEDSPRING_SCENE_DEFAULT_DATA_DIR);
}

namespace {

using namespace scene_detail;

LengthUnit parse_unit(Obj& o, const std::string& key) {
  const json* v = o.get(key);
  if (!v) fail(o.ctx(), o.at(key), "is required (the unit of the file's coordinates: mm, cm, m or um)");
  const std::string s = as_string(o.ctx(), *v, o.at(key));
  return with_path(o.ctx(), o.at(key), [&] { return parse_length_unit(s); });
}

void parse_source(const Ctx& c, const json& j, const std::string& path, SceneModel& m) {
  Obj o(c, j, path);
  ModelSource& s = m.source;
  const json* phantom = o.get("phantom");
  const json* mesh = o.get("mesh");
  const json* seg = o.get("segmentation");
  const json* line = o.get("centerline");
  o.finish();
  const int count = (phantom != nullptr) + (mesh != nullptr) + (seg != nullptr) + (line != nullptr);
  if (count == 0) fail(c, path, "needs one of phantom, mesh, segmentation or centerline");
  const bool line_and_mesh = count == 2 && line && mesh;
  if (count > 1 && !line_and_mesh)
    fail(c, path,
         "give exactly one of phantom, mesh, segmentation, centerline (or centerline + mesh for smrm)");

  if (phantom) {
    s.type = ModelSource::Type::Phantom;
    const std::string pp = o.at("phantom");
    if (phantom->is_string()) {
      s.phantom = phantom->get<std::string>();
    } else {
      Obj p(c, *phantom, pp);
      s.phantom = p.string("name", "");
      if (s.phantom == "tube") {
        s.rings = p.index("rings", s.rings, 2);
        s.spokes = p.index("spokes", s.spokes, 3);
        s.spacing = p.positive("spacing", s.spacing);
        s.radius = p.positive("radius", s.radius);
      } else if (s.phantom == "vessel") {
        const std::string vp = p.string("path", "straight_x");
        s.path = with_path(c, p.at("path"), [&] { return parse_vessel_path(vp); });
        const std::string cs = p.string("cross_section", "circular");
        s.cross_section = with_path(c, p.at("cross_section"), [&] { return parse_cross_section(cs); });
      }
      p.finish();
    }
    if (s.phantom != "kidney" && s.phantom != "tube" && s.phantom != "vessel")
      fail(c, pp, cat("unknown phantom '", s.phantom, "' (expected kidney, tube or vessel)"));
    const bool ok = (s.phantom == "kidney" && m.kind != ModelKind::Smrm) ||
                    (s.phantom == "tube" && m.kind == ModelKind::Surface) ||
                    (s.phantom == "vessel" && m.kind == ModelKind::Smrm);
    if (!ok)
      fail(c, pp,
           cat("phantom '", s.phantom, "' cannot make a ", to_string(m.kind),
               " model (kidney: surface, hybrid or volumetric; tube: surface; vessel: smrm)"));
  }
  // "branches": "all" (a vessel tree: every polyline of a centerline file, or the skeleton of every
  // endpoint of a mesh or segmentation) and its watertight surface ("blend", "blend_spacing_mm")
  // A tree from a mesh or a segmentation takes the watertight surface fitted to the wall by default, as
  // `medspring build vessel` does ("blend": false: one open tube per branch); from centerlines the tubes.
  auto tree_keys = [&](Obj& p, bool organ) {
    if (const json* all = p.get("branches")) {
      if (!all->is_string() || all->get<std::string>() != "all")
        fail(c, p.at("branches"), "must be \"all\" (one branch: \"branch\": N)");
      if (p.get("branch")) fail(c, p.at("branches"), "give \"branch\" or \"branches\", not both");
      if (m.kind != ModelKind::Smrm)
        fail(c, p.at("branches"), cat("a vessel tree is an smrm model, not ", to_string(m.kind)));
      s.all_branches = true;
    }
    s.blend = p.boolean("blend", organ && s.all_branches);
    if (const json* bs = p.get("blend_spacing_mm")) {
      s.blend_spacing = as_number(c, *bs, p.at("blend_spacing_mm"));
      if (!(s.blend_spacing > 0) || !std::isfinite(s.blend_spacing))
        fail(c, p.at("blend_spacing_mm"), cat("must be > 0 mm (got ", s.blend_spacing, ")"));
      if (!s.blend) fail(c, p.at("blend_spacing_mm"), "applies with \"blend\": true");
    }
    if (s.blend && !s.all_branches)
      fail(c, p.at("blend"), "a watertight (blended) surface applies to a tree (\"branches\": \"all\")");
  };
  if (mesh) {
    Obj p(c, *mesh, o.at("mesh"));
    const json* f = p.get("file");
    if (!f) fail(c, p.at("file"), "is required");
    s.mesh = resolve_file(c, *f, p.at("file"));
    s.mesh_unit = parse_unit(p, "unit");
    if (!line) tree_keys(p, true);  // a tree from the mesh's skeleton (not for the boundary of a centerline)
    p.finish();
    if (!line) s.type = ModelSource::Type::Mesh;
  }
  if (seg) {
    s.type = ModelSource::Type::Segmentation;
    Obj p(c, *seg, o.at("segmentation"));
    const json* f = p.get("file");
    if (!f) fail(c, p.at("file"), "is required");
    s.segmentation = resolve_file(c, *f, p.at("file"));
    const Index label = p.index("label", 1, 1);
    s.label = static_cast<std::int32_t>(label);
    tree_keys(p, true);
    p.finish();
  }
  if (line) {
    s.type = ModelSource::Type::Centerline;
    Obj p(c, *line, o.at("centerline"));
    const json* f = p.get("file");
    if (!f) fail(c, p.at("file"), "is required");
    s.centerline = resolve_file(c, *f, p.at("file"));
    s.centerline_unit = parse_unit(p, "unit");
    s.branch = p.index("branch", 0, 0);
    tree_keys(p, false);
    s.radius_array = p.string("radius_array", s.radius_array);
    if (const json* r = p.get("range_mm")) {
      const std::string rp = p.at("range_mm");
      if (!r->is_array() || r->size() != 2) fail(c, rp, "must be [start, end] in mm of arc length");
      s.range_start = as_number(c, (*r)[0], rp + "[0]");
      s.range_end = as_number(c, (*r)[1], rp + "[1]");
      if (s.range_start < 0 || s.range_end <= s.range_start)
        fail(c, rp, cat("needs 0 <= start < end (got ", s.range_start, ", ", s.range_end, ")"));
    }
    p.finish();
  }
  if (s.type == ModelSource::Type::Centerline && m.kind != ModelKind::Smrm)
    fail(c, o.at("centerline"), cat("a centerline source makes an smrm model, not ", to_string(m.kind)));
}

void parse_parameters(const Ctx& c, const json& j, const std::string& path, SceneModel& m) {
  switch (m.kind) {
    case ModelKind::Hybrid:
      // Declared once (models/hybrid_kidney.hpp, for_each_field): every key, type and range checked there.
      with_origin(c, [&] { params_from_json(j, path, m.hybrid); });
      return;
    case ModelKind::Surface:  // declared in physics/model.hpp
      with_origin(c, [&] { params_from_json(j, path, m.surface); });
      return;
    case ModelKind::Smrm: {  // declared in models/smrm_vessel.hpp
      SmrmSettings& s = m.smrm;
      with_origin(c, [&] { params_from_json(j, path, s); });
      // Bending (issue 17): "wall" (default, E I of the wall) or "constant" (k_b; 0 = the paper's chain).
      // A k_b without "bending" means "constant".
      if (j.contains("k_b") && !j.contains("bending")) s.bending = BendingMode::Constant;
      if (j.contains("k_b") && s.bending == BendingMode::Wall)
        fail(c, path + ".k_b", "applies to \"bending\": \"constant\" only");
      return;
    }
    case ModelKind::Volumetric:  // declared in models/volumetric_body.hpp; E and nu from "material"
      with_origin(c, [&] { params_from_json(j, path, m.volumetric); });
      return;
  }
}

// "material": "kidney" | {"preset": "aorta"} | {"E_kPa": 12, "nu": 0.45} -> calibrated stiffnesses of the
// kind (models/tissue.hpp); "parameters" parsed afterwards override them.
void parse_material(const Ctx& c, const json& j, const std::string& path, SceneModel& m) {
  TissueMaterial t;
  if (j.is_string()) {
    const std::string name = as_string(c, j, path);
    t = with_path(c, path, [&] { return tissue_preset(name); });
  } else {
    Obj o(c, j, path);
    const json* preset = o.get("preset");
    if (preset) {
      const std::string name = as_string(c, *preset, o.at("preset"));
      t = with_path(c, o.at("preset"), [&] { return tissue_preset(name); });
    }
    const json* e = o.get("E_kPa");
    if (!e && !preset) fail(c, o.at("E_kPa"), "is required (Young's modulus, kPa) unless a preset is named");
    if (e) {
      t.E_kPa = as_number(c, *e, o.at("E_kPa"));
      t.preset.clear();
    }
    t.nu = o.number("nu", t.nu);
    if (o.has("nu")) t.preset.clear();
    o.finish();
  }
  if (!(std::isfinite(t.E_kPa) && t.E_kPa > 0))
    fail(c, path + ".E_kPa", cat("must be > 0 (got ", t.E_kPa, ")"));
  if (!(std::isfinite(t.nu) && t.nu > -1.0 && t.nu < 0.5))
    fail(c, path + ".nu", cat("must be in (-1, 0.5) (got ", t.nu, ")"));
  const TissueOrgan organ =
      m.source.type == ModelSource::Type::Phantom ? TissueOrgan::Phantom : TissueOrgan::RealKidney;
  m.hybrid.nonlinear = m.nonlinear;
  if (!m.nonlinear) m.surface.duffing.mode = DuffingMode::Linear;
  if (m.kind == ModelKind::Hybrid) apply_tissue(t, organ, m.hybrid);
  if (m.kind == ModelKind::Surface) apply_tissue(t, organ, m.surface);
  if (m.kind == ModelKind::Smrm) apply_tissue(t, m.smrm);
  if (m.kind == ModelKind::Volumetric) {  // no calibration: the stiffness rule of models/volumetric_body.hpp
    m.volumetric.E_kPa = t.E_kPa;
    m.volumetric.nu = t.nu;
  }
  m.material = t;
}

void parse_model(const Ctx& c, const json& j, SceneModel& m) {
  Obj o(c, j, "model");
  const json* kind = o.get("kind");
  if (!kind) fail(c, "model.kind", "is required (surface, hybrid or smrm)");
  const std::string k = as_string(c, *kind, "model.kind");
  m.kind = with_path(c, "model.kind", [&] { return parse_model_kind(k); });
  const json* source = o.get("source");
  if (!source) fail(c, "model.source", "is required");
  parse_source(c, *source, "model.source", m);
  m.nonlinear = o.boolean("nonlinear", m.kind != ModelKind::Volumetric);  // volumetric: linear by default
  if (m.kind == ModelKind::Volumetric && m.nonlinear) m.volumetric.duffing = DuffingSettings{};
  if (const json* t = o.get("material")) parse_material(c, *t, "model.material", m);
  m.surface_nodes = o.index("surface_nodes", 0, 0);
  if (m.surface_nodes > 0 && m.surface_nodes < 20) fail(c, "model.surface_nodes", "must be 0 or >= 20");
  if (m.surface_nodes > 0 && m.source.type != ModelSource::Type::Mesh &&
      m.source.type != ModelSource::Type::Segmentation)
    fail(c, "model.surface_nodes", "applies only to a mesh or segmentation source (balloon remeshing)");
  m.atoms = o.index("atoms", 0, 0);
  if (m.atoms > 0 && m.atoms < 3)
    fail(c, "model.atoms", cat("must be 0 (default) or >= 3 (got ", m.atoms, ")"));
  if (m.atoms > 0 && m.kind == ModelKind::Surface) fail(c, "model.atoms", "a surface model has no atoms");
  if (m.atoms > 0 && m.kind == ModelKind::Volumetric)
    fail(c, "model.atoms",
         "a volumetric model has no atoms (its interior nodes come from the tetrahedral mesh)");
  if (const json* p = o.get("parameters")) parse_parameters(c, *p, "model.parameters", m);
  o.finish();
  if (m.atoms == 0 && m.kind == ModelKind::Hybrid) m.atoms = 42;
  if (m.atoms == 0 && m.kind == ModelKind::Smrm) m.atoms = 40;
  m.smrm.atoms = m.atoms > 0 ? m.atoms : m.smrm.atoms;
  m.hybrid.nonlinear = m.nonlinear;
  m.smrm.chain.nonlinear = m.nonlinear;
  if (!m.nonlinear) m.surface.duffing.mode = DuffingMode::Linear;
}

// One entry of "loads": the declared keys (LoadEntry, scene.hpp) read, then resolved to a SceneLoad.
SceneLoad parse_load(const Ctx& c, const json& j, const std::string& path) {
  LoadEntry e;
  with_origin(c, [&] { params_from_json(j, path, e); });
  SceneLoad L;
  L.where = path;
  const int picks = e.node.has_value() + e.point.has_value() + (e.ring || e.spoke);
  if (picks != 1) fail(c, path, "needs exactly one of node, point, or ring + spoke");
  if (e.node) {
    L.pick = SceneLoad::Pick::Node;
    L.node = *e.node;
  } else if (e.point) {
    L.pick = SceneLoad::Pick::Point;
    L.point = *e.point;
  } else {
    if (!e.ring || !e.spoke) fail(c, path, "ring and spoke go together");
    L.pick = SceneLoad::Pick::RingSpoke;
    L.ring = *e.ring;
    L.spoke = *e.spoke;
  }
  if (const Vec3* v = std::get_if<Vec3>(&e.direction)) {
    L.direction = SceneLoad::Direction::Vector;
    L.vector = *v;  // kept as written (build_scene normalises): scene_to_json -> parse_scene is the identity
    const double norm = L.vector.norm();
    if (norm < 1e-12) fail(c, path + ".direction", "must not be the zero vector");
    if (!std::isfinite(norm)) fail(c, path + ".direction", "is too long to normalise");
  } else {
    L.direction = std::get<NamedDirection>(e.direction) == NamedDirection::InwardNormal
                      ? SceneLoad::Direction::InwardNormal
                      : SceneLoad::Direction::TowardsAtom;
  }
  if (e.atom && L.direction != SceneLoad::Direction::TowardsAtom)
    fail(c, path + ".atom", "applies only with direction \"towards_atom\"");
  L.target_atom = e.atom.value_or(-1);
  L.magnitude = e.magnitude;
  L.t_on = e.t_on;
  L.t_ramp = e.t_ramp;
  if (e.t_release) {
    L.t_release = *e.t_release;
    if (L.t_release < L.t_on)
      fail(c, path + ".t_release", cat("must be >= t_on (", L.t_release, " < ", L.t_on, ")"));
  }
  L.ramp_down = e.ramp_down;
  return L;
}

void parse_integrator_block(const Ctx& c, const json& j, StepSettings& s) {
  with_origin(c, [&] { params_from_json(j, "integrator", s); });  // physics/integrators.hpp
}

void parse_local(const Ctx& c, const json& j, Scene& scene) {
  LocalOptions& L = scene.local;
  if (j.is_boolean()) {
    L.enabled = j.get<bool>();
    return;
  }
  L.enabled = true;  // a "local" object means on unless it says "enabled": false
  with_origin(c, [&] { params_from_json(j, "local", L); });  // declared in sim/simulation.hpp
  if (j.contains("k_loc")) scene.local_k_from_body = false;
  L.use_body_stiffness = scene.local_k_from_body;
}

void parse_record(const Ctx& c, const json& j, Scene& scene) {
  SceneRecord& r = scene.record;
  with_origin(c, [&] { params_from_json(j, "record", r); });  // declared in scene.hpp
  for (std::size_t i = 0; i < r.key_times.size(); ++i)
    if (r.key_times[i] > scene.duration)
      fail(c, cat("record.key_times[", i, "]"),
           cat("must be within [0, duration = ", scene.duration, "] ms (got ", r.key_times[i], ")"));
}

}  // namespace

Scene parse_scene(const std::string& text, const fs::path& base_dir, const std::string& origin) {
  const Ctx c{origin, base_dir};
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    std::string what = e.what();
    if (const auto p = what.find("] "); p != std::string::npos) what = what.substr(p + 2);
    throw IoError(cat(origin, ": invalid JSON: ", what));
  } catch (const json::exception& e) {  // e.g. number overflow (1e999)
    std::string what = e.what();
    if (const auto p = what.find("] "); p != std::string::npos) what = what.substr(p + 2);
    throw InvalidInput(cat(origin, ": invalid JSON: ", what, " (numbers must be finite)"));
  }
  Scene s;
  Obj o(c, j, "");
  s.name = o.string("name", "");
  s.description = o.string("description", "");
  const json* model = o.get("model");
  if (!model) fail(c, "model", "is required");
  parse_model(c, *model, s.model);
  if (const json* loads = o.get("loads")) {
    if (!loads->is_array()) fail(c, "loads", "must be an array");
    for (std::size_t k = 0; k < loads->size(); ++k)
      s.loads.push_back(parse_load(c, (*loads)[k], cat("loads[", k, "]")));
  }
  if (const json* in = o.get("integrator")) parse_integrator_block(c, *in, s.step);
  if (const json* d = o.get("duration")) {
    s.duration = as_number(c, *d, "duration");
    if (!(s.duration > 0)) fail(c, "duration", cat("must be > 0 ms (got ", s.duration, ")"));
    if (s.duration / s.step.dt > 1e8) fail(c, "duration", "is more than 1e8 updates");
  }
  if (const json* l = o.get("local")) parse_local(c, *l, s);
  if (const json* r = o.get("record")) parse_record(c, *r, s);
  if (const json* t = o.get("tools")) s.tools = parse_scene_tools(t->dump(), base_dir, origin);
  if (const json* t = o.get("contact")) s.contact = parse_scene_contact(t->dump(), origin);
  o.finish();
  s.file = origin;
  if (s.name.empty()) s.name = fs::path(origin).stem().string();
  if (s.model.kind == ModelKind::Hybrid || s.model.kind == ModelKind::Smrm) {
    // A tree's atom count is known once it is built (scene/build.cpp checks its indices then).
    const Index na = s.model.source.all_branches ? std::numeric_limits<Index>::max() : s.model.atoms;
    for (std::size_t k = 0; k < s.record.atoms.size(); ++k)
      if (s.record.atoms[k] >= na)
        fail(c, cat("record.atoms[", k, "]"),
             cat("index ", s.record.atoms[k], " out of range [0, ", na, ")"));
    for (const SceneLoad& L : s.loads)
      if (L.target_atom >= na)
        fail(c, L.where + ".atom", cat("index ", L.target_atom, " out of range [0, ", na, ")"));
  } else if (!s.record.atoms.empty()) {
    fail(c, "record.atoms", "a surface model has no atoms");
  }
  return s;
}

Scene load_scene(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw IoError(cat(file.string(), ": cannot read the scene file (missing or unreadable)"));
  std::stringstream ss;
  ss << in.rdbuf();
  fs::path base = file.parent_path();
  if (base.empty()) base = ".";
  return parse_scene(ss.str(), fs::absolute(base).lexically_normal(), file.string());
}

}  // namespace medspring
