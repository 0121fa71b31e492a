// Scene runs in batches (scene/batch.hpp): what a batch engine receives (each model, its DOF loads frame
// by frame) is what the CPU scene run uses, and the batch path's traces and summary are run_scene's.
// The CPU reference stepper makes the whole batch path checkable without a GPU: it must give run_scene's
// metrics bit for bit; the GPU stepper is compared with it in python/tests/test_study_device.py.
#include "medspring/scene/batch.hpp"

#include <gtest/gtest.h>

#include "medspring/physics/loads.hpp"
#include "medspring/scene/runner.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring {
namespace {

// A press with ramp and release, a second load switched on later, and a traced atom.
const char* kPress = R"({
  "name": "press", "model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
  "loads": [{"node": 223, "direction": "towards_atom", "atom": 21, "magnitude": 1.0, "t_ramp": 10,
             "t_release": 40},
            {"node": 17, "direction": "inward_normal", "magnitude": 0.3, "t_on": 20, "t_release": 45}],
  "duration": 60, "record": {"atoms": [21], "nodes": [5]}
})";
// Same model, another load (shares the first run's model: build_scene_reusing).
const char* kOtherLoad = R"({
  "name": "press", "model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
  "loads": [{"node": 40, "direction": "inward_normal", "magnitude": 0.6, "t_release": 30}],
  "duration": 60, "record": {"atoms": [21], "nodes": [5]}
})";
// Another stiffness: another model of the same topology, same batch.
const char* kStiffer = R"({
  "name": "press", "model": {"kind": "hybrid", "source": {"phantom": "kidney"}, "parameters": {"k_surf": 0.08}},
  "loads": [{"node": 223, "direction": "towards_atom", "atom": 21, "magnitude": 0.8, "t_release": 35}],
  "duration": 60, "record": {"atoms": [21], "nodes": [5]}
})";
// Another frame duration: a batch of its own.
const char* kOtherDt = R"({
  "name": "press", "model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
  "loads": [{"node": 223, "direction": "towards_atom", "atom": 21, "magnitude": 0.5, "t_release": 30}],
  "integrator": {"dt": 0.25}, "duration": 60, "record": {"atoms": [21], "nodes": [5]}
})";

BuiltScene built(const char* text) {
  return build_scene(parse_scene(text, ".", "batch.json"), nullptr);
}

TEST(SceneBatch, FrameDofLoadsAreTheSimulationsExternalForces) {
  const BuiltScene b = built(kPress);
  Simulation sim(b.body, b.settings);
  sim.set_loads(b.loads);
  MatX3 work, f(b.body->model().num_nodes(), 3);
  int loaded_frames = 0;
  for (int k = 0; k < 120; ++k) {  // ramp, hold, second load on, releases
    const double t = sim.time();
    const std::vector<PointLoad> loads = frame_dof_loads(*b.body, b.loads, t, work);
    sim.update();  // fills state().f_ext with the loads at the frame start
    // The batch engine evaluates its loads at every substep of the frame: the same force at any time.
    for (const double ts : {t, t + 0.1, t + 0.5}) {
      accumulate_loads(loads, ts, f);
      ASSERT_EQ(f, sim.state().f_ext) << "frame " << k << " at " << ts << " ms";  // exactly
    }
    loaded_frames += loads.empty() ? 0 : 1;
  }
  EXPECT_EQ(loaded_frames, 89);  // t = 0.5 .. 44.5 ms: the ramp is 0 at t = 0, the second release at 45
}

