// Checks of a packed spring table (pack_spring_table, physics/spring_table.hpp) shared by physics_tests
// PackedTable.* and builders_tests RealKidneyTable.* (the real kidney): the words decode to the table's
// entries, and the packed gather gives the unpacked gather's forces, bit for bit.
#pragma once

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "medspring/physics/spring_table.hpp"

namespace medspring::testing {

// Every packed word of P decodes to U's entry: other end, rest length, k, k', 1/k (bit for bit).
template <class R>
void expect_decodes_to(const SpringTableArrays<R>& P, const SpringTableArrays<R>& U) {
  const hd::SpringTable<R> pv = P.view(), uv = U.view();
  ASSERT_EQ(P.entries(), U.entries());
  const long long rows = U.row_node.empty() ? U.nodes : static_cast<long long>(U.row_node.size());
  long long checked = 0, bad = 0;
  for (long long r = 0; r < rows; ++r) {
    const int ri = static_cast<int>(r), a = hd::row_node(uv, ri), sl = ri / hd::kSlice;
    for (int j = 0; j < U.slice_width[static_cast<std::size_t>(sl)]; ++j) {
      const int e = U.slice_begin[static_cast<std::size_t>(sl)] + j * hd::kSlice + (ri - sl * hd::kSlice);
      const unsigned w = pv.packed[e];
      const int c = hd::packed_class(w, pv.class_bits);
      R k, kp, ik;
      hd::spring_params(uv, e, k, kp, ik);
      const bool same = hd::packed_other(w, pv.class_bits, a) == uv.other[e] && pv.cL0[c] == uv.L0[e] &&
                        pv.ck[c] == k && pv.ckp[c] == kp && pv.cik[c] == ik;
      bad += !same;
      ++checked;
    }
  }
  EXPECT_EQ(bad, 0) << "of " << checked << " entries";
  EXPECT_GT(checked, rows);
}

// The packed gather against the unpacked one on every row: the same values, the same arithmetic, so the
// same forces and stiffening, bit for bit (positions displaced at random so every law is active); the
// grid kernel's split table (heavy rows as chunks, row_node set) too.
template <class R, bool Soft, bool Stiff>
void expect_packed_gather_equal(const Model& m, const SpringTableArrays<R>& U) {
  SpringTableArrays<R> P = U;
  ASSERT_TRUE(pack_spring_table(P).fits);
  const hd::SpringTable<R> uv = U.view(), pv = P.view();
  std::vector<R> x(3 * static_cast<std::size_t>(m.num_nodes()));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  for (Index a = 0; a < m.num_nodes(); ++a)
    for (int c = 0; c < 3; ++c)
      x[static_cast<std::size_t>(3 * a + c)] = static_cast<R>(m.x0(a, c) + jitter(rng));
  const int rows = U.row_node.empty() ? U.nodes : static_cast<int>(U.row_node.size());
  int moved = 0;
  for (int r = 0; r < rows; ++r) {
    const int a = hd::row_node(uv, r);
    R fu[3] = {R(0), R(0), R(0)}, fp[3] = {R(0), R(0), R(0)}, su = R(1), sp = R(1);
    hd::gather_spring_forces<Soft, Stiff, 1, false>(uv, r, a, x.data(), su, fu);
    hd::gather_spring_forces<Soft, Stiff, 1, true>(pv, r, a, x.data(), sp, fp);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(fp[c], fu[c]) << m.name << " row " << r;
      moved += fu[c] != R(0);
    }
    EXPECT_EQ(sp, su) << m.name << " row " << r;
  }
  EXPECT_GT(moved, rows);
}

}  // namespace medspring::testing
