// The visibility filter of ALGORITHMS.md D-9 (§4.2) on a kidney-like block with a renal sinus: a 40 x 20 x
// 20 mm block (voxels of 0.5 mm) with a 4 mm wide, 12 mm deep slot cut into its top (the sinus), atoms on
// the long axis below it. For a node high on the slot's wall the nearest atom lies across the slot, so the
// union rule's spoke crosses the sinus, outside the organ; with the mask the filter takes the next atom and
// no spoke leaves the organ. Checked against the block's exact geometry, not the voxels.
#include <gtest/gtest.h>

#include <algorithm>

#include "medspring/core/check.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/tube_hybrid.hpp"

namespace medspring {
namespace {

constexpr double kSlotLo = 18, kSlotHi = 22, kSlotBottom = 8;  // mm

bool in_slot(const Vec3& p) {
  return p.x() > kSlotLo && p.x() < kSlotHi && p.y() > kSlotBottom;
}

/// How far a point lies outside the organ (block minus slot), mm.
double outside(const Vec3& p) {
  if (in_slot(p)) return std::min({p.x() - kSlotLo, kSlotHi - p.x(), p.y() - kSlotBottom});
  Vec3 d;
  for (int a = 0; a < 3; ++a) {
    const double hi = a == 0 ? 40.0 : 20.0;
    d[a] = std::max({0.0, -p[a], p[a] - hi});
  }
  return d.norm();
}

MaskVolume block_mask() {
  MaskVolume m;
  m.dims = {80, 40, 40};
  m.spacing = Vec3::Constant(0.5);
  m.origin = Vec3::Constant(0.25);
  m.data.assign(m.size(), 0);
  for (Index k = 0; k < 40; ++k)
    for (Index j = 0; j < 40; ++j)
      for (Index i = 0; i < 80; ++i) m.at(i, j, k) = in_slot(m.to_world(Vec3(i, j, k))) ? 0 : 1;
  return m;
}

struct Organ {
  MatX3 nodes, atoms;
};

Organ block_organ() {
  std::vector<Vec3> nodes;
  for (double z : {6.0, 10.0, 14.0}) {
    for (double y : {10.0, 14.0, 18.0}) {
      nodes.emplace_back(kSlotLo, y, z);  // the sinus's walls
      nodes.emplace_back(kSlotHi, y, z);
    }
    for (double x : {4.0, 10.0, 30.0, 36.0}) {
      nodes.emplace_back(x, 20.0, z);  // top and bottom faces
      nodes.emplace_back(x, 0.0, z);
    }
  }
  Organ o;
  o.nodes.resize(static_cast<Index>(nodes.size()), 3);
  for (std::size_t r = 0; r < nodes.size(); ++r) o.nodes.row(static_cast<Index>(r)) = nodes[r].transpose();
  const std::vector<double> xs = {2, 10, 22, 30, 38};  // irregular: atom 2 sits right of the sinus
  o.atoms.resize(static_cast<Index>(xs.size()), 3);
  for (std::size_t a = 0; a < xs.size(); ++a) o.atoms.row(static_cast<Index>(a)) << xs[a], 4.0, 10.0;
  return o;
}

/// The largest distance outside the organ of any point of any spoke (sampled every 0.05 mm).
double worst_outside(const MatX2i& spokes, const Organ& o) {
  double worst = 0;
  for (Index r = 0; r < spokes.rows(); ++r) {
    const Vec3 p = o.nodes.row(spokes(r, 0)).transpose(), q = o.atoms.row(spokes(r, 1)).transpose();
    const int n = static_cast<int>((q - p).norm() / 0.05) + 1;
    for (int s = 0; s <= n; ++s) worst = std::max(worst, outside(p + (q - p) * (static_cast<double>(s) / n)));
  }
  return worst;
}

TEST(SpokeVisibility, SpokesAcrossTheSinusAreRejected) {
  const Organ o = block_organ();
  const MaskVolume mask = block_mask();
  const MatX2i plain = union_spokes(o.nodes, o.atoms, 2);
  // Without the filter: the high node on the sinus's left wall (18, 18, 10) goes to atom 2 across it,
  // 2 mm (4 voxels) deep into the sinus at mid-crossing.
  EXPECT_GE(worst_outside(plain, o), 1.9);
  SpokeVisibility vis;
  const MatX2i filtered = union_spokes(o.nodes, o.atoms, 2, &mask, &vis);
  EXPECT_GT(vis.rejected, 0);
  EXPECT_EQ(vis.fallbacks, 0);
  // With it no spoke goes deeper than one voxel (+ half a voxel between the filter's samples).
  EXPECT_LE(worst_outside(filtered, o), 0.75);
  for (Index r = 0; r < filtered.rows(); ++r)
    EXPECT_TRUE(segment_inside_mask(mask, o.nodes.row(filtered(r, 0)).transpose(),
                                    o.atoms.row(filtered(r, 1)).transpose()));
  // Every node still has a spoke, every atom its two.
  std::vector<int> per_node(static_cast<std::size_t>(o.nodes.rows()), 0), per_atom(5, 0);
  for (Index r = 0; r < filtered.rows(); ++r) {
    ++per_node[static_cast<std::size_t>(filtered(r, 0))];
    ++per_atom[static_cast<std::size_t>(filtered(r, 1))];
  }
  EXPECT_EQ(*std::min_element(per_node.begin(), per_node.end()), 1);
  EXPECT_GE(*std::min_element(per_atom.begin(), per_atom.end()), 2);
}

TEST(SpokeVisibility, SegmentTestRejectsASegmentThroughACavity) {
  const MaskVolume m = block_mask();
  EXPECT_TRUE(segment_inside_mask(m, Vec3(4, 10, 10), Vec3(12, 2, 14)));      // stays in the block
  EXPECT_FALSE(segment_inside_mask(m, Vec3(16, 14, 10), Vec3(24, 14, 10)));   // straight through the sinus
  EXPECT_TRUE(segment_inside_mask(m, Vec3(14, 14, 10), Vec3(18.4, 14, 10)));  // less than a voxel into it
  EXPECT_FALSE(segment_inside_mask(m, Vec3(10, 10, 10), Vec3(10, 30, 10)));   // out through the top
}

TEST(SpokeVisibility, WithoutAMaskTheUnionRuleIsUnchanged) {
  // The phantom has no mask: the filter does not run and the spokes are the union rule's.
  const HybridKidney k = hybrid_kidney_phantom();
  EXPECT_FALSE(k.stats().visibility_filtered);
  EXPECT_EQ(k.stats().visibility.rejected, 0);
  const MatX2i plain = union_spokes(k.rest_surface(), k.model().x0.bottomRows(k.num_atoms()), 8);
  ASSERT_EQ(plain.rows(), k.spokes().rows());
  EXPECT_TRUE((plain.array() == k.spokes().array()).all());
  EXPECT_EQ(k.stats().spokes, 732);  // ALGORITHMS.md §4.2: ≈ 730 on the phantom
}

TEST(TubeHybridBody, IsTheMassSpringColumnOfTablesIAndII) {
  // D-18: 1200 surface nodes + 40 atoms; 3540 tube-grid springs + 39 centerline springs + 1200 spokes;
  // the end rings and end atoms fixed.
  const TubeHybridBody t;
  EXPECT_EQ(t.kind(), "hybrid");
  EXPECT_EQ(t.num_surface_nodes(), 1200);
  EXPECT_EQ(t.model().num_nodes(), 1240);
  EXPECT_EQ(t.model().num_springs(), 3540 + 39 + 1200);
  EXPECT_EQ(t.grid().rings, 40);
  const auto fixed = t.fixed_surface_nodes();
  EXPECT_EQ(std::count(fixed.begin(), fixed.end(), 1), 60);
  EXPECT_TRUE(t.model().fixed[static_cast<std::size_t>(t.atom_dof(0))]);
  EXPECT_TRUE(t.model().fixed[static_cast<std::size_t>(t.atom_dof(39))]);
  EXPECT_FALSE(t.model().fixed[static_cast<std::size_t>(t.atom_dof(20))]);
  EXPECT_THROW(TubeHybridBody({.rings = 1}), InvalidInput);
}

}  // namespace
}  // namespace medspring
