// Scene runs in batches on the GPU (gpu/scene_batch.hpp, docs/gpu.md "Study runs on the GPU"): the study
// runner's --device cuda path gives the CPU scene runs' metrics. Skips without a device; the refusal of a
// model the GPU path lacks runs everywhere the backend is built.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "gpu_test_support.hpp"
#include "medspring/gpu/scene_batch.hpp"
#include "medspring/physics/trace_table.hpp"
#include "medspring/scene/runner.hpp"
#include "medspring/scene/scene.hpp"

namespace medspring {
namespace {

std::string press(double k_surf, int node, double magnitude) {
  return cat(R"({"name": "press", "model": {"kind": "hybrid", "source": {"phantom": "kidney"},
    "parameters": {"k_surf": )",
             k_surf, R"(}}, "loads": [{"node": )", node, R"(, "direction": "inward_normal", "magnitude": )",
             magnitude, R"(, "t_release": 150}], "duration": 300, "record": {"atoms": [21]}})");
}

TEST(GpuSceneBatch, KidneyPressesOnTheGpuGiveTheCpuSceneRunsMetrics) {
  std::string why;
  if (!have_device(&why)) GTEST_SKIP() << why;
  std::vector<BuiltScene> built;
  const std::vector<std::tuple<double, int, double>> cases{
      {0.05, 223, 1.0}, {0.08, 17, 0.5}, {0.03, 40, 0.8}, {0.05, 300, 1.2}};
  for (const auto& [k, node, f] : cases)
    built.push_back(build_scene(parse_scene(press(k, node, f), ".", "press.json"), nullptr));
  std::vector<const BuiltScene*> runs;
  for (const BuiltScene& b : built) runs.push_back(&b);
  const std::vector<double> times{100.0, 300.0};
  // The default: traces reduced on the device, positions back only for the field snapshots.
  const std::vector<BatchRunResult> gpu = run_scene_batch(runs, gpu::scene_batch_stepper(), times);
  const std::vector<BatchRunResult> cpu = run_scene_batch(runs, make_cpu_batch_stepper, times);
  // The per-model synchronous copies give the same records as the whole-batch asynchronous readback
  // (both sampled on the host), and the device's reduction the same to the norms' rounding.
  const std::vector<BatchRunResult> sync =
      run_scene_batch(runs, gpu::scene_batch_stepper({}, gpu::Readback::Sync), times);
  const std::vector<BatchRunResult> async =
      run_scene_batch(runs, gpu::scene_batch_stepper({}, gpu::Readback::Async), times);
  ::testing::Test::RecordProperty("gpu_batch_seconds", std::to_string(gpu[0].run_seconds));
  ::testing::Test::RecordProperty("cpu_batch_seconds", std::to_string(cpu[0].run_seconds));
  ::testing::Test::RecordProperty("gpu_sync_readback_batch_seconds", std::to_string(sync[0].run_seconds));
  ::testing::Test::RecordProperty("gpu_async_readback_batch_seconds", std::to_string(async[0].run_seconds));
  ::testing::Test::RecordProperty("gpu_median_frame_us", std::to_string(gpu[0].summary.median_update_us));
  for (std::size_t i = 0; i < runs.size(); ++i) {
    SCOPED_TRACE(i);
    const RunSummary& g = gpu[i].summary;
    const RunSummary ref = run_scene(built[i]).summary;  // the CPU scene run (= cpu[i], bit for bit)
    EXPECT_EQ(cpu[i].summary.contact_hold_mm, ref.contact_hold_mm);
    EXPECT_EQ(sync[i].summary.contact_peak_mm, async[i].summary.contact_peak_mm);
    EXPECT_EQ(sync[i].summary.max_disp_peak_mm, async[i].summary.max_disp_peak_mm);
    EXPECT_NEAR(g.contact_peak_mm, async[i].summary.contact_peak_mm,
                1e-12 * async[i].summary.contact_peak_mm);
    EXPECT_NEAR(g.max_disp_peak_mm, async[i].summary.max_disp_peak_mm,
                1e-12 * async[i].summary.max_disp_peak_mm);
    EXPECT_EQ(sync[i].fields.back(), gpu[i].fields.back());
    EXPECT_EQ(async[i].fields.back(), gpu[i].fields.back());
    EXPECT_EQ(g.substeps, ref.substeps);
    EXPECT_EQ(g.warnings, ref.warnings);
    const std::vector<std::pair<double, double>> metrics{{g.contact_peak_mm, ref.contact_peak_mm},
                                                         {g.contact_hold_mm, ref.contact_hold_mm},
                                                         {g.max_disp_peak_mm, ref.max_disp_peak_mm},
                                                         {g.atom_hold_mm, ref.atom_hold_mm},
                                                         {g.final_max_disp_mm, ref.final_max_disp_mm}};
    for (const auto& [got, want] : metrics) EXPECT_NEAR(got, want, 1e-9 * std::max(1.0, std::abs(want)));
    EXPECT_EQ(g.return_ms, ref.return_ms);  // a frame time: equal unless a displacement sits at 1e-3 mm
    for (std::size_t k = 0; k < times.size(); ++k)
      EXPECT_LT((gpu[i].fields[k] - cpu[i].fields[k]).cwiseAbs().maxCoeff(), 1e-9);
  }
}

// The device's trace reduction (Engine::request_traces: hd::trace_sample per model, src/gpu/sample.cu)
// against the host sampling (scene_trace_sample) of the same engine's positions, every frame of four
// presses with their own load nodes and traced points, in fp64 and fp32 (positions about each model's
// centre), on both kernels.
TEST(GpuSceneBatch, DeviceReducedTracesEqualTheHostSampledOnes) {
  REQUIRE_GPU();
  std::vector<BuiltScene> built;
  const std::vector<std::tuple<double, int, double>> cases{
      {0.05, 223, 1.0}, {0.08, 17, 0.5}, {0.03, 40, 0.8}, {0.05, 300, 1.2}};
  for (const auto& [k, node, f] : cases)
    built.push_back(build_scene(parse_scene(press(k, node, f), ".", "press.json"), nullptr));
  built[2].trace_nodes.push_back(5);  // models with different numbers of points: padded rows
  std::vector<const Model*> models;
  std::vector<TraceProbe> probes(built.size());
  for (std::size_t b = 0; b < built.size(); ++b) {
    models.push_back(&built[b].body->model());
    ASSERT_TRUE(trace_probe(built[b], probes[b]));
  }
  double worst = 0.0;
  std::size_t values = 0, exact = 0;
  for (const auto& [precision, kernel] : {std::pair{gpu::Precision::Double, gpu::Options::Kernel::Grid},
                                          {gpu::Precision::Float, gpu::Options::Kernel::Grid},
                                          {gpu::Precision::Double, gpu::Options::Kernel::PerBlock}}) {
    gpu::Options o;
    o.precision = precision;
    o.kernel = kernel;
    gpu::Engine e(models, built[0].settings.step, o);
    e.set_trace_probes(probes);
    ASSERT_EQ(e.trace_width(), 1 + 3);  // model 2: its load node, node 5, atom 21; the others 2 points
    std::vector<double> v;
    MatX3 f_ext, S;
    State st = make_state(*models[0]);
    for (int k = 0; k <= 400; ++k) {  // 200 ms: press, release at 150 ms, return
      if (k > 0) {
        for (std::size_t b = 0; b < built.size(); ++b)
          e.set_loads(static_cast<int>(b), frame_dof_loads(*built[b].body, built[b].loads, e.time(), f_ext));
        e.step();
      }
      e.request_traces();
      e.traces(v);
      ASSERT_EQ(v.size(), built.size() * 4);
      for (std::size_t b = 0; b < built.size(); ++b) {
        st.x = e.positions(static_cast<int>(b));
        built[b].body->map_to_surface(st, S);
        SceneTrace host;
        scene_trace_sample(built[b], e.time(), Vec3::Zero(), S, st.x, 0.0, host);
        std::vector<double> want{host.max_disp[0]};
        for (const auto& n : host.node_disp) want.push_back(n[0]);
        for (const auto& n : host.atom_disp) want.push_back(n[0]);
        want.resize(4, 0.0);  // padding
        for (std::size_t q = 0; q < want.size(); ++q) {
          const double got = v[b * 4 + q];
          ++values;
          exact += got == want[q] ? 1 : 0;
          const double d = std::abs(got - want[q]) / std::max(1e-12, std::abs(want[q]));
          worst = std::max(worst, d);
          ASSERT_LE(d, 1e-12) << "frame " << k << ", model " << b << ", value " << q << ": " << got << " vs "
                              << want[q];
        }
      }
    }
  }
  ::testing::Test::RecordProperty("values", std::to_string(values));
  ::testing::Test::RecordProperty("bit_identical", std::to_string(exact));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", worst);
  ::testing::Test::RecordProperty("max_relative_difference", buf);
}

// What the reduction saves: 512 presses (one model, their own load nodes) through the study's batch path,
// traces reduced on the device against the whole batch's positions back after every frame (sampled on
// the host). Records both times (no timed assertion); the records agree to the norms' rounding.
TEST(GpuSceneBatch, ReducedTracesAgainstTheWholeBatchReadback) {
  REQUIRE_GPU();
  std::vector<BuiltScene> built;
  built.reserve(512);
  built.push_back(build_scene(parse_scene(press(0.05, 0, 1.0), ".", "press.json"), nullptr));
  const Index surface = built[0].body->num_surface_nodes();
  for (int i = 1; i < 512; ++i)
    built.push_back(build_scene_reusing(
        parse_scene(press(0.05, static_cast<int>((37 * i) % surface), 0.5 + 0.001 * i), ".", "press.json"),
        built[0]));
  std::vector<const BuiltScene*> runs;
  for (const BuiltScene& b : built) runs.push_back(&b);
  const std::vector<double> times{150.0};
  const std::vector<BatchRunResult> red = run_scene_batch(runs, gpu::scene_batch_stepper(), times);
  const std::vector<BatchRunResult> all =
      run_scene_batch(runs, gpu::scene_batch_stepper({}, gpu::Readback::Async), times);
  ::testing::Test::RecordProperty("runs", "512");
  ::testing::Test::RecordProperty("frames", std::to_string(red[0].summary.updates));
  ::testing::Test::RecordProperty("device_reduced_batch_seconds", std::to_string(red[0].run_seconds));
  ::testing::Test::RecordProperty("whole_batch_readback_seconds", std::to_string(all[0].run_seconds));
  ::testing::Test::RecordProperty("device_reduced_median_frame_us",
                                  std::to_string(red[0].summary.median_update_us));
  ::testing::Test::RecordProperty("whole_batch_readback_median_frame_us",
                                  std::to_string(all[0].summary.median_update_us));
  for (std::size_t i = 0; i < runs.size(); ++i) {
    SCOPED_TRACE(i);
    const RunSummary &r = red[i].summary, &a = all[i].summary;
    EXPECT_EQ(r.substeps, a.substeps);
    EXPECT_NEAR(r.contact_peak_mm, a.contact_peak_mm, 1e-12 * a.contact_peak_mm);
    EXPECT_NEAR(r.max_disp_peak_mm, a.max_disp_peak_mm, 1e-12 * a.max_disp_peak_mm);
    EXPECT_NEAR(r.atom_hold_mm, a.atom_hold_mm, 1e-12 * a.atom_hold_mm);
    EXPECT_EQ(red[i].fields[0], all[i].fields[0]);
  }
}

TEST(GpuSceneBatch, RefusesAModelTheGpuPathLacksBeforeAnyDeviceWork) {
  const BuiltScene v = build_scene(parse_scene(R"({"model": {"kind": "smrm", "source": {"phantom": "vessel"}},
    "loads": [{"ring": 20, "spoke": 7, "direction": "towards_atom", "magnitude": 0.1}], "duration": 5})",
                                               ".", "v.json"),
                                   nullptr);
  try {
    run_scene_batch({&v}, gpu::scene_batch_stepper(), {});
    FAIL() << "no error";
  } catch (const gpu::GpuError& e) {
    EXPECT_NE(std::string(e.what()).find("CPU engine"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace medspring
