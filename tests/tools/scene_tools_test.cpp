// "tools" in scene files (docs/tools.md): parsing, bad input with JSON paths, and runs of the two
// example scenes (examples/tools) with their force, torque, area, penetration and grasp traces.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "medspring/core/error.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/runner.hpp"
#include "medspring/scene/scene.hpp"

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

}  // namespace
}  // namespace medspring
