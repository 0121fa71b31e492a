// The hybrid kidney (458 surface nodes + 42 atoms with dozens of spokes each) through the GPU path's
// arithmetic on the CPU: spring table gather + hd::node_substep against the engine's step() (docs/gpu.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>

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

// Compact parameters on the kidney (docs/gpu.md): its springs' stiffnesses depend on their rest lengths,
// so nearly every spring is its own class -- more than the default cap (kCompactClasses), and the GPU
// keeps the per-entry arrays. With the cap raised the classes still give the same trajectory, bit for bit.
TEST(HybridGather, CompactParametersOnTheKidneyAreBitIdentical) {
  const HybridKidney kidney = hybrid_kidney_phantom();
  const Model& m = kidney.model();
  PointLoad L;
  L.node = 223;
  L.force = Vec3(0, 0, -1.0);
  L.t_ramp = 10.0;
  L.t_release = 150.0;
  const std::vector<PointLoad> loads{L};
  testing::GatherStepper<double> full(m, loads), compact(m, loads);
  SpringTableArrays<double> T = make_spring_table<double>(m);
  EXPECT_FALSE(compact_spring_params(T));  // over the default cap: left as it is
  EXPECT_FALSE(T.k.empty());
  ASSERT_TRUE(compact_spring_params(compact.T, 65536));
  ASSERT_TRUE(compact_node_params(compact.N, 65536));
  StepSettings s;
  for (int f = 0; f < 300; ++f) {
    full.frame(s);
    compact.frame(s);
  }
  EXPECT_GT(std::abs(full.x[3 * 223 + 2] - full.N.x0[3 * 223 + 2]), 1.0);
  EXPECT_EQ(compact.x, full.x);
  EXPECT_EQ(compact.v, full.v);
  EXPECT_EQ(compact.substeps, full.substeps);
  ::testing::Test::RecordProperty("spring_classes", std::to_string(compact.T.ck.size()));
  ::testing::Test::RecordProperty("node_classes", std::to_string(compact.N.cmass.size()));
}

// The one-block-per-model kernel's algorithm (rows dealt to 256 threads by degree, positions in two
// buffers, velocities in place) on the CPU against the engine's step(): the per-block path's arithmetic.
TEST(HybridGather, OneBlockPerModelAlgorithmEqualsTheEngineStep) {
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
  testing::BlockStepper<double> blk(m, loads, 256);
  testing::GatherStepper<double> g(m, loads);
  double worst = 0, to_gather = 0;
  for (int f = 0; f < 600; ++f) {
    ASSERT_TRUE(step(m, st, s, &loads).ok());
    blk.frame(s);
    g.frame(s);
    worst = std::max(
        {worst, testing::relative_difference(blk.x, st.x), testing::relative_difference(blk.v, st.v)});
    MatX3 gx(m.num_nodes(), 3);
    for (Index q = 0; q < 3 * m.num_nodes(); ++q) gx.data()[q] = g.x[static_cast<std::size_t>(q)];
    to_gather = std::max(to_gather, testing::relative_difference(blk.x, gx));
  }
  EXPECT_LE(worst, 1e-13);
  EXPECT_LE(to_gather, 1e-13);  // the row order changes which thread gathers a node, not its terms
  EXPECT_EQ(blk.substeps, static_cast<long>(st.substeps));
  EXPECT_EQ(blk.failures, 0);
  EXPECT_NEAR(blk.stiffening, st.stiffening, 1e-9 * st.stiffening);
  ::testing::Test::RecordProperty("max_relative_difference", (std::ostringstream() << worst).str());
  ::testing::Test::RecordProperty("block_vs_grid_gather", (std::ostringstream() << to_gather).str());
}

