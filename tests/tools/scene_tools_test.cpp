// "tools" in scene files (docs/tools.md): parsing, bad input with JSON paths, and runs of the two
// example scenes (examples/tools) with their force, torque, area, penetration and grasp traces.
#include "medspring/scene/scene_tools.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <optional>

#include "medspring/core/error.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/runner.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/sim/checkpoint.hpp"

namespace medspring {
namespace {

const std::filesystem::path kExamples = MEDSPRING_EXAMPLES_DIR;

std::string error_of(const std::string& tools_json) {
  const std::string text =
      R"({"model": {"kind": "hybrid", "source": {"phantom": "kidney"}}, "tools": )" + tools_json + "}";
  try {
    parse_scene(text, ".", "s.json");
  } catch (const InvalidInput& e) {
    return e.what();
  } catch (const IoError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SceneTools, ContactSubstepIsABooleanThatRoundTrips) {
  EXPECT_FALSE(parse_scene_contact("{}", "s.json").substep);  // default: held over the update
  const ContactSettings on = parse_scene_contact(R"({"substep": true})", "s.json");
  EXPECT_TRUE(on.substep);
  EXPECT_TRUE(parse_scene_contact(scene_contact_json(on), "s.json").substep);
  try {
    parse_scene_contact(R"({"substep": 1})", "s.json");
    FAIL() << "a number was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("s.json: contact.substep: must be true or false"), std::string::npos)
        << e.what();
  }
}

TEST(SceneTools, BadToolsAreNamedByTheirJsonPath) {
  auto has = [](const std::string& m, const std::string& part) {
    return m.find(part) != std::string::npos ? ::testing::AssertionSuccess()
                                             : ::testing::AssertionFailure() << m;
  };
  EXPECT_TRUE(
      has(error_of(R"([{"shape": "sphere", "radius": -1, "path": [{"t": 0, "position": [0, 0, 30]}]}])"),
          "s.json: tools[0].radius"));
  EXPECT_TRUE(
      has(error_of(R"([{"shape": "sphere", "radius": 0, "path": [{"t": 0, "position": [0, 0, 30]}]}])"),
          "tools[0].radius"));
  EXPECT_TRUE(has(error_of(R"([{"shape": "cube", "radius": 1, "path": [{"t": 0, "position": [0, 0, 30]}]}])"),
                  "tools[0].shape"));
  EXPECT_TRUE(has(error_of(R"([{"shape": "sphere", "radius": 1}])"), "needs exactly one of path"));
  EXPECT_TRUE(has(error_of(R"([{"shape": "sphere", "radius": 1, "path": [{"t": 0, "position": [0, 0]}]}])"),
                  "tools[0].path[0].position"));
  EXPECT_TRUE(has(error_of(R"([{"shape": "sphere", "radius": 1, "path": [{"t": 5, "position": [0, 0, 1]},
                                {"t": 5, "position": [0, 0, 1]}]}])"),
                  "tools[0].path[1].t: 5 ms is not after"));
  EXPECT_TRUE(has(error_of(R"([{"shape": "sphere", "radius": 1, "path": [{"t": 0, "position": [0, 0, 1],
                                "rotation": [0, 0, 0, 0]}]}])"),
                  "tools[0].path[0].rotation"));
  EXPECT_TRUE(has(error_of(R"([{"shape": "sphere", "radius": 1, "speed": 3, "path": []}])"),
                  "tools[0].speed: unknown key"));
  EXPECT_TRUE(has(error_of(R"([{"shape": "sphere", "radius": 1, "path_file": "/nonexistent.csv"}])"),
                  "/nonexistent.csv"));
}

TEST(SceneTools, ProbePressAndSlideTracesForceTorqueAreaAndPenetration) {
  const Scene scene = load_scene(kExamples / "probe_press_slide.json");
  ASSERT_EQ(scene.tools.size(), 1u);
  EXPECT_DOUBLE_EQ(scene.contact.friction, 0.2);
  const Scene again = parse_scene(scene_to_json(scene), ".", "round trip");  // what was run, re-read
  ASSERT_EQ(again.tools.size(), 1u);
  EXPECT_EQ(again.tools[0].path.size(), scene.tools[0].path.size());
  const BuiltScene b = build_scene(scene, nullptr);
  const SceneResult r = run_scene(b);
  ASSERT_EQ(r.trace.tools.size(), 1u);
  const SceneTrace::ToolTrace& t = r.trace.tools[0];
  ASSERT_EQ(t.fz.size(), r.trace.time.size());
  // while pressed and held (150-200 ms) the reaction pushes the probe back up, over an area
  for (Index q = 0; q < r.trace.size(); ++q) {
    const double time = r.trace.time[q];
    if (time >= 150 && time <= 200) {
      EXPECT_GT(t.fz[q], 0) << time;
      EXPECT_GT(t.area[q], 0) << time;
      EXPECT_LE(t.penetration[q], 0.05 * 8) << time;
    }
    if (time > 560) {
      EXPECT_EQ(t.fz[q], 0) << time;  // lifted off
    }
  }
  // friction resists the +x slide: the same run without friction has a larger fx while sliding
  Scene frictionless = scene;
  frictionless.contact.friction = 0;
  const SceneResult r0 = run_scene(build_scene(frictionless, nullptr));
  double fx = 0, fx0 = 0;
  for (Index q = 0; q < r.trace.size(); ++q)
    if (r.trace.time[q] > 260 && r.trace.time[q] < 380) {
      fx += t.fx[q];
      fx0 += r0.trace.tools[0].fx[q];
    }
  std::printf("slide: sum of fx with friction %.4f N, without %.4f N\n", fx, fx0);
  EXPECT_LT(fx, fx0 - 1e-3);
  EXPECT_EQ(r.summary.warnings, 0u);
}

