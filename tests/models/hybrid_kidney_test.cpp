// The hybrid kidney phantom: ALGORITHMS.md §4, §8.5-25, §7.1 and §2.2 reference values.
#include "medspring/models/hybrid_kidney.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/static_solve.hpp"

namespace medspring {
namespace {

TEST(HybridKidney, PhantomCountsOfSection85) {  // §8.5-25
  const HybridKidney k = hybrid_kidney_phantom();
  const HybridStats s = k.stats();
  EXPECT_EQ(s.surface_nodes, 458);
  EXPECT_EQ(s.atoms, 42);
  EXPECT_EQ(s.surface_springs, 1368);
  EXPECT_EQ(k.faces().rows(), 912);
  EXPECT_EQ(s.centerline_springs, 41);
  EXPECT_GE(s.min_spokes_per_atom, 8);
  EXPECT_EQ(s.surface_nodes_without_spoke, 0);
  EXPECT_NEAR(static_cast<double>(s.spokes), 730.0, 40.0);  // "about 730"
  EXPECT_EQ(k.model().num_nodes(), 500);
  EXPECT_EQ(k.model().num_springs(), 1368 + 41 + s.spokes);
  EXPECT_EQ(k.kind(), "hybrid");
}

TEST(HybridKidney, StableStepReferenceValues) {  // §2.2: Gershgorin dt <= 0.40 ms, power iteration 0.84 ms
  const HybridKidney k = hybrid_kidney_phantom();
  EXPECT_NEAR(2.0 / k.model().omega_gershgorin, 0.40, 0.02);
  EXPECT_NEAR(2.0 / (k.model().omega_rest / 1.05), 0.84, 0.03);
  EXPECT_GT(k.model().dt_safe_rest(), 0.5);  // default dt = 0.5 ms: one substep at rest
}

struct KidneyRun {
  double contact = 0, mid_atom = 0, max_other = 0;
};

KidneyRun static_press(bool nonlinear, double magnitude) {
  HybridSettings st;
  st.nonlinear = nonlinear;
  const HybridKidney k = hybrid_kidney_phantom(st);
  const Model& m = k.model();
  const Index c = 223, mid = k.atom_dof(21);
  const Vec3 dir = -(m.x0.row(c) - m.x0.row(mid)).normalized().transpose();  // §7.1: towards atom 21
  MatX3 f = MatX3::Zero(m.num_nodes(), 3);
  k.transfer_force(c, magnitude * dir, f);
  const MatX3 u = static_equilibrium(m, f).x - m.x0;
  KidneyRun r;
  r.contact = u.row(c).norm();
  r.mid_atom = u.row(mid).norm();
  for (Index i = 0; i < k.num_surface_nodes(); ++i)
    if (i != c) r.max_other = std::max(r.max_other, u.row(i).norm());
  return r;
}

TEST(HybridKidney, PressMatchesThePrototypeOfSection71) {
  const KidneyRun nl = static_press(true, 1.0);
  EXPECT_NEAR(nl.contact, 5.08, 0.05);
  EXPECT_NEAR(nl.mid_atom, 1.71, 0.03);
  EXPECT_NEAR(nl.max_other, 1.50, 0.03);
  const KidneyRun lin = static_press(false, 1.0);
  EXPECT_LE(nl.contact, lin.contact);  // hard springs: nonlinear displacement <= linear
  const KidneyRun light = static_press(true, 0.2);
  EXPECT_LT(light.contact, nl.contact);
  EXPECT_GT(light.mid_atom, 0.0);  // global deformation: the skeleton moves
}

TEST(HybridKidney, ForceThenReleaseReturnsToRestWithin200ms) {  // §7.1, §8.2-12
  const HybridKidney k = hybrid_kidney_phantom();
  const Model& m = k.model();
  State s = make_state(m);
  const Index c = 223;
  const Vec3 F = -(m.x0.row(c) - m.x0.row(k.atom_dof(21))).normalized().transpose();
  std::vector<PointLoad> loads{{.node = c, .force = F, .t_ramp = 20, .t_release = 500}};
  while (s.t < 500 - 1e-9) step(m, s, {.dt = 0.5}, &loads);
  EXPECT_NEAR((s.x.row(c) - m.x0.row(c)).norm(), 5.08, 0.06);
  double t_back = -1;
  while (s.t < 1000 - 1e-9) {
    step(m, s, {.dt = 0.5}, &loads);
    if (t_back < 0 && (s.x - m.x0).rowwise().norm().maxCoeff() < 1e-3) t_back = s.t - 500;
  }
  EXPECT_GT(t_back, 0);
  EXPECT_LT(t_back, 200);
  EXPECT_EQ(s.warnings.total(), 0u);
  // surface map = the first 458 DOFs
  MatX3 S;
  k.map_to_surface(s, S);
  EXPECT_EQ(S.rows(), 458);
  EXPECT_EQ(S, s.x.topRows(458));
}

TEST(HybridKidney, BuildIsDeterministic) {  // §8.5-26
  const HybridKidney a = hybrid_kidney_phantom(), b = hybrid_kidney_phantom();
  EXPECT_EQ(a.spokes(), b.spokes());
  EXPECT_EQ(a.model().springs.L0, b.model().springs.L0);
}

TEST(HybridKidney, RejectsBadInput) {
  const SurfaceMesh m = kidney_phantom();
  EXPECT_THROW(HybridKidney(m, kidney_phantom_atoms(42).topRows(1)), InvalidInput);
  MatX3 coincident = kidney_phantom_atoms(5);
  coincident.row(3) = coincident.row(2);
  EXPECT_THROW(HybridKidney(m, coincident), InvalidInput);
  HybridSettings st;
  st.k_surf = -1;
  EXPECT_THROW(HybridKidney(m, kidney_phantom_atoms(42), st), InvalidInput);
  st = {};
  st.fixed = {1000};
  EXPECT_THROW(HybridKidney(m, kidney_phantom_atoms(42), st), InvalidInput);
}

TEST(HybridKidney, FixedAtomsStayAtRestWhileTheOthersMove) {  // fixed_atoms (CONTRIBUTING.md example)
  HybridSettings settings;
  settings.fixed_atoms = {42};
  EXPECT_THROW(hybrid_kidney_phantom(settings), InvalidInput);  // 42 atoms: 0..41
  settings.fixed_atoms = {0, 41};
  const HybridKidney k = hybrid_kidney_phantom(settings);
  State s = make_state(k.model());
  const Vec3 F(0.0, 0.0, -1.0);
  for (int i = 0; i < 200; ++i) {  // 100 ms under 1 N on the top node
    s.f_ext.setZero();
    k.transfer_force(223, F, s.f_ext);
    step(k.model(), s, {.dt = 0.5});
  }
  const auto moved = [&](Index a) {
    return (s.x.row(k.atom_dof(a)) - k.model().x0.row(k.atom_dof(a))).norm();
  };
  EXPECT_EQ(moved(0), 0.0);
  EXPECT_EQ(moved(41), 0.0);
  EXPECT_GT(moved(21), 1e-3);  // the middle atom is free and follows the load
}

}  // namespace
}  // namespace medspring