// Heavy rows split across threads (kernels_split.hpp): the atoms' spokes in chunks of at most 17 springs
// (the mean work of a thread), partial sums combined in spring order after a barrier. The summation order
// of an atom's force changes (chunk sums), so the match with step() is to rounding.
TEST(HybridGather, SplitHeavyRowsEqualTheEngineStepAndShortenTheCriticalPath) {
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
  const int threads = 256;
  testing::SplitStepper<double> sp(m, loads, threads);
  double worst = 0, peak = 0;
  for (int f = 0; f < 600; ++f) {
    ASSERT_TRUE(step(m, st, s, &loads).ok());
    sp.frame(s);
    worst =
        std::max({worst, testing::relative_difference(sp.x, st.x), testing::relative_difference(sp.v, st.v)});
    peak = std::max(peak, (st.x - m.x0).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(peak, 1.0);
  EXPECT_LE(worst, 1e-12);
  EXPECT_EQ(sp.substeps, static_cast<long>(st.substeps));
  EXPECT_EQ(sp.failures, 0);
  EXPECT_NEAR(sp.stiffening, st.stiffening, 1e-9 * st.stiffening);
  // Every spring end exactly once; the split nodes are the heavy ones.
  const SplitTableArrays<double>& S = sp.S;
  long real = 0;
  for (std::size_t e = 0; e < S.table.entries(); ++e) real += S.table.k[e] != 0.0;
  EXPECT_EQ(real, 2L * m.num_springs());
  EXPECT_EQ(S.chunk, 17);
  // Critical path: the most springs one thread gathers in phase 1, plus the slots it sums in phase 2.
  std::vector<int> work(threads, 0);
  for (std::size_t r = 0; r < S.part.size(); ++r) {
    const int sl = static_cast<int>(r) / hd::kSlice;
    int e = S.table.slice_begin[static_cast<std::size_t>(sl)] + static_cast<int>(r) % hd::kSlice, springs = 0;
    for (int j = 0; j < S.table.slice_width[static_cast<std::size_t>(sl)]; ++j, e += hd::kSlice)
      springs += S.table.k[static_cast<std::size_t>(e)] != 0.0;
    work[r % threads] += springs;
  }
  for (std::size_t k = 0; k < S.heavy_node.size(); ++k)
    work[k % threads] += S.part_begin[k + 1] - S.part_begin[k];
  const int critical = *std::max_element(work.begin(), work.end());
  EXPECT_LE(critical, 2 * S.chunk + 8);  // against 80 without splitting
  ::testing::Test::RecordProperty("max_relative_difference", (std::ostringstream() << worst).str());
  ::testing::Test::RecordProperty("split_nodes", std::to_string(S.heavy_node.size()));
  ::testing::Test::RecordProperty("parts", std::to_string(S.parts()));
  ::testing::Test::RecordProperty("rows", std::to_string(S.part.size()));
  ::testing::Test::RecordProperty("critical_springs", std::to_string(critical));
}

// Load balance of the atoms' spokes (docs/gpu.md): the work of a thread is the springs it gathers.
struct Balance {
  double entries_per_end = 0;  // table entries (with padding) per spring end
  int critical = 0;            // the most springs one thread of a 256-thread block gathers per substep
  double mean = 0;             // the mean over the threads that have rows
  long warp_steps = 0;         // SIMT cost: sum over the block's warps and rounds of the widest lane
};
Balance balance(const Model& m, RowOrder order, int threads) {
  const SpringTableArrays<double> T = make_spring_table<double>(m, order, threads);
  std::vector<int> degree(static_cast<std::size_t>(m.num_nodes()), 0);
  for (Index s = 0; s < m.num_springs(); ++s) {
    ++degree[static_cast<std::size_t>(m.springs.i[static_cast<std::size_t>(s)])];
    ++degree[static_cast<std::size_t>(m.springs.j[static_cast<std::size_t>(s)])];
  }
  std::vector<int> work(static_cast<std::size_t>(threads), 0);
  for (Index r = 0; r < m.num_nodes(); ++r) {
    const Index a = T.row_node.empty() ? r : T.row_node[static_cast<std::size_t>(r)];
    work[static_cast<std::size_t>(r % threads)] += degree[static_cast<std::size_t>(a)];
  }
  Balance b;
  for (Index r0 = 0; r0 < m.num_nodes(); r0 += 32) {  // a warp's 32 consecutive rows in one round
    int widest = 0;
    for (Index r = r0; r < std::min<Index>(r0 + 32, m.num_nodes()); ++r)
      widest = std::max(
          widest,
          degree[static_cast<std::size_t>(T.row_node.empty() ? r : T.row_node[static_cast<std::size_t>(r)])]);
    b.warp_steps += widest;
  }
  b.entries_per_end = static_cast<double>(T.entries()) / (2.0 * m.num_springs());
  b.critical = *std::max_element(work.begin(), work.end());
  b.mean = 2.0 * m.num_springs() / std::min<double>(threads, m.num_nodes());
  return b;
}

TEST(HybridGather, RowOrdersBalanceTheAtomsSpokes) {
  const HybridKidney kidney = hybrid_kidney_phantom();
  const Model& m = kidney.model();
  const int threads = 256;
  for (RowOrder order : {RowOrder::HeavyLast, RowOrder::Balanced}) {  // a permutation of the nodes
    const SpringTableArrays<double> T = make_spring_table<double>(m, order, threads);
    std::vector<int> seen(static_cast<std::size_t>(m.num_nodes()), 0);
    ASSERT_EQ(T.row_node.size(), static_cast<std::size_t>(m.num_nodes()));
    for (int a : T.row_node) ++seen.at(static_cast<std::size_t>(a));
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), m.num_nodes());
  }
  const Balance nodes = balance(m, RowOrder::Nodes, threads);
  const Balance heavy = balance(m, RowOrder::HeavyLast, threads);
  const Balance dealt = balance(m, RowOrder::Balanced, threads);
  int max_degree = 0;
  {
    std::vector<int> degree(static_cast<std::size_t>(m.num_nodes()), 0);
    for (Index s = 0; s < m.num_springs(); ++s) {
      max_degree =
          std::max(max_degree, ++degree[static_cast<std::size_t>(m.springs.i[static_cast<std::size_t>(s)])]);
      max_degree =
          std::max(max_degree, ++degree[static_cast<std::size_t>(m.springs.j[static_cast<std::size_t>(s)])]);
    }
  }
  // Heavy rows in warps of their own: less padding than the node order.
  EXPECT_LT(heavy.entries_per_end, nodes.entries_per_end);
  EXPECT_LT(dealt.entries_per_end, nodes.entries_per_end);
  // Dealt by degree in snake order: no thread holds two heavy rows; the critical path is at most the
  // heaviest row plus the lightest rows dealt back to it.
  EXPECT_LE(dealt.critical, nodes.critical);
  EXPECT_LT(dealt.warp_steps, nodes.warp_steps);
  EXPECT_LE(dealt.critical, max_degree + 16);
  for (const auto& [name, b] :
       {std::pair<const char*, Balance>{"nodes", nodes}, {"heavy_last", heavy}, {"balanced", dealt}}) {
    ::testing::Test::RecordProperty(std::string(name) + "_entries_per_spring_end",
                                    (std::ostringstream() << b.entries_per_end).str());
    ::testing::Test::RecordProperty(std::string(name) + "_critical_springs", std::to_string(b.critical));
    ::testing::Test::RecordProperty(std::string(name) + "_warp_steps", std::to_string(b.warp_steps));
  }
  ::testing::Test::RecordProperty("mean_springs_per_thread", (std::ostringstream() << dealt.mean).str());
  ::testing::Test::RecordProperty("max_degree", std::to_string(max_degree));
}

