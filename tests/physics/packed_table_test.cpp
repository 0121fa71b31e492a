// Packed spring tables (pack_spring_table, physics/spring_table.hpp; gpu::Options::packed_table,
// docs/gpu.md): each entry one 32-bit word (other end's offset, class of (L0, k, k', 1/k)). The words
// decode to the unpacked table's entries bit for bit (a small tube, a 1M-node tube: the GPU benchmark's
// size), the packed gather (hd::gather_spring_forces<..., Packed = true>) gives the unpacked gather's forces
// bit for bit, and a table that does not fit is left as it is.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>
#include <string>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/spring_table.hpp"
#include "packed_table_check.hpp"

namespace medspring {
namespace {

using testing::expect_decodes_to;
using testing::expect_packed_gather_equal;

Model tube_of(Index rings, Index spokes, bool soft) {
  SurfaceBodyParams p;
  p.duffing.soft = soft;
  for (Index j = 0; j < spokes; ++j) {
    p.fixed.push_back(j);
    p.fixed.push_back((rings - 1) * spokes + j);
  }
  const double radius = std::max(3.0, 2.5 * static_cast<double>(spokes) / (2.0 * 3.141592653589793));
  return make_surface_model(tube(rings, spokes, 2.5, radius), p, soft ? "soft_tube" : "tube");
}

template <class R>
PackReport pack_and_check(const Model& m, bool compact, RowOrder order = RowOrder::HeavyLast) {
  const SpringTableArrays<R> U0 = make_spring_table<R>(m, order);
  SpringTableArrays<R> U = U0;
  if (compact) compact_spring_params(U, 65536);
  SpringTableArrays<R> P = U;
  const PackReport rep = pack_spring_table(P);
  EXPECT_TRUE(rep.fits) << m.name << ": " << rep.classes << " classes, offset " << rep.max_offset;
  if (!rep.fits) return rep;
  EXPECT_TRUE(P.other.empty() && P.L0.empty() && P.k.empty() && P.cls.empty());
  EXPECT_EQ(P.cL0.size(), static_cast<std::size_t>(rep.classes));
  expect_decodes_to(P, U0);
  return rep;
}

TEST(PackedTable, WordsDecodeToTheTableEntriesSmallTubes) {
  for (const bool soft : {false, true}) {
    const Model m = tube_of(12, 10, soft);
    for (const bool compact : {false, true}) {
      const PackReport rep = pack_and_check<double>(m, compact);
      EXPECT_LE(rep.classes, 16);  // a uniform tube: a few (L0, k) pairs and the padding class
      pack_and_check<float>(m, compact, RowOrder::Nodes);
    }
  }
}

// The GPU benchmark's 1M-node tube (1,000 rings of 1,000 spokes, bench --gpu): it packs (830 classes in 10
// bits here: the chords' rest lengths differ in their last bits around the ring; offsets up to about one
// ring), and every word decodes to its entry.
TEST(PackedTable, MillionNodeTubePacksAndDecodes) {
  const auto t0 = std::chrono::steady_clock::now();
  const Model m = tube_of(1000, 1000, false);
  ASSERT_EQ(m.num_nodes(), 1000000);
  const PackReport rep = pack_and_check<double>(m, true);
  EXPECT_LE(rep.max_offset, 1001);  // neighbours within a ring and the next: node order is ring by ring
  RecordProperty("classes", std::to_string(rep.classes));
  RecordProperty("class_bits", std::to_string(rep.class_bits));
  RecordProperty("max_offset", std::to_string(rep.max_offset));
  RecordProperty(
      "seconds",
      std::to_string(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()));
}

// A table whose classes need more bits than allowed is left as it is (fits false, the figures given); a
// bad bit count is refused.
TEST(PackedTable, TableThatDoesNotFitIsLeftAsItIs) {
  const Model m = tube_of(12, 10, false);
  const SpringTableArrays<double> U = make_spring_table<double>(m);
  SpringTableArrays<double> P = U;
  const PackReport rep = pack_spring_table(P, 0);  // no class bits: only a one-class table would fit
  EXPECT_FALSE(rep.fits);
  EXPECT_GT(rep.classes, 1);
  EXPECT_TRUE(P.packed.empty());
  EXPECT_EQ(P.other, U.other);
  EXPECT_EQ(P.L0, U.L0);
  EXPECT_EQ(P.k, U.k);
  EXPECT_THROW(pack_spring_table(P, 25), InvalidInput);
}

TEST(PackedTable, PackedGatherGivesTheSameForcesBitForBit) {
  const Model hard = tube_of(12, 10, false), soft = tube_of(12, 10, true);
  expect_packed_gather_equal<double, false, true>(hard, make_spring_table<double>(hard, RowOrder::HeavyLast));
  expect_packed_gather_equal<double, true, true>(soft, make_spring_table<double>(soft));
  expect_packed_gather_equal<double, true, false>(soft, make_grid_split_table<double>(soft, 3).table);
  expect_packed_gather_equal<float, false, false>(hard, make_spring_table<float>(hard));
  expect_packed_gather_equal<float, true, true>(soft, make_grid_split_table<float>(soft, 3).table);
}

}  // namespace
}  // namespace medspring
