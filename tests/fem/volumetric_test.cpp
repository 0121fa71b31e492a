// The volumetric spring organ (issue 23, docs/volumetric.md): the volume term against finite differences,
// the stiffness rule against linear elasticity on a single tetrahedron and on a cube, bad input refused
// with the defect named, inversion during a run counted, and the TetGen build at a node count.
#include "medspring/fem/volumetric.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <map>
#include <random>

#include "medspring/core/error.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/tet_mesh.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/static_solve.hpp"
#include "volumetric_box.hpp"
#include "volumetric_fixtures.hpp"

using namespace medspring;
using medspring::testing::box_surface;
using medspring::testing::one_tet;

namespace {

MatX3 regular_tet(double l) {
  MatX3 X(4, 3);
  const double s = l / std::sqrt(8.0);
  X << s, s, s, s, -s, -s, -s, s, -s, -s, -s, s;
  if (signed_tet_volume(X.row(0), X.row(1), X.row(2), X.row(3)) < 0) X.row(1).swap(X.row(2));
  return X;
}

// A model with one volume term (no springs) on a skewed tetrahedron.
Model volume_only(double kv) {
  ModelBuilder b("vol");
  const Vec3 p[4] = {Vec3(0, 0, 0), Vec3(2, 0.3, 0.1), Vec3(0.4, 1.7, -0.2), Vec3(0.3, 0.5, 1.9)};
  for (const Vec3& q : p) b.add_node(q, 1.0, 0.5, 0.0);
  b.set_fixed(0);
  b.add_volume(0, 1, 2, 3, kv);
  return b.build();
}

// Cube [0, L]^3 meshed by fem::box_mesh (Kuhn split) as a VolumetricMesh (corners only, surface first).
VolumetricMesh cube_mesh(int cells, double L) {
  std::vector<double> xs;
  for (int i = 0; i <= cells; ++i) xs.push_back(L * i / cells);
  return medspring::testing::box(xs, xs, xs);
}

// Effective Young's modulus (kPa) and Poisson ratio of a box [0, L]^3 mesh under opposite uniform tractions
// sigma on its faces z = 0 and z = L (tiny return springs against rigid motion): mean face displacements.
std::pair<double, double> uniaxial(const VolumetricMesh& vm, double L, double nu) {
  const double sigma = 1e-5;  // N/mm^2 (1e-3 of E): linear range
  VolumetricSettings st;
  st.E_kPa = 10;
  st.nu = nu;
  st.return_k = 1e-9;
  const VolumetricBody body(vm, st, "box");
  const Model& m = body.model();
  MatX3 f = MatX3::Zero(m.num_nodes(), 3);
  for (Index t = 0; t < vm.F.rows(); ++t) {
    const Vec3 a = vm.X.row(vm.F(t, 0)), b = vm.X.row(vm.F(t, 1)), c = vm.X.row(vm.F(t, 2));
    const Vec3 n = (b - a).cross(c - a);
    if (std::abs(std::abs(n.normalized()(2)) - 1) > 1e-9) continue;
    const double A = 0.5 * n.norm();
    for (int k = 0; k < 3; ++k) f(vm.F(t, k), 2) += (a(2) > L / 2 ? 1 : -1) * sigma * A / 3;
  }
  const StaticResult r = static_equilibrium(m, f);
  const MatX3 u = r.x - m.x0;
  double top = 0, bot = 0, xp = 0, xm = 0;
  int nt = 0, nb = 0, np = 0, nm = 0;
  for (Index i = 0; i < body.num_surface_nodes(); ++i) {
    if (std::abs(m.x0(i, 2) - L) < 1e-9) top += u(i, 2), ++nt;
    if (std::abs(m.x0(i, 2)) < 1e-9) bot += u(i, 2), ++nb;
    if (std::abs(m.x0(i, 0) - L) < 1e-9) xp += u(i, 0), ++np;
    if (std::abs(m.x0(i, 0)) < 1e-9) xm += u(i, 0), ++nm;
  }
  const double ezz = (top / nt - bot / nb) / L, exx = (xp / np - xm / nm) / L;
  return {sigma / ezz * 1e3, -exx / ezz};
}

}  // namespace

