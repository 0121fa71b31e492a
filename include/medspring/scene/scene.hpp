// Scene files (docs/scenes.md): one JSON document that says which organ model to build and from what,
// the loads on it, the integrator, the duration, local deformation and what to record.
//
//   Scene scene = load_scene("scenes/kidney_1.0N_nonlinear.json");   // parsed, validated, paths resolved
//   BuiltScene built = build_scene(scene, &loader);                    // scene/build.hpp
//   SceneResult r = run_scene(built, hooks);                           // scene/runner.hpp
//
// Errors are InvalidInput (or IoError for an unreadable file) with one line naming the scene file and
// the JSON path at fault: "kidney.json: loads[1].magnitude: must be finite (got inf)". Unknown keys are
// errors too ("model.parameters.k_srf: unknown key (expected one of ...)"). The JSON parser
// (nlohmann_json) is private to this layer's source: this header uses only engine types.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "medspring/core/params.hpp"
#include "medspring/core/types.hpp"
#include "medspring/core/units.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/tissue.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/scene/scene_tools.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring {

/// The three model kinds (DESIGN.md): plain surface mass-spring, hybrid (surface + atoms), SMRM vessel.
enum class ModelKind { Surface, Hybrid, Smrm, Volumetric };
ModelKind parse_model_kind(const std::string& text);  // "surface" | "hybrid" | "smrm" | "volumetric"
std::string to_string(ModelKind kind);

/// Where the geometry of a model comes from: exactly one of a phantom, a mesh, a segmentation or a
/// centerline (an SMRM centerline may add a boundary mesh for marched spokes, §5.6).
struct ModelSource {
  enum class Type { Phantom, Mesh, Segmentation, Centerline };
  Type type = Type::Phantom;

  // Phantoms (§1.1, §8.0): "kidney" (458 nodes; hybrid atoms of §4.1), "tube" (structured tube of
  // rings x spokes), "vessel" (SMRM phantom of §8.0).
  std::string phantom = "kidney";
  VesselPath path = VesselPath::StraightX;                        // vessel phantom centerline
  CrossSectionShape cross_section = CrossSectionShape::Circular;  // vessel phantom cross-section
  Index rings = 40, spokes = 30;                                  // tube phantom
  double spacing = 2.5, radius = 3.0;                             // tube phantom, mm

  // Mesh: a closed triangle surface (absolute path after parsing); for an SMRM centerline source, an
  // optional boundary that the spokes are marched to.
  std::filesystem::path mesh;
  LengthUnit mesh_unit = LengthUnit::Millimetre;

  // Segmentation: a label volume (spacing in mm from the file) and the label of the organ.
  std::filesystem::path segmentation;
  std::int32_t label = 1;

  // Centerline: polylines with radii (.vtp / .vtk), one branch, optionally an arc-length window.
  std::filesystem::path centerline;
  LengthUnit centerline_unit = LengthUnit::Millimetre;
  Index branch = 0;
  bool all_branches = false;   // "branches": "all": every polyline, merged into a vessel tree (smrm)
  bool blend = false;          // "blend": true: the tree's one watertight surface (docs/vessels.md)
  double blend_spacing = 0.0;  // "blend_spacing_mm": ring spacing of its path tubes (0 = atom spacing)
  std::string radius_array = "MaximumInscribedSphereRadius";
  double range_start = 0.0;                                    // mm of arc length from the first point
  double range_end = std::numeric_limits<double>::infinity();  // mm (inf = to the end)
};

/// The model of a scene: kind, source and parameters (defaults of ALGORITHMS.md §9).
struct SceneModel {
  ModelKind kind = ModelKind::Hybrid;
  ModelSource source;
  bool nonlinear = true;      // D-4: every inter-node spring Duffing (false: all linear)
  Index surface_nodes = 0;    // > 0: remesh a mesh/segmentation surface to exactly this many nodes
                              // (balloon, §4.4); 0: use the surface as read
  Index atoms = 0;            // centerline atoms; 0 = kind default (hybrid 42, smrm 40)
  HybridSettings hybrid;      // kind "hybrid" (nonlinear copied in by the parser)
  SurfaceBodyParams surface;  // kind "surface" (duffing.mode Linear when not nonlinear)
  SmrmSettings smrm;          // kind "smrm" (chain.nonlinear copied in by the parser)
  /// Kind "volumetric" (issue 23): E, nu from "material"; the node count aimed at is "nodes" (mesh_nodes).
  VolumetricSettings volumetric;
  // "material": a preset name or {"E_kPa", "nu"} (or {"preset"}): resolved by the parser to the calibrated
  // stiffnesses of the kind (models/tissue.hpp) before "parameters", which override them.
  std::optional<TissueMaterial> material;
};

/// A point force of a scene, before it is resolved on the built model (build_scene).
struct SceneLoad {
  enum class Pick { Node, Point, RingSpoke };
  enum class Direction { Vector, InwardNormal, TowardsAtom };
  Pick pick = Pick::Node;
  Index node = 0;             // Pick::Node: surface node index
  Vec3 point = Vec3::Zero();  // Pick::Point: the surface node nearest to this point (mm) is loaded
  Index ring = 0, spoke = 0;  // Pick::RingSpoke: node ring * spokes + spoke of a structured grid
  Direction direction = Direction::InwardNormal;
  Vec3 vector = Vec3::Zero();  // Direction::Vector, as written (normalised by build_scene)
  Index target_atom = -1;      // Direction::TowardsAtom on a hybrid: atom (-1 = the middle atom)
  double magnitude = 0.0;      // N
  double t_on = 0.0;           // ms
  double t_ramp = 20.0;        // ms
  double t_release = std::numeric_limits<double>::infinity();  // ms (inf = never)
  bool ramp_down = false;                                      // release over t_ramp instead of instantly
  std::string where;                                           // JSON path, "loads[k]", for messages
};

