// What the study's files share (not installed): one scene run and its facts, and small helpers.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "medspring/models/smrm_tree.hpp"
#include "medspring/paper/study.hpp"
#include "medspring/paper/timing.hpp"

namespace medspring::paper::detail {

namespace fs = std::filesystem;
using json = nlohmann::json;

// The frame shown as "force on": the last recorded before the release at 500 ms (the frame at 500 ms
// already shows the force released, and with it the local dent gone).
constexpr double kHold = 495.0;

/// One scene run of the study, with what the figures need.
struct SceneRun {
  Experiment e;
  std::string set;  // "real" | "phantom"
  Scene scene;
  fs::path dir;     // absolute, inside the output folder
  std::string rel;  // relative to the output folder
  json summary;
  Vec3 contact = Vec3::Zero();  // rest position of the loaded node, mm
  Vec3 dir_force = Vec3::UnitZ();
  Vec3 axis = Vec3::UnitX();     // long axis (first to last atom)
  Vec3 tangent = Vec3::UnitX();  // tangent at the loaded atom (vessel)
  Vec3 center = Vec3::Zero();
  double size = 1.0;    // bounding-box diagonal of the rest surface, mm
  double radius = 1.0;  // vessel: radius at the contact (spoke length), mm
  std::vector<std::string> notes;
  json model_facts = json::object();  // hybrid: spokes and the visibility filter (D-9)
};

/// Fills the geometric facts of a run from its built scene (contact, force direction, size, axis).
void record_geometry(SceneRun& r, const BuiltScene& built);

const SceneRun& find_run(const std::vector<SceneRun>& runs, const std::string& set, const std::string& file);

/// The phantom tree (a trunk and a branch, mm) and the tree scene of the study's tree runs.
std::vector<Centerline> phantom_tree_lines();
/// blend: the tree's watertight surface ("blend": true; a loader with CGAL), else one tube per branch.
std::string tree_scene_json(const std::string& name, const fs::path& file, const std::string& unit,
                            Index node, Index atom, double force, Index every, bool blend = false);

/// The whole vessel tree (issue 17): light and strong force on the arch and on a branch. Returns the
/// tree's facts (tables.json "tree") and appends the runs.
json run_tree(const StudyOptions& o, StudyHost& host, const std::string& primary, const fs::path& root,
              std::vector<SceneRun>& tree_runs);

/// Tables I and II as JSON (tables.json): every case, the table cells and the ordering checks.
json tables_json(const std::vector<TimedCase>& timed, const TimingProtocol& p, const std::string& machine);

/// Renders the key frames and plots into root/figures (python3 with VTK and matplotlib).
void make_figures(const StudyOptions& o, const fs::path& root, const std::string& primary,
                  const std::vector<SceneRun>& runs, const std::vector<SceneRun>& tree_runs,
                  const json& cases);

/// The facts of the report (results.json) besides the runs and tables.
json parameters_json(const SceneRun& kidney, const SceneRun& vessel);

std::string cpu_name();
std::string now_utc();
void write_text(const fs::path& file, const std::string& text);
json vec(const Vec3& v);

}  // namespace medspring::paper::detail