TEST(VolumeTerm, EnergyForcesAndStiffnessMatchFiniteDifferences) {
  const Model m = volume_only(0.3);
  MatX3 x = m.x0;
  x.row(1) += Vec3(0.2, -0.1, 0.05).transpose();  // volume strain ~ 10 %
  x.row(3) += Vec3(-0.1, 0.15, 0.3).transpose();
  MatX3 f(4, 3), zero = MatX3::Zero(4, 3);
  internal_forces(m, x, zero, f);
  const double h = 1e-6;
  for (Index a = 0; a < 4; ++a)
    for (int c = 0; c < 3; ++c) {
      MatX3 xp = x, xm = x;
      xp(a, c) += h;
      xm(a, c) -= h;
      const double fd = -(potential_energy(m, xp) - potential_energy(m, xm)) / (2 * h);
      EXPECT_NEAR(f(a, c), fd, 1e-7 * (1 + std::abs(fd))) << "node " << a << " comp " << c;
    }
  // the tangent stiffness is minus the derivative of the forces
  const Eigen::MatrixXd K = Eigen::MatrixXd(tangent_stiffness(m, x, {.include_return = true}));
  for (Index a = 0; a < 4; ++a)
    for (int c = 0; c < 3; ++c) {
      MatX3 xp = x, xm = x, fp(4, 3), fm(4, 3);
      xp(a, c) += h;
      xm(a, c) -= h;
      internal_forces(m, xp, zero, fp);
      internal_forces(m, xm, zero, fm);
      const MatX3 col = -(fp - fm) / (2 * h);
      for (Index b = 0; b < 4; ++b)
        for (int r = 0; r < 3; ++r)
          EXPECT_NEAR(K(3 * b + r, 3 * a + c), col(b, r), 1e-6 * (1 + K.cwiseAbs().maxCoeff()));
    }
  // energy at rest is zero and grows quadratically in the volume strain
  EXPECT_EQ(potential_energy(m, m.x0), 0.0);
  const double V0 = m.volume.V0[0];
  const double V = signed_tet_volume(x.row(0), x.row(1), x.row(2), x.row(3));
  EXPECT_NEAR(potential_energy(m, x), 0.5 * 0.3 * (V - V0) * (V - V0) / V0, 1e-15);
}

TEST(VolumeTerm, StableStepAccountsForTheVolumeTerm) {
  ModelBuilder with("with"), without("without");
  const Vec3 p[4] = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 2)};
  for (const Vec3& q : p) {
    with.add_node(q, 1.0, 0.5, 0.0);
    without.add_node(q, 1.0, 0.5, 0.0);
  }
  for (Index a = 0; a < 4; ++a)
    for (Index b = a + 1; b < 4; ++b) {
      with.add_spring(a, b, 0.1, DuffingSettings{DuffingMode::Linear});
      without.add_spring(a, b, 0.1, DuffingSettings{DuffingMode::Linear});
    }
  with.add_volume(0, 1, 2, 3, 2.0);
  const Model mw = with.build(), mo = without.build();
  EXPECT_GT(mw.omega_rest, 1.5 * mo.omega_rest);        // the stiff volume term raises omega_max ...
  EXPECT_LE(mw.omega_rest, 1.2 * mw.omega_gershgorin);  // ... within the Gershgorin bound (+ power safety)
  // an explicit run at the model's own stable step stays bounded (no energy growth)
  State s = make_state(mw);
  s.x.row(1) += Vec3(0.3, 0.1, 0).transpose();
  const double e0 = total_energy(mw, s.x, s.v);
  for (int i = 0; i < 2000; ++i) step(mw, s, {.dt = 0.5});
  EXPECT_TRUE(s.x.allFinite());
  EXPECT_LT(total_energy(mw, s.x, s.v), e0);
  EXPECT_EQ(s.warnings.total(), 0u);
}

TEST(Volumetric, SingleTetrahedronHasTheExactBulkModulus) {
  for (double nu : {0.3, 0.45, 0.49}) {
    VolumetricSettings st;
    st.E_kPa = 10;
    st.nu = nu;
    st.fixed = {0, 1, 2};
    MatX3 X(4, 3);
    X << 0, 0, 0, 3, 0.2, 0, 0.5, 2.5, 0.1, 0.7, 0.4, 2.2;  // an irregular tetrahedron
    const VolumetricBody body(one_tet(X), st, "tet");
    const double e = 1e-5;
    const double V = body.stats().volume_mm3;
    const double K = body.stats().lambda + 2.0 * body.stats().mu / 3.0;
    const MatX3 x = (1.0 + e) * X;
    const double W = potential_energy(body.model(), x);
    EXPECT_NEAR(W / (0.5 * V * K * 9 * e * e), 1.0, 1e-3) << "nu " << nu;
  }
}

