#include "medspring/local/deformer.hpp"

#include <gtest/gtest.h>

#include "local_fixtures.hpp"
#include "medspring/core/error.hpp"

namespace medspring {
namespace {

using testing::mesh_adjacency;

struct Update {
  Index contact;
  Vec3 F;
};

// The same sequence of updates (repeated contacts, a contact change, a release) through a cached and
// an uncached deformer must give identical U.
void expect_cached_equals_uncached(LocalDeformer cached, LocalDeformer uncached,
                                   const std::vector<Update>& seq) {
  MatX3 Uc, Uu;
  for (std::size_t t = 0; t < seq.size(); ++t) {
    SCOPED_TRACE(::testing::Message() << "update " << t);
    const LocalSolveInfo ic = cached.compute(seq[t].contact, seq[t].F, Uc);
    const LocalSolveInfo iu = uncached.compute(seq[t].contact, seq[t].F, Uu);
    EXPECT_EQ(ic.zero, iu.zero);
    ASSERT_EQ(Uc.rows(), Uu.rows());
    EXPECT_EQ(cached.patch().nodes, uncached.patch().nodes);
    for (Index r = 0; r < Uc.rows(); ++r)
      for (Index a = 0; a < 3; ++a) EXPECT_EQ(Uc(r, a), Uu(r, a));  // bit for bit
  }
}

const std::vector<Update> kSequence = {
    {607, Vec3(0, 0, -0.05)},       {607, Vec3(0, 0.01, -0.1)},       {607, Vec3(0, 0.02, -0.2)},
    {30 * 7 + 29, Vec3(0.1, 0, 0)}, {30 * 7 + 29, Vec3(0.1, 0.2, 0)}, {607, Vec3::Zero()},
    {45, Vec3(0, 0.3, 0.1)},
};

TEST(LocalDeformer, CachedSolveEqualsUncachedSolveBitForBit) {
  for (const LocalStiffness mode : {LocalStiffness::Isotropic, LocalStiffness::Linearized,
                                    LocalStiffness::AxisProjected, LocalStiffness::PaperLiteral}) {
    SCOPED_TRACE(to_string(mode));
    LocalDeformationSettings s;
    s.solver.stiffness = mode;
    const MatX3 X = tube(40, 30).V;
    const LocalDeformer cached = LocalDeformer::tube(40, 30, s, X);
    s.cache_local = false;
    const LocalDeformer uncached = LocalDeformer::tube(40, 30, s, X);
    expect_cached_equals_uncached(cached, uncached, kSequence);
  }
  const SurfaceMesh kid = kidney_phantom();
  LocalDeformationSettings s;
  const LocalDeformer cached = LocalDeformer::mesh(mesh_adjacency(kid), kid.V, s);
  s.cache_local = false;
  const LocalDeformer uncached = LocalDeformer::mesh(mesh_adjacency(kid), kid.V, s);
  expect_cached_equals_uncached(
      cached, uncached,
      {{223, Vec3(0, 0.2, 0)}, {223, Vec3(0, 1.0, 0)}, {5, Vec3(1, 0, 0)}, {223, Vec3(0, 0, 1)}});
}

TEST(LocalDeformer, TubeDeformerUsesTheFiveByFiveWindow) {
  LocalDeformer d = LocalDeformer::tube(40, 30, {.patch = {.k_loc = 1.0}, .solver = {}});
  MatX3 U;
  const Vec3 F(0, 0, 1);
  d.compute(20 * 30 + 7, F, U);
  EXPECT_EQ(d.patch().size(), 25);
  EXPECT_NEAR(U(12, 2), 39.0 / 172.0, 1e-9 * 39.0 / 172.0);
}

TEST(LocalDeformer, KidneyDeformerUsesTheBfsPatch) {
  const SurfaceMesh kid = kidney_phantom();
  const Adjacency adj = mesh_adjacency(kid);
  LocalDeformer d = LocalDeformer::mesh(adj, kid.V);
  MatX3 U;
  d.compute(223, Vec3(0, 0.2, 0), U);
  EXPECT_EQ(d.patch().nodes, bfs_patch(adj, kid.V, 223, 25));
  EXPECT_GT(U(0, 1), 0.0);
}

TEST(LocalDeformer, BadInputIsRejected) {
  LocalDeformer d = LocalDeformer::tube(40, 30);
  MatX3 U;
  EXPECT_THROW(d.compute(1200, Vec3(0, 0, 1), U), InvalidInput);
  EXPECT_THROW(d.compute(-1, Vec3(0, 0, 1), U), InvalidInput);
  LocalDeformationSettings lin;
  lin.solver.stiffness = LocalStiffness::Linearized;
  EXPECT_THROW(LocalDeformer::tube(40, 30, lin), InvalidInput);  // needs positions
  EXPECT_THROW(LocalDeformer::tube(40, 30, {}, MatX3(), std::vector<std::uint8_t>(7, 0)), InvalidInput);
  const SurfaceMesh kid = kidney_phantom();
  EXPECT_THROW(LocalDeformer::mesh(mesh_adjacency(kid), MatX3::Zero(10, 3)), InvalidInput);
  LocalDeformer big =
      LocalDeformer::mesh(mesh_adjacency(kid), kid.V, {.patch = {.count = 459}, .solver = {}});
  EXPECT_THROW(big.compute(3, Vec3(1, 0, 0), U), InvalidInput);  // patch larger than the mesh
  // Flat patch, no return spring: the singular patch is reported when the contact is selected.
  lin.solver.return_stiffness = 0.0;
  LocalDeformer flat = LocalDeformer::tube(40, 30, lin, testing::flat_tube_positions(40, 30));
  EXPECT_THROW(flat.compute(607, Vec3(0, 0, 1), U), SolverError);
}

}  // namespace
}  // namespace medspring