/// A direction given by name in a load: "inward_normal" or "towards_atom".
enum class NamedDirection { InwardNormal, TowardsAtom };
std::string to_string(NamedDirection d);
NamedDirection parse_enum(const std::string& text, NamedDirection*);

/// One entry of "loads" as a scene file writes it; parse_scene resolves it to a SceneLoad (exactly one
/// of node, point, ring + spoke; atom only with "towards_atom"; t_release >= t_on).
struct LoadEntry {
  std::optional<Index> node, ring, spoke;
  std::optional<Vec3> point;
  std::variant<Vec3, NamedDirection> direction = NamedDirection::InwardNormal;
  std::optional<Index> atom;
  double magnitude = 0.0, t_on = 0.0, t_ramp = 20.0;
  std::optional<double> t_release;
  bool ramp_down = false;
};

/// The declaration of LoadEntry (core/params.hpp): the keys of each entry of "loads", the table in
/// docs/parameters.md.
template <ParamOf<LoadEntry> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"node", "", "the surface node loaded (give node, point or ring + spoke)"}.nonnegative(),
    s.node);
  v(ParamSpec{"point", "mm", "the surface node nearest to this point is loaded"}, s.point);
  v(ParamSpec{"ring", "", "ring of a structured grid (tube phantom; with spoke): node ring * spokes + spoke"}
        .nonnegative(),
    s.ring);
  v(ParamSpec{"spoke", "", "spoke of a structured grid (with ring)"}.nonnegative(), s.spoke);
  v(ParamSpec{"direction", "", "[x, y, z] (normalised), inward_normal or towards_atom"}.required(),
    s.direction);
  v(ParamSpec{"atom", "", "towards_atom: the atom pulled towards (null: the middle atom)"}.nonnegative(),
    s.atom);
  v(ParamSpec{"magnitude", "N", "force"}.nonnegative().required().unit_in_messages(), s.magnitude);
  v(ParamSpec{"t_on", "ms", "time the force starts"}.nonnegative(), s.t_on);
  v(ParamSpec{"t_ramp", "ms", "linear ramp up (and down, with ramp_down)"}.nonnegative(), s.t_ramp);
  v(ParamSpec{"t_release", "ms", "time the force is released (null: never); >= t_on"}.nonnegative(),
    s.t_release);
  v(ParamSpec{"ramp_down", "", "release over t_ramp instead of instantly"}, s.ramp_down);
}

/// What a run records besides the per-frame traces (which cover every frame).
struct SceneRecord {
  Index every = 10;               // write a surface frame every N updates (and the first and last)
  std::vector<double> key_times;  // ms: frames also written at the first update reaching each time
  std::vector<Index> nodes;       // surface nodes whose displacement is traced (load nodes always are)
  std::vector<Index> atoms;       // atoms whose displacement is traced (hybrid, smrm)
  bool frames = true;             // write surface frames (.vtp + .pvd); false: traces only
};

/// The declaration of SceneRecord (core/params.hpp): the scene's "record" block, `run --set
/// record.NAME=VALUE`, the table in docs/parameters.md.
template <ParamOf<SceneRecord> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"every", "", "write a surface frame every N updates (and the first and last)"}.at_least(1),
    s.every);
  v(ParamSpec{"frames", "", "write surface frames (.vtp + .pvd); false: traces only"}, s.frames);
  v(ParamSpec{"key_times", "ms", "frames also written at the first update reaching each time (<= duration)"}
        .nonnegative(),
    s.key_times);
  v(ParamSpec{"nodes", "", "surface nodes whose displacement is traced (load nodes always are)"}, s.nodes);
  v(ParamSpec{"atoms", "", "atoms whose displacement is traced (hybrid, smrm)"}, s.atoms);
}

struct Scene {
  std::string name;            // default: the file name without extension
  std::string description;     // free text
  std::filesystem::path file;  // the scene file (parse_scene: its `origin`); prefixes every message
  SceneModel model;
  std::vector<SceneLoad> loads;
  StepSettings step;              // "integrator": method, dt, substep, safety
  double duration = 1000.0;       // ms
  LocalOptions local;             // "local": eq. (6) overlay
  bool local_k_from_body = true;  // k_loc not given: the body's (kidney k_surf, vessel 0.05 N/mm)
  SceneRecord record;
  std::vector<SceneTool> tools;  // "tools": rigid instruments with pose paths (docs/tools.md)
  ContactSettings contact;       // "contact": their contact response (dt, min_mass from the model)
};

/// Reads, parses and validates a scene file. Relative file names inside it are resolved against the
/// scene file's folder; "${MEDSPRING_DATA}" expands to $MEDSPRING_DATA (or the build's data folder).
/// Every referenced file must exist. Throws IoError (unreadable file, invalid JSON with line and
/// column) or InvalidInput ("<file>: <json.path>: <problem>").
Scene load_scene(const std::filesystem::path& file);

/// Parses a scene from JSON text; `base_dir` resolves relative paths, `origin` prefixes messages.
Scene parse_scene(const std::string& json_text, const std::filesystem::path& base_dir,
                  const std::string& origin = "scene");

/// The scene as JSON text with every default filled in (what was run), 2-space indented.
std::string scene_to_json(const Scene& scene);

/// The data folder used for "${MEDSPRING_DATA}": $MEDSPRING_DATA when set and non-empty, else the
/// folder configured at build time.
std::filesystem::path scene_data_dir();

}  // namespace medspring
