// The real kidney's spring table packed (pack_spring_table; gpu::Options::packed_table, docs/gpu.md): the
// grid kernel's table of the hybrid kidney built from the HuBMAP mesh (its atoms' heavy rows split) packs --
// a class per distinct (L0, k, k', 1/k), offsets within the model -- every word decodes to its entry, and
// the packed gather gives the unpacked gather's forces bit for bit, fp64 and fp32.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "../physics/packed_table_check.hpp"
#include "medspring/builders/kidney_build.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

template <class R>
void expect_real_kidney_packs(const Model& m, bool soft) {
  const SpringTableArrays<R> U = make_grid_split_table<R>(m).table;
  SpringTableArrays<R> P = U;
  const PackReport rep = pack_spring_table(P);
  ASSERT_TRUE(rep.fits) << rep.classes << " classes in " << rep.class_bits << " bits, offsets up to "
                        << rep.max_offset << " of " << rep.offset_limit;
  testing::expect_decodes_to(P, U);
  if (soft)
    testing::expect_packed_gather_equal<R, true, true>(m, U);
  else
    testing::expect_packed_gather_equal<R, false, true>(m, U);
  ::testing::Test::RecordProperty(sizeof(R) == 8 ? "classes_fp64" : "classes_fp32",
                                  std::to_string(rep.classes));
  ::testing::Test::RecordProperty("class_bits", std::to_string(rep.class_bits));
  ::testing::Test::RecordProperty("max_offset", std::to_string(rep.max_offset));
  std::printf("real kidney packed: %d nodes, %lld classes in %d bits, offsets up to %lld (limit %lld)\n",
              static_cast<int>(m.num_nodes()), rep.classes, rep.class_bits, rep.max_offset, rep.offset_limit);
}

TEST(RealKidneyTable, PackedTableDecodesAndGathersBitForBit) {
  const KidneyBuild k =
      build_kidney_model({.source = {.mesh = testing::require_data_file("kidney_left_hubmap_vhm.obj"),
                                     .unit = LengthUnit::Metre}});
  const Model& m = k.model->model();
  expect_real_kidney_packs<double>(m, m.has_soft_springs);
  expect_real_kidney_packs<float>(m, m.has_soft_springs);
}

}  // namespace
}  // namespace medspring