TEST(Volumetric, RegularTetrahedronMatchesLinearElasticityOnAverageOverOrientations) {
  // The isotropic part of one tetrahedron's springs + volume term is the linear-elastic tensor: the energy
  // of a strain, averaged over random orientations of the tetrahedron, is V (mu e:e + lambda/2 tr(e)^2).
  VolumetricSettings st;
  st.E_kPa = 10;
  st.nu = 0.45;
  st.fixed = {0, 1, 2};
  const MatX3 X = regular_tet(4.0);
  const VolumetricBody body(one_tet(X), st, "tet");
  const double V = body.stats().volume_mm3, mu = body.stats().mu, la = body.stats().lambda;
  Mat3 eps;
  eps << 1, 0.4, -0.2, 0.4, -0.5, 0.3, -0.2, 0.3, 0.2;  // general strain
  eps *= 1e-5;
  const double target = V * (mu * (eps.array() * eps.array()).sum() + 0.5 * la * eps.trace() * eps.trace());
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  double sum = 0;
  const int N = 6000;
  for (int i = 0; i < N; ++i) {
    const Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
    const Mat3 R = q.normalized().toRotationMatrix();
    const Mat3 e = R * eps * R.transpose();
    MatX3 x = X;
    for (Index a = 0; a < 4; ++a) x.row(a) += (e * X.row(a).transpose()).transpose();
    sum += potential_energy(body.model(), x);
  }
  EXPECT_NEAR(sum / N / target, 1.0, 0.03);  // Monte Carlo: ~1 % standard error at N = 6000
}

TEST(Volumetric, CubeUnderUniaxialTractionGivesYoungsModulusAndPoissonRatio) {
  // Homogeneous uniaxial stress: linear elasticity gives strain sigma / E along z and -nu sigma / E across.
  // On an unstructured TetGen mesh (edges of all orientations) the rule of docs/volumetric.md comes close;
  // on the structured Kuhn split (every cell's edges along the axes, face and body diagonals) the springs
  // are anisotropic (cubic symmetry) and nu is underestimated: reported, loosely bounded.
  const double L = 20;
  const fem::VolumetricMeshSettings ms{.target_nodes = 900};
  const VolumetricMesh unstructured = fem::volumetric_mesh(box_surface(6, L), ms);
  const VolumetricMesh kuhn = cube_mesh(4, L);
  for (double nu : {0.3, 0.45}) {
    const auto [E_u, nu_u] = uniaxial(unstructured, L, nu);
    const auto [E_k, nu_k] = uniaxial(kuhn, L, nu);
    std::cout << "cube, nu = " << nu << ": TetGen " << unstructured.X.rows() << " nodes: E_eff = " << E_u
              << " kPa (10), nu_eff = " << nu_u << "; Kuhn " << kuhn.X.rows() << " nodes: E_eff = " << E_k
              << " kPa, nu_eff = " << nu_k << "\n";
    EXPECT_NEAR(E_u / 10.0, 1.0, 0.15) << "nu " << nu;
    EXPECT_NEAR(nu_u, nu, 0.05) << "nu " << nu;
    EXPECT_NEAR(E_k / 10.0, 1.0, 0.3) << "nu " << nu;
    EXPECT_NEAR(nu_k, nu, 0.15) << "nu " << nu;
  }
}