// Issue 21: heavy rows split in the grid kernel too (make_grid_split_table): an atom's spokes gathered by
// up to a warp of threads, summed by the lead lane after the warp's barrier.
TEST(HybridGather, GridSplitRowsEqualTheEngineStepAndKeepEveryNodeInOneWarp) {
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
  testing::GridSplitStepper<double> gp(m, loads);
  double worst = 0, peak = 0;
  for (int f = 0; f < 600; ++f) {
    ASSERT_TRUE(step(m, st, s, &loads).ok());
    gp.frame(s);
    worst =
        std::max({worst, testing::relative_difference(gp.x, st.x), testing::relative_difference(gp.v, st.v)});
    peak = std::max(peak, (st.x - m.x0).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(peak, 1.0);
  EXPECT_LE(worst, 1e-12);
  EXPECT_EQ(gp.substeps, static_cast<long>(st.substeps));
  EXPECT_EQ(gp.failures, 0);
  EXPECT_NEAR(gp.stiffening, st.stiffening, 1e-9 * st.stiffening);
  const GridSplitArrays<double>& G = gp.G;
  long real = 0;  // every spring end exactly once
  for (std::size_t e = 0; e < G.table.entries(); ++e) real += G.table.k[e] != 0.0;
  EXPECT_EQ(real, 2L * m.num_springs());
  ASSERT_FALSE(G.heavy_node.empty());
  for (std::size_t k = 0; k < G.heavy_node.size();
       ++k) {  // a node's chunks: consecutive, one warp, lead first
    const int first = G.lead_row[k], count = G.part_begin[k + 1] - G.part_begin[k];
    EXPECT_EQ(first / hd::kSlice, (first + count - 1) / hd::kSlice) << "node " << G.heavy_node[k];
    for (int j = 0; j < count; ++j) {
      EXPECT_EQ(G.table.row_node[static_cast<std::size_t>(first + j)], G.heavy_node[k]);
      EXPECT_EQ(G.part[static_cast<std::size_t>(first + j)], G.part_begin[k] + j);
    }
  }
  // The widest row (springs one thread gathers) against the table without splitting (HeavyLast).
  int widest = 0, widest_before = 0;
  for (int w : G.table.slice_width) widest = std::max(widest, w);
  for (int w : make_spring_table<double>(m, RowOrder::HeavyLast).slice_width)
    widest_before = std::max(widest_before, w);
  EXPECT_EQ(G.chunk, kHeavyDegree);  // the median degree of the phantom is below 8
  EXPECT_LE(widest, G.chunk);
  EXPECT_GT(widest_before, 2 * kHeavyDegree);
  ::testing::Test::RecordProperty("max_relative_difference", (std::ostringstream() << worst).str());
  ::testing::Test::RecordProperty("split_nodes", std::to_string(G.heavy_node.size()));
  ::testing::Test::RecordProperty("rows", std::to_string(G.rows()));
  ::testing::Test::RecordProperty("entries", std::to_string(G.table.entries()));
  ::testing::Test::RecordProperty("widest_row",
                                  std::to_string(widest) + " (before " + std::to_string(widest_before) + ")");
}

}  // namespace
}  // namespace medspring