TEST(SceneBatch, CpuBatchEqualsTheSceneRunsBitForBit) {
  const BuiltScene a = built(kPress);
  const BuiltScene b = build_scene_reusing(parse_scene(kOtherLoad, ".", "b.json"), a);
  const BuiltScene c = built(kStiffer);
  const BuiltScene d = built(kOtherDt);
  ASSERT_NE(a.body, c.body);
  EXPECT_EQ(batch_key(a), batch_key(c));
  EXPECT_NE(batch_key(a), batch_key(d));
  const std::vector<const BuiltScene*> runs{&a, &d, &b, &c};
  const std::vector<double> times{0.0, 25.0, 60.0};

  std::vector<std::vector<const Model*>> groups;  // what each stepper was made for
  const BatchStepperFactory spy = [&](const std::vector<const BuiltScene*>& g) {
    groups.emplace_back();
    for (const BuiltScene* s : g) groups.back().push_back(&s->body->model());
    return make_cpu_batch_stepper(g);
  };
  const std::vector<BatchRunResult> r = run_scene_batch(runs, spy, times);
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0], (std::vector<const Model*>{&a.body->model(), &b.body->model(), &c.body->model()}));
  EXPECT_EQ(groups[1], (std::vector<const Model*>{&d.body->model()}));
  ASSERT_EQ(r.size(), 4u);
  EXPECT_EQ(r[1].group, 1);
  EXPECT_EQ(r[2].group_size, 3);

  for (std::size_t i = 0; i < runs.size(); ++i) {
    SCOPED_TRACE(i);
    BuiltScene one = *runs[i];
    one.scene.record.frames = true;  // frames at the field times, as SceneRunner asks
    one.scene.record.every = 1 << 30;
    one.scene.record.key_times = times;
    std::vector<double> ft;
    std::vector<MatX3> fields;
    RunHooks hooks;
    hooks.on_frame = [&](const Simulation& sim, const RecordedFrame& f) {
      ft.push_back(f.time);
      fields.push_back(sim.surface() - one.body->rest_surface());
    };
    const SceneResult cpu = run_scene(one, hooks);
    const RunSummary& s = r[i].summary;
    EXPECT_EQ(s.updates, cpu.summary.updates);
    EXPECT_EQ(s.substeps, cpu.summary.substeps);
    EXPECT_EQ(s.warnings, cpu.summary.warnings);
    EXPECT_EQ(s.contact_peak_mm, cpu.summary.contact_peak_mm);  // bit for bit
    EXPECT_EQ(s.contact_hold_mm, cpu.summary.contact_hold_mm);
    EXPECT_EQ(s.max_disp_peak_mm, cpu.summary.max_disp_peak_mm);
    EXPECT_EQ(s.atom_hold_mm, cpu.summary.atom_hold_mm);
    EXPECT_EQ(s.local_hold_mm, cpu.summary.local_hold_mm);
    EXPECT_EQ(s.return_ms, cpu.summary.return_ms);
    EXPECT_EQ(s.final_max_disp_mm, cpu.summary.final_max_disp_mm);
    EXPECT_EQ(s.release_time, cpu.summary.release_time);
    EXPECT_GT(s.contact_peak_mm, 0.1);
    ASSERT_EQ(r[i].fields.size(), times.size());
    for (std::size_t k = 0; k < times.size(); ++k) {
      std::size_t j = 0;  // SceneRunner's choice: the first recorded frame reaching the time
      while (j + 1 < ft.size() && ft[j] < times[k] - 1e-9) ++j;
      EXPECT_EQ(r[i].field_times[k], ft[j]);
      EXPECT_EQ(r[i].fields[k], fields[j]);
    }
  }
}

TEST(SceneBatch, RefusesWhatTheBatchPathDoesNotRun) {
  BuiltScene a = built(kPress);
  a.settings.local.enabled = true;
  try {
    run_scene_batch({&a}, make_cpu_batch_stepper, {});
    FAIL() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("local deformation overlay"), std::string::npos) << e.what();
  }
  const BuiltScene b = built(kPress);
  EXPECT_THROW(run_scene_batch({&b}, make_cpu_batch_stepper, {70.0}), InvalidInput);  // past the duration
  EXPECT_EQ(batch_unsupported(b), "");
}

}  // namespace
}  // namespace medspring
