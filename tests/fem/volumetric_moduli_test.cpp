// Effective moduli of a volumetric spring mesh and the opt-in moduli correction (issue 23,
// models/volumetric_moduli.hpp, docs/volumetric.md "Effective moduli of the mesh").
#include "medspring/models/volumetric_moduli.hpp"

#include <gtest/gtest.h>

#include <iostream>

#include "medspring/core/error.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/model.hpp"
#include "volumetric_fixtures.hpp"

using namespace medspring;
using medspring::testing::box_surface;
using medspring::testing::one_tet;

// Effective moduli of a mesh (models/volumetric_moduli.hpp, docs/volumetric.md "Effective moduli of the
// mesh"): exact for the P1 finite element (homogeneous fields are in its space) under both boundary
// conditions; exact for one tetrahedron of the spring rule (bulk modulus, and the mean over the five
// deviatoric modes is the isotropic part, i.e. mu); and on a TetGen cube the relaxed network stays close.
TEST(MeshModuli, P1ElementsGiveTheExactModuliUnderUniformStrainAndUniformTraction) {
  const double L = 20;
  const VolumetricMesh m = fem::volumetric_mesh(box_surface(6, L), {.target_nodes = 600});
  double mu = 0, la = 0;
  lame_parameters(10, 0.3, mu, la, "test");
  const MeshModuli mm = mesh_moduli(p1_stiffness(m.X, m.T, mu, la), m.X, m.surface_nodes, L * L * L, &m.F);
  const double K = la + 2 * mu / 3;
  EXPECT_NEAR(mm.mu / mu, 1.0, 1e-8);
  EXPECT_NEAR(mm.mu_min / mu, 1.0, 1e-8);
  EXPECT_NEAR(mm.mu_max / mu, 1.0, 1e-8);
  EXPECT_NEAR(mm.K / K, 1.0, 1e-8);
  EXPECT_NEAR(mm.mu_traction / mu, 1.0, 1e-6);
  EXPECT_NEAR(mm.K_traction / K, 1.0, 1e-6);
  EXPECT_NEAR(mm.nu(), 0.3, 1e-8);
  EXPECT_NEAR(mm.E() * 1e3, 10.0, 1e-7);
}

TEST(MeshModuli, OneTetrahedronOfTheSpringRuleHasMuAndKExactly) {
  MatX3 X(4, 3);
  X << 0, 0, 0, 3, 0.2, 0, 0.5, 2.5, 0.1, 0.7, 0.4, 2.2;  // irregular
  for (double nu : {0.3, 0.45}) {
    VolumetricSettings st;
    st.nu = nu;
    st.fixed = {0, 1, 2};
    const VolumetricBody body(one_tet(X), st, "tet");
    const MeshModuli mm = mesh_moduli(body.model(), 4);  // every node on the boundary: affine
    const double mu = body.stats().mu, K = body.stats().lambda + 2 * mu / 3;
    EXPECT_NEAR(mm.mu / mu, 1.0, 1e-9) << "nu " << nu;  // the isotropic part of the springs is mu
    EXPECT_NEAR(mm.K / K, 1.0, 1e-9) << "nu " << nu;    // bulk exact for every shape
    EXPECT_LT(mm.mu_min, 0.99 * mu) << "one tetrahedron is anisotropic";
    EXPECT_GT(mm.mu_max, 1.01 * mu);
  }
}

TEST(MeshModuli, TetgenCubeRelaxesLittleBelowTheRule) {
  const double L = 20;
  const VolumetricMesh m = fem::volumetric_mesh(box_surface(6, L), {.target_nodes = 900});
  for (double nu : {0.3, 0.45}) {
    VolumetricSettings st;
    st.nu = nu;
    st.return_k = 0.0;
    st.fixed = {0, 1, 2, 3};
    const VolumetricBody body(m, st, "cube");
    const MeshModuli mm = mesh_moduli(body.model(), m.surface_nodes, 0, &m.F);
    const double mu = body.stats().mu, K = body.stats().lambda + 2 * mu / 3;
    std::cout << "cube " << m.X.rows() << " nodes, nu = " << nu << ": mu/mu " << mm.mu_traction / mu << " .. "
              << mm.mu / mu << ", K/K " << mm.K_traction / K << " .. " << mm.K / K << ", nu_eff " << mm.nu()
              << "\n";
    EXPECT_NEAR(mm.volume, L * L * L, 1e-6 * L * L * L);
    EXPECT_NEAR(mm.mu_affine / mu, 1.0, 0.03);  // the rule holds on average over the mesh's orientations
    EXPECT_NEAR(mm.K_affine / K, 1.0, 1e-9);    // and exactly for the bulk modulus
    EXPECT_LE(mm.mu, mm.mu_affine * (1 + 1e-9)) << "relaxation only lowers the energy";
    EXPECT_LE(mm.mu_traction, mm.mu * (1 + 1e-9)) << "uniform traction is the lower bound";
    EXPECT_LE(mm.K_traction, mm.K * (1 + 1e-9));
    EXPECT_GT(mm.mu_traction / mu, 0.85);
    EXPECT_GT(mm.K_traction / K, 0.85);
    EXPECT_NEAR(mm.nu(), nu, 0.03);
  }
  EXPECT_THROW(mesh_moduli(p1_stiffness(m.X, m.T, 1, 1), m.X, 0, 1.0), InvalidInput);
}

TEST(MeshModuli, TheOptInCorrectionBringsTheCubesModuliToTheTarget) {
  const double L = 20;
  const VolumetricMesh m = fem::volumetric_mesh(box_surface(6, L), {.target_nodes = 900});
  for (double nu : {0.3, 0.45}) {
    VolumetricSettings st;
    st.nu = nu;
    st.return_k = 0.0;
    st.fixed = {0, 1, 2, 3};
    st.moduli_correction = true;
    const VolumetricBody body(m, st, "cube");
    const MeshModuli mm = mesh_moduli(body.model(), m.surface_nodes, 0, &m.F);
    const double mu = body.stats().mu, K = body.stats().lambda + 2 * mu / 3;
    std::cout << "cube, nu = " << nu << ", corrected: springs x " << body.stats().spring_correction
              << ", volume terms x " << body.stats().volume_correction << "; mu/mu "
              << 0.5 * (mm.mu + mm.mu_traction) / mu << ", K/K " << 0.5 * (mm.K + mm.K_traction) / K
              << " (before " << body.stats().mu_ratio_before << ", " << body.stats().K_ratio_before << ")\n";
    EXPECT_NEAR(0.5 * (mm.mu + mm.mu_traction) / mu, 1.0, 0.01) << "nu " << nu;
    EXPECT_NEAR(0.5 * (mm.K + mm.K_traction) / K, 1.0, 0.01) << "nu " << nu;
    EXPECT_LT(body.stats().mu_ratio_before, 0.99);
    EXPECT_GT(body.stats().spring_correction, 1.01);
    // the body keeps the corrected scales and the flag off: rebuilding from settings() is the same model
    EXPECT_FALSE(body.settings().moduli_correction);
    const VolumetricBody again(m, body.settings(), "cube");
    EXPECT_EQ(model_fingerprint(again.model()), model_fingerprint(body.model()));
  }
}