TEST(Volumetric, BadInputIsRefusedWithTheDefectNamed) {
  const MatX3 X = regular_tet(4.0);
  auto expect_refused = [](auto&& build, const std::string& needle) {
    try {
      build();
      ADD_FAILURE() << "accepted; expected '" << needle << "'";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  VolumetricSettings st;
  st.fixed = {0, 1, 2};
  expect_refused(
      [&] {
        VolumetricSettings s = st;
        s.nu = 0.5;
        VolumetricBody b(one_tet(X), s);
      },
      "nu: must be in (-1, 0.5)");
  expect_refused(
      [&] {
        VolumetricSettings s = st;
        s.E_kPa = 0;
        VolumetricBody b(one_tet(X), s);
      },
      "E_kPa: must be > 0");
  expect_refused(
      [&] {
        VolumetricMesh m = one_tet(X);
        std::swap(m.T(0, 1), m.T(0, 2));
        VolumetricBody b(m, st);
      },
      "is inverted");
  expect_refused(
      [&] {
        MatX3 Y = X;
        Y.row(3) = (Y.row(0) + Y.row(1) + Y.row(2)) / 3;  // flat
        VolumetricBody b(one_tet(Y), st);
      },
      "is degenerate");
  expect_refused(
      [&] {  // an interior node outside the surface
        VolumetricMesh m = one_tet(X);
        m.X.conservativeResize(5, 3);
        m.X.row(4) = Vec3(10, 10, 10).transpose();
        m.T.resize(4, 4);
        m.T << 4, 0, 1, 2, 4, 0, 3, 1, 4, 1, 3, 2, 4, 0, 2, 3;
        VolumetricBody b(m, st);
      },
      "interior node 4");
  expect_refused(
      [&] {
        VolumetricSettings s = st;
        s.fixed = {0, 1};
        s.return_k = 0.0;
        VolumetricBody b(one_tet(X), s);
      },
      "collinear");
  expect_refused(
      [&] {
        VolumetricSettings s = st;
        s.fixed = {};
        s.return_k = 0.0;
        VolumetricBody b(one_tet(X), s);
      },
      "every rigid motion is free");
  expect_refused(
      [&] {
        VolumetricMesh m = one_tet(X);
        m.F.conservativeResize(3, 3);  // a face missing: the surface is not the mesh's boundary
        VolumetricBody b(m, st);
      },
      "boundary face");
  // return springs off by default with supports, on without
  const VolumetricBody held(one_tet(X), st);
  EXPECT_EQ(held.model().kr.maxCoeff(), 0.0);
  VolumetricSettings free_body;
  const VolumetricBody anchored(one_tet(X), free_body);
  EXPECT_GT(anchored.model().kr.minCoeff(), 0.0);
}

TEST(Volumetric, InversionDuringARunIsCountedNotNaN) {
  VolumetricSettings st;
  st.fixed = {0, 1, 2};
  const MatX3 X = regular_tet(4.0);
  const VolumetricBody body(one_tet(X), st, "tet");
  State s = make_state(body.model());
  // push the free corner through the opposite face with a force far above the tetrahedron's stiffness
  const Vec3 c = (X.row(0) + X.row(1) + X.row(2)).transpose() / 3;
  const Vec3 dir = (c - X.row(3).transpose()).normalized();
  body.transfer_force(3, 5.0 * dir, s.f_ext);
  for (int i = 0; i < 400; ++i) step(body.model(), s, {.dt = 0.5});
  EXPECT_TRUE(s.x.allFinite());
  EXPECT_GT(s.warnings.inverted_elements, 0u);
  EXPECT_GE(s.warnings.total(), s.warnings.inverted_elements);
}

TEST(Volumetric, TetgenBuildAimsAtTheNodeCountAndKeepsTheSurface) {
  const SurfaceMesh surf = kidney_phantom();
  for (Index target : {800, 2000}) {
    const VolumetricMesh vm = fem::volumetric_mesh(surf, {.target_nodes = target});
    EXPECT_NEAR(static_cast<double>(vm.X.rows()), static_cast<double>(target), 0.25 * target);
    EXPECT_EQ(vm.surface_nodes, surf.num_vertices());
    EXPECT_EQ((vm.X.topRows(vm.surface_nodes) - surf.V).cwiseAbs().maxCoeff(), 0.0);
    VolumetricSettings st;
    st.return_k = 0.02;
    const VolumetricBody body(vm, st, "kidney");
    EXPECT_EQ(body.kind(), "volumetric");
    EXPECT_EQ(body.num_surface_nodes(), surf.num_vertices());
    EXPECT_EQ(body.model().volume.size(), vm.T.rows());
    // a load on a surface node moves the surface through the identity map
    State s = make_state(body.model());
    body.transfer_force(10, Vec3(0, 0, -0.01), s.f_ext);  // a point load: 0.2 N would invert tetrahedra
    for (int i = 0; i < 50; ++i) step(body.model(), s, {.dt = 0.5});
    MatX3 surface;
    body.map_to_surface(s, surface);
    EXPECT_EQ(surface.rows(), surf.num_vertices());
    EXPECT_GT((surface.row(10) - surf.V.row(10)).norm(), 1e-4);
    EXPECT_EQ(s.warnings.total(), 0u)
        << "nonfinite " << s.warnings.nonfinite << " vmax " << s.warnings.velocity_limit << " capped "
        << s.warnings.substeps_capped << " failed " << s.warnings.failed << " inverted "
        << s.warnings.inverted_elements;
  }
  EXPECT_THROW(fem::volumetric_mesh(surf, {.target_nodes = 10}), InvalidInput);
}

// surface_subdivisions (docs/accuracy-nonlinear.md, "The load site"): the model's surface is the given one
// subdivided at edge midpoints (the same polyhedron, 4x the faces), its first #V nodes the given vertices,
// unmoved.
TEST(Volumetric, SubdividedSurfaceKeepsTheGivenVerticesFirstAndTheSamePolyhedron) {
  const SurfaceMesh surf = kidney_phantom();
  const Index nv = surf.num_vertices(), nf = surf.num_faces();
  const VolumetricMesh vm = fem::volumetric_mesh(surf, {.target_nodes = 4 * nv, .surface_subdivisions = 1});
  EXPECT_EQ(vm.surface_nodes, nv + 3 * nf / 2);  // V + E on a closed triangle surface
  EXPECT_EQ(vm.F.rows(), 4 * nf);
  EXPECT_EQ((vm.X.topRows(nv) - surf.V).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(vm.X.rows(), vm.surface_nodes);  // an interior
  EXPECT_NEAR(std::abs(signed_volume(vm.X.topRows(vm.surface_nodes), vm.F)),
              std::abs(signed_volume(surf.V, surf.F)), 1e-9 * std::abs(signed_volume(surf.V, surf.F)));
  // the target counts the refined surface's vertices; the subdivision count is bounded
  EXPECT_THROW(fem::volumetric_mesh(surf, {.target_nodes = 2 * nv, .surface_subdivisions = 1}), InvalidInput);
  EXPECT_THROW(fem::volumetric_mesh(surf, {.target_nodes = 4 * nv, .surface_subdivisions = 4}), InvalidInput);
}

TEST(Volumetric, ModelPackageRebuildsTheSameModel) {
  const VolumetricMesh vm = fem::volumetric_mesh(kidney_phantom(), {.target_nodes = 700});
  VolumetricSettings st;
  st.E_kPa = 12;
  st.nu = 0.4;
  st.fixed = {0, 1, 2, 3, 4, 5};
  const VolumetricBody body(vm, st, "kidney");
  const ModelPackage p = decode_model_package(encode_model_package(package_of(body, "vol")), "test");
  EXPECT_EQ(p.kind, "volumetric");
  const BodyPtr again = make_body(p);
  EXPECT_EQ(again->kind(), "volumetric");
  EXPECT_TRUE(check_fingerprint(p, *again));
  EXPECT_EQ(model_fingerprint(again->model()), model_fingerprint(body.model()));
}

namespace medspring {
namespace {

// The organ tables' solvers (docs/accuracy.md): the modified Newton (kept factorisation) reaches the same
// equilibrium as full Newton, and the small-strain response (one factorisation, fem::spring_displacement_
// linear) is the nonlinear static response in the limit of a small load.
TEST(VolumetricStatics, ModifiedNewtonAndSmallStrainResponseAgreeWithFullNewton) {
  const double L = 20;
  const VolumetricMesh mesh = cube_mesh(3, L);
  VolumetricSettings s;
  for (Index i = 0; i < mesh.surface_nodes; ++i)
    if (mesh.X(i, 2) < 1e-9) s.fixed.push_back(i);  // the bottom face
  const VolumetricBody body(mesh, s, "cube");
  const Model& m = body.model();
  MatX3 f = MatX3::Zero(m.num_nodes(), 3);
  Index top = 0;
  for (Index i = 0; i < mesh.surface_nodes; ++i)
    if ((mesh.X.row(i) - Vec3(L / 3, L / 3, L).transpose()).norm() <
        (mesh.X.row(top) - Vec3(L / 3, L / 3, L).transpose()).norm())
      top = i;
  f.row(top) = Vec3(0.01, 0, -0.05).transpose();  // a large load: several Newton steps
  StaticSettings full, kept;
  full.tolerance = kept.tolerance = 1e-9;
  kept.reuse_tangent = true;
  const StaticResult a = static_equilibrium(m, f, full), b = static_equilibrium(m, f, kept);
  const double u = (a.x - m.x0).rowwise().norm().maxCoeff();
  EXPECT_GT(u, 0.5) << "the load should deform the cube visibly (mm)";
  EXPECT_LT((a.x - b.x).cwiseAbs().maxCoeff(), 1e-6 * u);

  const fem::ContactLoad small{Vec3(L / 2, L / 2, L), Vec3(0, 0, -1e-5), 5.0};
  const MatX3 lin = fem::spring_displacement_linear(body, {small}).at(0);
  const MatX3 nl = fem::spring_displacement(body, small);
  const double peak = nl.rowwise().norm().maxCoeff();
  EXPECT_GT(peak, 0.0);
  EXPECT_LT((lin - nl).rowwise().norm().maxCoeff(), 1e-3 * peak);
}

}  // namespace
}  // namespace medspring

// The support rule of an organ that no single slab holds (docs/accuracy-volumetric.md, "The aorta"): a bed of
// the surface facing away from the load plus a cut cap; the FEM and the spring model hold the same region,
// and a rule that holds a single point (every rotation about it free) is refused on both sides.
TEST(SupportRule, AFacingBedAndACapHoldAVesselLikeOrganAndALonePointIsRefused) {
  SurfaceMesh s = icosphere(2, 10.0);
  s.V.col(0) *= 4.0;  // a 80 x 20 x 20 mm cigar
  fem::SupportRule rule{Vec3(0, 0, -1), 0.0};
  rule.facing_deg = 60;
  rule.caps = {{Vec3(-1, 0, 0), 1.0}};
  MatX3 N;
  vertex_normals(s.V, s.F, N);
  const std::vector<Index> held = fem::support_nodes(s, rule);
  const double xmin = s.V.col(0).minCoeff();
  std::vector<char> in(static_cast<std::size_t>(s.num_vertices()), 0);
  for (Index i : held) in[static_cast<std::size_t>(i)] = 1;
  Index bed = 0, cap = 0;
  for (Index i = 0; i < s.num_vertices(); ++i) {
    const bool facing = -N(i, 2) >= 0.5, at_cap = s.V(i, 0) <= xmin + 1.0;
    const bool lowest = s.V(i, 2) == s.V.col(2).minCoeff();
    EXPECT_EQ(in[static_cast<std::size_t>(i)] != 0, facing || at_cap || lowest) << "node " << i;
    bed += facing ? 1 : 0;
    cap += at_cap ? 1 : 0;
  }
  EXPECT_GT(bed, 20);
  EXPECT_GE(cap, 1);
  // the bed runs along the whole organ (a slab under the lowest point would not)
  double lo = 1e9, hi = -1e9;
  for (Index i : held)
    if (-N(i, 2) >= 0.5) lo = std::min(lo, s.V(i, 0)), hi = std::max(hi, s.V(i, 0));
  EXPECT_LT(lo, -25.0);
  EXPECT_GT(hi, 25.0);
  EXPECT_THROW(fem::support_nodes(s.V, rule), InvalidInput);  // needs the normals
  fem::SupportRule bad = rule;
  bad.facing_deg = 120;
  EXPECT_THROW(fem::support_nodes(s, bad), InvalidInput);

  // the FEM holds the same region of its boundary: every fixed node faces away or lies at the cap
  const fem::OrganReference ref(s, fem::Material::from_kpa(10, 0.45), rule);
  EXPECT_GT(ref.fixed_fem_nodes().size(), held.size());  // corners and mid-edge nodes
  for (Index i : ref.fixed_fem_nodes())
    EXPECT_TRUE(ref.mesh().X(i, 2) < 0 || ref.mesh().X(i, 0) <= xmin + 1.0) << "FEM node " << i;

  // the lowest point(s) held (one, or two on a line): refused by the FEM (rigid motions free) and by the
  // volumetric kind (no return springs)
  const fem::SupportRule lone{Vec3(0, 0, -1), 0.0};
  ASSERT_LE(fem::support_nodes(s, lone).size(), 2u);
  try {
    const fem::OrganReference r(s, fem::Material::from_kpa(10, 0.45), lone);
    ADD_FAILURE() << "a single support point accepted by the FEM";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("rigid motion"), std::string::npos) << e.what();
  }
  VolumetricSettings st;
  st.fixed = fem::support_nodes(s, lone);
  try {
    const VolumetricBody b(fem::volumetric_mesh(s, {.target_nodes = 300}), st, "cigar");
    ADD_FAILURE() << "a single support point accepted by the volumetric kind";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("collinear or coincident"), std::string::npos) << e.what();
  }
}
