// The batch path's per-frame traces reduced by the stepper (docs/gpu.md, "Study runs on the GPU"): the
// values hd::trace_sample computes -- the code the GPU's reduction kernel runs (src/gpu/sample.cu) -- on
// a CPU-run batch equal the host sampling (scene_trace_sample) of the same positions, and the runner's
// reduced path gives the host-sampled summaries with positions read only for the field snapshots.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "medspring/physics/trace_table.hpp"
#include "medspring/scene/batch.hpp"
#include "medspring/scene/runner.hpp"
#include "medspring/scene/scene.hpp"

namespace medspring {
namespace {

// Hybrid kidney presses of one batch (same topology): other load nodes, a recorded node, a traced atom.
const char* kPress = R"({
  "name": "press", "model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
  "loads": [{"node": 223, "direction": "towards_atom", "atom": 21, "magnitude": 1.0, "t_ramp": 10,
             "t_release": 40},
            {"node": 17, "direction": "inward_normal", "magnitude": 0.3, "t_on": 20, "t_release": 45}],
  "duration": 60, "record": {"atoms": [21], "nodes": [5]}
})";
const char* kOther = R"({
  "name": "press", "model": {"kind": "hybrid", "source": {"phantom": "kidney"}, "parameters": {"k_surf": 0.08}},
  "loads": [{"node": 40, "direction": "inward_normal", "magnitude": 0.6, "t_release": 30}],
  "duration": 60, "record": {"atoms": [21, 30]}
})";
const char* kSurface = R"({
  "name": "press", "model": {"kind": "surface", "source": {"phantom": "kidney"}},
  "loads": [{"node": 100, "direction": "inward_normal", "magnitude": 0.4, "t_release": 30}],
  "duration": 60, "record": {"nodes": [7]}
})";

BuiltScene built(const char* text) {
  return build_scene(parse_scene(text, ".", "batch.json"), nullptr);
}

double rel(double got, double want) {
  return std::abs(got - want) / std::max(1e-300, std::abs(want));
}

// The CPU reference stepper, its traces reduced with hd::trace_sample on the host (what the GPU stepper
// does on the device); counts the position reads the runner makes.
class ReducingCpuStepper final : public BatchStepper {
 public:
  explicit ReducingCpuStepper(const std::vector<const BuiltScene*>& g)
      : inner_(make_cpu_batch_stepper(g)), nodes_(g.front()->body->model().num_nodes()) {}
  void set_loads(int b, const std::vector<PointLoad>& loads) override { inner_->set_loads(b, loads); }
  void step() override { inner_->step(); }
  void positions(int b, MatX3& x) override {
    ++position_reads;
    inner_->positions(b, x);
  }
  double time(int b) const override { return inner_->time(b); }
  std::uint64_t substeps(int b) const override { return inner_->substeps(b); }
  std::uint64_t warnings(int b) const override { return inner_->warnings(b); }
  bool set_trace_probes(const std::vector<TraceProbe>& probes) override {
    table_ = make_trace_table(probes, nodes_);
    return true;
  }
  void trace_values(std::vector<double>& out) override {
    const auto W = static_cast<std::size_t>(table_.width());
    out.assign(static_cast<std::size_t>(table_.batch) * W, 0.0);
    MatX3 x;
    for (int b = 0; b < table_.batch; ++b) {
      inner_->positions(b, x);
      trace_values(table_, b, x, out.data() + static_cast<std::size_t>(b) * W);
    }
  }
  inline static int position_reads = 0;

 private:
  using BatchStepper::trace_values;
  static void trace_values(const TraceTableData& t, int b, const MatX3& x, double* out) {
    medspring::trace_values(t, b, x, out);
  }
  std::unique_ptr<BatchStepper> inner_;
  Index nodes_;
  TraceTableData table_;
};

TEST(SceneBatchTraces, ProbeIsTheSurfaceRowsAndTheTracedPoints) {
  const BuiltScene a = built(kPress), c = built(kOther);
  TraceProbe p, q;
  ASSERT_TRUE(trace_probe(a, p));
  ASSERT_TRUE(trace_probe(c, q));
  const Model& m = a.body->model();
  State st = make_state(m);
  st.x = m.x0;
  MatX3 S;
  a.body->map_to_surface(st, S);
  ASSERT_EQ(static_cast<Index>(p.surface_dof.size()), S.rows());
  for (Index s = 0; s < S.rows(); ++s)
    EXPECT_EQ(S.row(s), m.x0.row(p.surface_dof[static_cast<std::size_t>(s)]));
  EXPECT_EQ(p.surface_rest, a.body->rest_surface());
  ASSERT_EQ(p.point_dof.size(), a.trace_nodes.size() + a.trace_atom_dofs.size());  // 223, 17, 5; atom 21
  EXPECT_EQ(p.point_dof.size(), 4u);
  EXPECT_EQ(p.point_dof.back(), a.trace_atom_dofs[0]);
  EXPECT_EQ(p.point_rest.row(3), m.x0.row(a.trace_atom_dofs[0]));
  // One mesh: the surface is stored once; the points padded to the most a model has.
  const TraceTableData t = make_trace_table({p, q, p}, m.num_nodes());
  EXPECT_EQ(t.dof_stride, 0);
  EXPECT_EQ(t.surface_dof.size(), p.surface_dof.size());
  EXPECT_EQ(t.points, 4);
  EXPECT_EQ(t.point_dof[4 + 3], -1);  // model 1: load node 40, atoms 21 and 30
  // An SMRM vessel's surface is rebuilt from its atoms, not a selection of DOF rows: no probe.
  const BuiltScene v = build_scene(parse_scene(R"({"model": {"kind": "smrm", "source": {"phantom": "vessel"}},
    "loads": [{"ring": 20, "spoke": 7, "direction": "towards_atom", "magnitude": 0.1}], "duration": 5})",
                                               ".", "v.json"),
                                   nullptr);
  TraceProbe w;
  EXPECT_FALSE(trace_probe(v, w));
  EXPECT_THROW(make_trace_table({p, TraceProbe{}}, m.num_nodes()), InvalidInput);  // other surface size
}

