// The hybrid kidney (458 surface nodes + 42 atoms with dozens of spokes each) through the GPU path's
// arithmetic on the CPU: spring table gather + hd::node_substep against the engine's step() (docs/gpu.md).
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "gather_stepper.hpp"
#include "medspring/models/hybrid_kidney.hpp"

namespace medspring {
namespace {

TEST(HybridGather, KidneyPressAndReleaseEqualsTheEngineStep) {
  const HybridKidney kidney = hybrid_kidney_phantom();
  const Model& m = kidney.model();
  PointLoad L;
  L.node = 223;
  L.force = Vec3(0, 0, -1.0);
  L.t_ramp = 10.0;
  L.t_release = 150.0;
  const std::vector<PointLoad> loads{L};
  StepSettings s;
  State st = make_state(m, s);
  testing::GatherStepper<double> g(m, loads);
  double worst = 0, peak = 0;
  for (int f = 0; f < 600; ++f) {
    ASSERT_TRUE(step(m, st, s, &loads).ok());
    g.frame(s);
    worst =
        std::max({worst, testing::relative_difference(g.x, st.x), testing::relative_difference(g.v, st.v)});
    peak = std::max(peak, (st.x - m.x0).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(peak, 1.0);  // §8: about 5 mm at the contact node under 1 N
  EXPECT_LE(worst, 1e-13);
  EXPECT_EQ(g.substeps, static_cast<long>(st.substeps));
  EXPECT_EQ(g.failures, 0);
  // The atoms' spokes make wide slices: the table still lists every spring end exactly once.
  const SpringTableArrays<double> T = make_spring_table<double>(m);
  long real = 0;
  for (std::size_t e = 0; e < T.entries(); ++e) real += T.k[e] != 0.0;
  EXPECT_EQ(real, 2L * m.num_springs());
  ::testing::Test::RecordProperty("max_relative_difference", (std::ostringstream() << worst).str());
  ::testing::Test::RecordProperty("table_entries_per_spring_end",
                                  std::to_string(static_cast<double>(T.entries()) / (2.0 * m.num_springs())));
}

}  // namespace
}  // namespace medspring
