// Scene -> JSON (scene_to_json): the scene with every default filled in, as `medspring run` writes it
// beside its output (docs/scenes.md). Split from scene.cpp (the reader).
#include <cmath>
#include <nlohmann/json.hpp>

#include "medspring/core/check.hpp"
#include "medspring/medial/frames.hpp"
#include "medspring/physics/parallel.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/scene/scene_tools.hpp"
#include "params_json.hpp"

namespace medspring {

using json = nlohmann::json;

namespace {

json vec_json(const Vec3& v) {
  return json::array({v.x(), v.y(), v.z()});
}

}  // namespace

std::string scene_to_json(const Scene& s) {
  const ModelSource& src = s.model.source;
  json source;
  auto tree_keys = [&](json& obj) {  // a vessel tree (docs/vessels.md)
    if (!src.all_branches) return;
    obj["branches"] = "all";
    obj["blend"] = src.blend;
    if (src.blend && src.blend_spacing > 0) obj["blend_spacing_mm"] = src.blend_spacing;
  };
  switch (src.type) {
    case ModelSource::Type::Phantom: {
      json p = {{"name", src.phantom}};
      if (src.phantom == "tube")
        p.update(
            {{"rings", src.rings}, {"spokes", src.spokes}, {"spacing", src.spacing}, {"radius", src.radius}});
      if (src.phantom == "vessel")
        p.update({{"path", to_string(src.path)}, {"cross_section", to_string(src.cross_section)}});
      source["phantom"] = p;
      break;
    }
    case ModelSource::Type::Mesh:
      break;
    case ModelSource::Type::Segmentation:
      source["segmentation"] = {{"file", src.segmentation.string()}, {"label", src.label}};
      tree_keys(source["segmentation"]);
      break;
    case ModelSource::Type::Centerline: {
      json cl = {{"file", src.centerline.string()},
                 {"unit", to_string(src.centerline_unit)},
                 {"branch", src.branch},
                 {"radius_array", src.radius_array}};
      if (src.all_branches) cl.erase("branch");
      tree_keys(cl);
      if (src.range_start > 0 || std::isfinite(src.range_end))
        cl["range_mm"] = {src.range_start,
                          std::isfinite(src.range_end) ? json(src.range_end) : json(nullptr)};
      source["centerline"] = cl;
      break;
    }
  }
  if (!src.mesh.empty()) {
    source["mesh"] = {{"file", src.mesh.string()}, {"unit", to_string(src.mesh_unit)}};
    if (src.type == ModelSource::Type::Mesh) tree_keys(source["mesh"]);
  }

  json params;
  const SceneModel& m = s.model;
  if (m.kind == ModelKind::Hybrid) {
    params = params_to_json(m.hybrid);
  } else if (m.kind == ModelKind::Surface) {
    params = params_to_json(m.surface);
  } else if (m.kind == ModelKind::Volumetric) {
    const VolumetricSettings& v = m.volumetric;
    params = {{"nodes", m.volumetric_nodes},
              {"density", v.density},
              {"beta", v.beta},
              {"spring_scale", v.spring_scale},
              {"volume_scale", v.volume_scale},
              {"compression", v.compression},
              {"mass_scaling_dt", v.mass_scaling_dt},
              {"duffing", params_to_json(v.duffing)},
              {"fixed", v.fixed}};
    if (v.return_k) params["k_r"] = *v.return_k;
  } else {
    params = params_to_json(m.smrm);
    if (m.smrm.bending != BendingMode::Constant) params.erase("k_b");
  }
  json model = {{"kind", to_string(m.kind)},
                {"source", source},
                {"nonlinear", m.nonlinear},
                {"surface_nodes", m.surface_nodes},
                {"parameters", params}};
  if (m.kind != ModelKind::Surface && m.kind != ModelKind::Volumetric) model["atoms"] = m.atoms;
  if (m.kind == ModelKind::Volumetric && !m.material)  // E and nu are the model's parameters
    model["material"] = {{"E_kPa", m.volumetric.E_kPa}, {"nu", m.volumetric.nu}};
  if (m.material) {
    if (!m.material->preset.empty())
      model["material"] = m.material->preset;
    else
      model["material"] = {{"E_kPa", m.material->E_kPa}, {"nu", m.material->nu}};
  }

  json loads = json::array();
  for (const SceneLoad& L : s.loads) {
    json l;
    if (L.pick == SceneLoad::Pick::Node) l["node"] = L.node;
    if (L.pick == SceneLoad::Pick::Point) l["point"] = vec_json(L.point);
    if (L.pick == SceneLoad::Pick::RingSpoke) l.update({{"ring", L.ring}, {"spoke", L.spoke}});
    if (L.direction == SceneLoad::Direction::Vector) l["direction"] = vec_json(L.vector);
    if (L.direction == SceneLoad::Direction::InwardNormal) l["direction"] = "inward_normal";
    if (L.direction == SceneLoad::Direction::TowardsAtom) {
      l["direction"] = "towards_atom";
      if (L.target_atom >= 0) l["atom"] = L.target_atom;
    }
    l.update({{"magnitude", L.magnitude},
              {"t_on", L.t_on},
              {"t_ramp", L.t_ramp},
              {"t_release", std::isfinite(L.t_release) ? json(L.t_release) : json(nullptr)},
              {"ramp_down", L.ramp_down}});
    loads.push_back(l);
  }
  json local = params_to_json(s.local);
  if (s.local_k_from_body) local.erase("k_loc");
  json j = {{"name", s.name},
            {"description", s.description},
            {"model", model},
            {"loads", loads},
            {"integrator", params_to_json(s.step)},
            {"duration", s.duration},
            {"local", local},
            {"record",
             {{"every", s.record.every},
              {"frames", s.record.frames},
              {"key_times", s.record.key_times},
              {"nodes", s.record.nodes},
              {"atoms", s.record.atoms}}}};
  if (!s.tools.empty()) {
    j["tools"] = json::parse(scene_tools_json(s.tools));
    j["contact"] = json::parse(scene_contact_json(s.contact));
  }
  return j.dump(2);
}

}  // namespace medspring