// hd::trace_sample (the device's code, run here on the CPU) on every frame of a CPU-run batch against
// scene_trace_sample of the same positions: hybrid and surface kidneys, presses with ramp and release.
TEST(SceneBatchTraces, HdTraceSampleEqualsTheHostSamplingOnACpuBatch) {
  const BuiltScene a = built(kPress), c = built(kOther), s = built(kSurface);
  std::size_t values = 0, exact = 0;
  double worst = 0.0;
  for (const std::vector<const BuiltScene*>& g :
       {std::vector<const BuiltScene*>{&a, &c}, std::vector<const BuiltScene*>{&s}}) {
    std::unique_ptr<BatchStepper> stepper = make_cpu_batch_stepper(g);
    std::vector<TraceProbe> probes(g.size());
    for (std::size_t b = 0; b < g.size(); ++b) ASSERT_TRUE(trace_probe(*g[b], probes[b]));
    const TraceTableData t = make_trace_table(probes, g[0]->body->model().num_nodes());
    std::vector<double> v(static_cast<std::size_t>(t.width()));
    MatX3 f_ext, S;
    State st = make_state(g[0]->body->model());
    for (int k = 0; k <= 120; ++k) {  // 60 ms: ramp, hold, releases, return
      if (k > 0) {
        for (std::size_t b = 0; b < g.size(); ++b)
          stepper->set_loads(static_cast<int>(b), frame_dof_loads(*g[b]->body, g[b]->loads,
                                                                  stepper->time(static_cast<int>(b)), f_ext));
        stepper->step();
      }
      for (std::size_t b = 0; b < g.size(); ++b) {
        const BuiltScene& r = *g[b];
        stepper->positions(static_cast<int>(b), st.x);
        r.body->map_to_surface(st, S);
        SceneTrace host;
        scene_trace_sample(r, 0.0, Vec3::Zero(), S, st.x, 0.0, host);
        trace_values(t, static_cast<int>(b), st.x, v.data());
        std::vector<double> want{host.max_disp[0]};
        for (const auto& n : host.node_disp) want.push_back(n[0]);
        for (const auto& n : host.atom_disp) want.push_back(n[0]);
        ASSERT_EQ(want.size(), probes[b].point_dof.size() + 1);
        for (std::size_t q = 0; q < want.size(); ++q) {
          ++values;
          exact += v[q] == want[q] ? 1 : 0;
          worst = std::max(worst, want[q] == 0.0 ? std::abs(v[q]) : rel(v[q], want[q]));
        }
      }
    }
  }
  ::testing::Test::RecordProperty("values", std::to_string(values));
  ::testing::Test::RecordProperty("bit_identical", std::to_string(exact));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", worst);
  ::testing::Test::RecordProperty("max_relative_difference", buf);
  EXPECT_LE(worst, 1e-12) << exact << " of " << values << " bit-identical";
  EXPECT_GT(values, 1000u);
}

// run_scene_batch with the traces reduced by the stepper: the host-sampled batch's summaries (to 1e-12
// relative: the norms' rounding) and its field snapshots bit for bit, with positions read only for them.
TEST(SceneBatchTraces, ReducedTracesGiveTheHostSampledSummaries) {
  const BuiltScene a = built(kPress), c = built(kOther);
  const std::vector<const BuiltScene*> runs{&a, &c};
  const std::vector<double> times{25.0, 60.0};
  ReducingCpuStepper::position_reads = 0;
  const std::vector<BatchRunResult> red = run_scene_batch(
      runs, [](const std::vector<const BuiltScene*>& g) { return std::make_unique<ReducingCpuStepper>(g); },
      times);
  EXPECT_EQ(ReducingCpuStepper::position_reads, 2 * 3);  // 2 models x frames 0 (rest), 50 (25 ms), 120
  const std::vector<BatchRunResult> host = run_scene_batch(runs, make_cpu_batch_stepper, times);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    SCOPED_TRACE(i);
    const RunSummary &r = red[i].summary, &h = host[i].summary;
    EXPECT_EQ(r.substeps, h.substeps);
    for (const auto& [got, want] : {std::pair{r.contact_peak_mm, h.contact_peak_mm},
                                    {r.contact_hold_mm, h.contact_hold_mm},
                                    {r.max_disp_peak_mm, h.max_disp_peak_mm},
                                    {r.atom_hold_mm, h.atom_hold_mm},
                                    {r.final_max_disp_mm, h.final_max_disp_mm}})
      EXPECT_LE(rel(got, want), 1e-12) << got << " vs " << want;
    EXPECT_GT(r.contact_peak_mm, 0.1);
    EXPECT_EQ(r.return_ms, h.return_ms);
    EXPECT_EQ(r.local_hold_mm, 0.0);
    EXPECT_EQ(red[i].field_times, host[i].field_times);
    ASSERT_EQ(red[i].fields.size(), times.size());
    for (std::size_t k = 0; k < times.size(); ++k) EXPECT_EQ(red[i].fields[k], host[i].fields[k]);
  }
}

}  // namespace
}  // namespace medspring
