// ALGORITHMS.md §5.2 and §8.2 check 9: the SMRM centerline chain built by make_chain_model.
#include "medspring/medial/chain.hpp"

#include <gtest/gtest.h>

#include "medspring/core/error.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/physics/static_solve.hpp"

namespace medspring {
namespace {

TEST(CenterlineChain, VesselDefaultsOfSection9) {  // §5.2, §9
  const Model m = make_chain_model(vessel_phantom_atoms(VesselPath::Helix));
  ASSERT_EQ(m.num_nodes(), 40);
  ASSERT_EQ(m.num_springs(), 39);
  EXPECT_TRUE(m.fixed[0] && m.fixed[39]);
  for (Index i = 1; i < 39; ++i) EXPECT_FALSE(m.fixed[static_cast<std::size_t>(i)]);
  for (Index i = 0; i < 40; ++i) {
    EXPECT_EQ(m.mass[i], 0.5);
    EXPECT_EQ(m.damping[i], 0.25);  // beta m
    EXPECT_EQ(m.kr[i], 0.02);
  }
  for (Index s = 0; s < 39; ++s) {
    EXPECT_EQ(m.springs.k[s], 0.2);
    const double L0 = m.springs.L0[s];
    EXPECT_NEAR(m.springs.kp[s], 0.2 / (L0 * L0), 1e-15);  // D-3 Strain, eta = 1
  }
  EXPECT_EQ(m.bending.size(), 0);
  const Model lin = make_chain_model(vessel_phantom_atoms(VesselPath::Helix), {.nonlinear = false});
  for (Index s = 0; s < 39; ++s) EXPECT_EQ(lin.springs.kp[s], 0.0);
}

TEST(CenterlineChain,
     ReferenceEquilibriumOfSection82) {  // §8.2-9 through the chain builder (k_r = 0.05), 1e-3 mm
  const MatX3 C0 = vessel_phantom_atoms(VesselPath::StraightX);
  MatX3 f = MatX3::Zero(40, 3);
  f(19, 1) = 0.5;
  const Model nl = make_chain_model(C0, {.kr = 0.05});
  const Model lin = make_chain_model(C0, {.kr = 0.05, .nonlinear = false});
  EXPECT_NEAR(static_equilibrium(nl, f).x(19, 1), 4.5915, 1e-3);
  EXPECT_NEAR(static_equilibrium(lin, f).x(19, 1), 4.6448, 1e-3);
  f(19, 1) = 0.05;
  EXPECT_NEAR(static_equilibrium(nl, f).x(19, 1), 0.8675, 1e-3);
}

TEST(CenterlineChain, OptionalBendingSpringsStiffenTheChain) {  // §5.2 option
  const MatX3 C0 = vessel_phantom_atoms(VesselPath::StraightX);
  const Model bent = make_chain_model(C0, {.kb = 0.05});
  EXPECT_EQ(bent.bending.size(), 38);
  MatX3 f = MatX3::Zero(40, 3);
  f(20, 1) = 0.05;
  const double plain = static_equilibrium(make_chain_model(C0), f).x(20, 1);
  EXPECT_LT(static_equilibrium(bent, f).x(20, 1), 0.5 * plain);
}

TEST(CenterlineChain, FreeEndsAndBadInput) {
  const MatX3 C0 = vessel_phantom_atoms(VesselPath::Arc, 5);
  const Model m = make_chain_model(C0, {.fix_first = false});
  EXPECT_FALSE(m.fixed[0]);
  EXPECT_TRUE(m.fixed[4]);
  MatX3 bad = C0;
  bad.row(3) = bad.row(2);
  try {
    make_chain_model(bad);
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("atoms 2 and 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(make_chain_model(MatX3::Zero(1, 3)), InvalidInput);
  EXPECT_THROW(make_chain_model(C0, {.mass = 0.0}), InvalidInput);
}

}  // namespace
}  // namespace medspring