TEST(SceneTools, GraspPullStretchesTheTissueAndReportsTheGraspForce) {
  const Scene scene = load_scene(kExamples / "grasp_pull.json");
  const BuiltScene b = build_scene(scene, nullptr);
  const SceneResult r = run_scene(b);
  const SceneTrace::ToolTrace& t = r.trace.tools[0];
  double grasp_hold = 0, grasp_after = 1;
  for (Index q = 0; q < r.trace.size(); ++q) {
    if (r.trace.time[q] >= 300 && r.trace.time[q] <= 500) grasp_hold = std::max(grasp_hold, t.grasp[q]);
    if (r.trace.time[q] > 600) grasp_after = std::min(grasp_after, t.grasp[q]);
  }
  EXPECT_GT(grasp_hold, 1e-3);
  EXPECT_EQ(grasp_after, 0.0);
  EXPECT_GT(r.summary.max_disp_peak_mm, 4.0);  // the pulled tissue stretched
  EXPECT_EQ(r.summary.warnings, 0u);
}

// A run with tools is checkpointed like any run: stopped while the grasper holds the tissue (and again
// while the probe slides), resumed from the checkpoint, it gives the same traces bit for bit.
TEST(SceneTools, RunsWithToolsResumeFromACheckpointBitForBit) {
  for (const char* file : {"grasp_pull.json", "probe_press_slide.json"}) {
    const Scene scene = load_scene(kExamples / file);
    const BuiltScene b = build_scene(scene, nullptr);
    const SceneResult full = run_scene(b);
    std::optional<Checkpoint> saved;
    RunHooks stop;
    stop.stop_at = std::string(file) == "grasp_pull.json" ? 400.0 : 300.0;  // grasping / sliding
    stop.on_checkpoint = [&](const Checkpoint& c) { saved = c; };
    const SceneResult first = run_scene(b, stop);
    ASSERT_TRUE(first.stopped) << file;
    ASSERT_TRUE(saved.has_value()) << file;
    // through the file format, as `medspring run --resume` does
    const Checkpoint back = decode_checkpoint(encode_checkpoint(*saved), "test");
    RunHooks resume;
    resume.resume = &back;
    const SceneResult rest = run_scene(b, resume);
    ASSERT_EQ(rest.trace.tools.size(), 1u);
    const auto& a = full.trace.tools[0];
    const auto& c = rest.trace.tools[0];
    ASSERT_EQ(c.fz.size(), a.fz.size()) << file;
    EXPECT_EQ(c.fx, a.fx) << file;
    EXPECT_EQ(c.fz, a.fz) << file;
    EXPECT_EQ(c.tz, a.tz) << file;
    EXPECT_EQ(c.penetration, a.penetration) << file;
    EXPECT_EQ(c.grasp, a.grasp) << file;
    EXPECT_EQ(rest.trace.max_disp, full.trace.max_disp) << file;
    EXPECT_EQ(rest.summary.final_max_disp_mm, full.summary.final_max_disp_mm) << file;
  }
  // a checkpoint of a run with tools does not resume a scene whose tools differ
  const Scene scene = load_scene(kExamples / "probe_press_slide.json");
  std::optional<Checkpoint> saved;
  RunHooks stop;
  stop.stop_at = 100;
  stop.on_checkpoint = [&](const Checkpoint& c) { saved = c; };
  run_scene(build_scene(scene, nullptr), stop);
  ASSERT_TRUE(saved.has_value());
  Scene other = scene;
  other.tools[0].tool.radius *= 2;
  RunHooks resume;
  resume.resume = &*saved;
  try {
    run_scene(build_scene(other, nullptr), resume);
    ADD_FAILURE() << "resumed with another tool";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("tools[0] differs"), std::string::npos) << e.what();
  }
  Scene none = scene;
  none.tools.clear();
  try {
    run_scene(build_scene(none, nullptr), resume);
    ADD_FAILURE() << "resumed without the tools";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("saved with 1 tools"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace medspring
