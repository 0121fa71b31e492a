// Scene runs in batches on the GPU (gpu/scene_batch.hpp, docs/gpu.md "Study runs on the GPU"): the study
// runner's --device cuda path gives the CPU scene runs' metrics. Skips without a device; the refusal of a
// model the GPU path lacks runs everywhere the backend is built.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "gpu_test_support.hpp"
#include "medspring/gpu/scene_batch.hpp"
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
  const std::vector<BatchRunResult> gpu = run_scene_batch(runs, gpu::scene_batch_stepper(), times);
  const std::vector<BatchRunResult> cpu = run_scene_batch(runs, make_cpu_batch_stepper, times);
  // The per-model synchronous copies give the same records as the whole-batch asynchronous readback.
  const std::vector<BatchRunResult> sync =
      run_scene_batch(runs, gpu::scene_batch_stepper({}, gpu::Readback::Sync), times);
  ::testing::Test::RecordProperty("gpu_batch_seconds", std::to_string(gpu[0].run_seconds));
  ::testing::Test::RecordProperty("cpu_batch_seconds", std::to_string(cpu[0].run_seconds));
  ::testing::Test::RecordProperty("gpu_sync_readback_batch_seconds", std::to_string(sync[0].run_seconds));
  ::testing::Test::RecordProperty("gpu_median_frame_us", std::to_string(gpu[0].summary.median_update_us));
  for (std::size_t i = 0; i < runs.size(); ++i) {
    SCOPED_TRACE(i);
    const RunSummary& g = gpu[i].summary;
    const RunSummary ref = run_scene(built[i]).summary;  // the CPU scene run (= cpu[i], bit for bit)
    EXPECT_EQ(cpu[i].summary.contact_hold_mm, ref.contact_hold_mm);
    EXPECT_EQ(sync[i].summary.contact_peak_mm, g.contact_peak_mm);
    EXPECT_EQ(sync[i].summary.max_disp_peak_mm, g.max_disp_peak_mm);
    EXPECT_EQ(sync[i].fields.back(), gpu[i].fields.back());
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
