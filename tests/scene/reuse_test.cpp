// build_scene_reusing (scene/build.hpp): a scene built on the model of an earlier build resolves its
// loads and settings exactly as a fresh build does, and runs bit for bit the same.
#include <gtest/gtest.h>

#include "medspring/scene/build.hpp"
#include "medspring/scene/runner.hpp"
#include "medspring/scene/scene.hpp"

namespace medspring {
namespace {

const char* kKidney = R"({
  "model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
  "loads": [{"node": 223, "direction": "towards_atom", "atom": 21, "magnitude": 1.0, "t_release": 50}],
  "duration": 100, "record": {"atoms": [21]}
})";

const char* kKidneyOtherLoads = R"({
  "model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
  "loads": [{"node": 17, "direction": "inward_normal", "magnitude": 0.4},
            {"point": [0, 0, 30], "direction": "towards_atom", "magnitude": 0.2, "t_on": 10}],
  "integrator": {"dt": 0.25}, "duration": 60, "record": {"atoms": [3, 30], "nodes": [5]}
})";

const char* kVessel = R"({
  "model": {"kind": "smrm", "source": {"phantom": "vessel"}},
  "loads": [{"ring": 20, "spoke": 7, "direction": "towards_atom", "magnitude": 0.1}],
  "duration": 40, "local": true
})";

void expect_same_run(const BuiltScene& a, const BuiltScene& b) {
  ASSERT_EQ(a.loads.size(), b.loads.size());
  for (std::size_t k = 0; k < a.loads.size(); ++k) {
    EXPECT_EQ(a.loads[k].node, b.loads[k].node);
    EXPECT_EQ(a.loads[k].force, b.loads[k].force);  // exactly
    EXPECT_EQ(a.loads[k].t_on, b.loads[k].t_on);
  }
  EXPECT_EQ(a.trace_nodes, b.trace_nodes);
  EXPECT_EQ(a.trace_atom_dofs, b.trace_atom_dofs);
  EXPECT_EQ(a.atom_dof_begin, b.atom_dof_begin);
  EXPECT_EQ(a.dt_safe_rest, b.dt_safe_rest);
  const SceneResult ra = run_scene(a), rb = run_scene(b);
  EXPECT_EQ(ra.trace.max_disp, rb.trace.max_disp);  // bit for bit
  EXPECT_EQ(ra.trace.node_disp, rb.trace.node_disp);
  EXPECT_EQ(ra.trace.atom_disp, rb.trace.atom_disp);
  EXPECT_EQ(ra.summary.contact_hold_mm, rb.summary.contact_hold_mm);
  EXPECT_GT(ra.summary.max_disp_peak_mm, 0.0);
}

TEST(SceneReuse, OtherLoadsOnTheSameKidneyModelMatchAFreshBuild) {
  const BuiltScene base = build_scene(parse_scene(kKidney, ".", "a.json"), nullptr);
  const Scene other = parse_scene(kKidneyOtherLoads, ".", "b.json");
  const BuiltScene reused = build_scene_reusing(other, base);
  EXPECT_EQ(reused.body, base.body);  // the model is shared, not rebuilt
  expect_same_run(reused, build_scene(other, nullptr));
}

TEST(SceneReuse, VesselAtomsAndLocalPatchesMatchAFreshBuild) {
  const Scene s = parse_scene(kVessel, ".", "v.json");
  const BuiltScene base = build_scene(s, nullptr);
  expect_same_run(build_scene_reusing(s, base), build_scene(s, nullptr));
}

TEST(SceneReuse, LoadsTheModelCannotTakeAreStillRejectedWithTheirJsonPath) {
  const BuiltScene base = build_scene(parse_scene(kKidney, ".", "a.json"), nullptr);
  std::string text = kKidney;
  text.replace(text.find("223"), 3, "9999");
  try {
    build_scene_reusing(parse_scene(text, ".", "a.json"), base);
    FAIL() << "an out-of-range node was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("a.json: loads[0].node"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace medspring
