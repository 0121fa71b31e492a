// The linear static response (issue 23, physics/linear_response.hpp, docs/linear-response.md) on the kidney
// phantom's volumetric body: K0 u = f exactly, the nonlinear static equilibrium approached to second order
// as the load shrinks, the cached columns against the direct solve, the compliance's symmetry, the supports,
// the inversion count against count_inverted, the step (Integrator::LinearStatic), bad input.
#include "medspring/physics/linear_response.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/state.hpp"
#include "medspring/physics/static_solve.hpp"
#include "medspring/physics/volume_terms.hpp"
#include "volumetric_fixtures.hpp"

using namespace medspring;

namespace {

struct Kidney {
  std::shared_ptr<VolumetricBody> body;
  Index top = 0;
  Kidney() {
    const SurfaceMesh s = kidney_phantom();
    VolumetricSettings vs;
    vs.fixed = medspring::testing::bottom_supports(s);
    body = std::make_shared<VolumetricBody>(fem::volumetric_mesh(s, {.target_nodes = 600}), vs, "kidney");
    top = medspring::testing::top_node(s);
  }
};

const Kidney& kidney() {
  static const Kidney k;
  return k;
}

MatX3 load_on(Index n, Index node, const Vec3& f) {
  MatX3 F = MatX3::Zero(n, 3);
  F.row(node) = f.transpose();
  return F;
}

double peak(const MatX3& x, const MatX3& x0) {
  return (x - x0).rowwise().norm().maxCoeff();
}

}  // namespace

TEST(LinearResponse, SolvesTheTangentAtRestExactly) {
  const Model& m = kidney().body->model();
  LinearResponse R(m);
  EXPECT_EQ(R.free_dofs(), 3 * static_cast<Index>(m.free_nodes.size()));
  EXPECT_GT(R.factor_nonzeros(), 0u);
  EXPECT_GE(R.direct_threshold(), 1);
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 0.05);
  MatX3 F = MatX3::Zero(m.num_nodes(), 3);
  for (Index i = 0; i < m.num_nodes(); i += 3) F.row(i) << g(rng), g(rng), g(rng);
  MatX3 x(m.num_nodes(), 3);
  VecX b, u;
  R.positions(F, x, b, u);  // many loaded nodes: the direct solve
  EXPECT_EQ(R.cached_nodes(), 0u);
  const Eigen::SparseMatrix<double> K = tangent_stiffness(m, m.x0, {.include_return = true});
  const MatX3 U = x - m.x0;
  VecX Ku = K * flat(U);
  double rmax = 0, fmax = 0;
  for (Index a : m.free_nodes)
    for (int d = 0; d < 3; ++d) {
      rmax = std::max(rmax, std::abs(Ku[3 * a + d] - F(a, d)));
      fmax = std::max(fmax, std::abs(F(a, d)));
    }
  EXPECT_LT(rmax, 1e-9 * fmax) << "K0 u = f over the free DOFs";
  for (Index a = 0; a < m.num_nodes(); ++a)
    if (m.fixed[a]) {
      EXPECT_EQ((x.row(a) - m.x0.row(a)).norm(), 0.0) << "fixed node " << a;
    }
}

TEST(LinearResponse, ApproachesTheNonlinearEquilibriumToSecondOrder) {
  // The nonlinear static equilibrium (springs, volume terms, Newton) under F and F/4: the linear response's
  // error relative to the displacement is first order in the load, so it drops by about 4x.
  const Model& m = kidney().body->model();
  LinearResponse R(m);
  const Index n = m.num_nodes(), top = kidney().top;
  double rel[2];
  int k = 0;
  for (double load : {0.4, 0.1}) {
    const MatX3 F = load_on(n, top, Vec3(0, 0, -load));
    MatX3 x(n, 3);
    VecX b, u;
    R.positions(F, x, b, u);
    const StaticResult s = static_equilibrium(m, F, {.tolerance = 1e-10});
    rel[k] = (x - s.x).rowwise().norm().maxCoeff() / peak(s.x, m.x0);
    std::cout << "[ linear vs nonlinear statics ] " << load << " N: peak " << peak(s.x, m.x0)
              << " mm, max error " << rel[k] << " of it\n";
    ++k;
  }
  // a point load: large strain next to it (4 % of the peak at 1 mm, 29 % at 3.5 mm; docs/linear-response.md
  // has the disk loads of the accuracy tables)
  EXPECT_LT(rel[0], 0.5);
  EXPECT_GT(rel[0], 0.0);
  EXPECT_NEAR(rel[0] / rel[1], 4.0, 1.0) << "the linearisation error is second order in the load";
}

TEST(LinearResponse, CachedColumnsAgreeWithTheDirectSolveAndAreSymmetric) {
  // Double columns: to 1e-10 of the peak. Float columns (the default): each entry rounded to a relative
  // 2^-24, so the sum of single-node responses is within 1e-6 of the peak of the direct solve (measured:
  // 2.4e-8), and the blocks are symmetric to 1e-6 of their largest entry.
  const Model& m = kidney().body->model();
  const Index n = m.num_nodes();
  for (const auto precision : {LinearResponse::Precision::Double, LinearResponse::Precision::Float}) {
    const bool dbl = precision == LinearResponse::Precision::Double;
    SCOPED_TRACE(dbl ? "double columns" : "float columns");
    const double tol = dbl ? 1e-10 : 1e-6;
    LinearResponse R(m, LinearResponse::kDefaultCacheBytes, precision);
    // free nodes spread over the body, more than the direct threshold
    std::vector<Index> nodes;
    for (Index i = 0; i < n && static_cast<int>(nodes.size()) <= R.direct_threshold() + 2; i += 7)
      if (!m.fixed[i]) nodes.push_back(i);
    ASSERT_GT(static_cast<int>(nodes.size()), R.direct_threshold());
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> U(-0.2, 0.2);
    MatX3 F = MatX3::Zero(n, 3), sum = m.x0, x(n, 3);
    VecX b, u;
    for (Index j : nodes) {
      const Vec3 f(U(rng), U(rng), U(rng));
      F.row(j) = f.transpose();
      EXPECT_EQ(R.positions(load_on(n, j, f), x, b, u), 1);  // one node: its columns
      EXPECT_TRUE(R.cached(j));
      sum += x - m.x0;
    }
    EXPECT_EQ(R.cached_nodes(), nodes.size());
    EXPECT_GT(R.cached_bytes(), nodes.size() * 9 * static_cast<std::size_t>(n) * (dbl ? 8u : 4u));
    EXPECT_EQ(R.positions(F, x, b, u), static_cast<Index>(nodes.size()));  // the direct solve
    EXPECT_LT((x - sum).cwiseAbs().maxCoeff(), tol * peak(x, m.x0));
    // C_ij = C_ji^T, and C_jj symmetric positive definite
    for (std::size_t a = 0; a + 1 < nodes.size(); ++a) {
      const Mat3 Cij = R.block(nodes[a], nodes[a + 1]), Cji = R.block(nodes[a + 1], nodes[a]);
      const Mat3 Cjj = R.block(nodes[a], nodes[a]);
      const double scale = Cjj.cwiseAbs().maxCoeff();
      EXPECT_LT((Cij - Cji.transpose()).cwiseAbs().maxCoeff(), tol * scale);
      EXPECT_LT((Cjj - Cjj.transpose()).cwiseAbs().maxCoeff(), tol * scale);
      EXPECT_GT(Eigen::SelfAdjointEigenSolver<Mat3>(Cjj).eigenvalues().minCoeff(), 0.0);
    }
    // a full cache: the same numbers through the direct solve (double), nothing kept
    LinearResponse small(m, 1, precision);
    MatX3 y(n, 3);
    small.positions(load_on(n, nodes[0], Vec3(0.1, 0, -0.3)), y, b, u);
    R.positions(load_on(n, nodes[0], Vec3(0.1, 0, -0.3)), x, b, u);
    EXPECT_EQ(small.cached_nodes(), 0u);
    EXPECT_LT((x - y).cwiseAbs().maxCoeff(), tol * peak(x, m.x0));
    const Mat3 Cd = small.block(nodes[1], nodes[0]);
    EXPECT_LT((Cd - R.block(nodes[1], nodes[0])).cwiseAbs().maxCoeff(),
              tol * R.block(nodes[0], nodes[0]).cwiseAbs().maxCoeff());
  }
}

TEST(LinearResponse, CountsInvertedTetrahedraAsCountInverted) {
  const Model& m = kidney().body->model();
  const Index n = m.num_nodes(), top = kidney().top;
  LinearResponse R(m);
  MatX3 x(n, 3);
  VecX b, u;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  // loads on one node, on three, and on every fifth (beyond the direct threshold at the largest)
  std::vector<std::vector<Index>> sets{{top}, {top, top / 2, n / 3}};
  std::vector<Index> many;
  for (Index i = 0; i < n; i += 5) many.push_back(i);
  sets.push_back(many);
  std::uint64_t most = 0;
  for (const auto& set : sets)
    for (double load : {0.0, 0.05, 2.0, 20.0, 200.0}) {
      MatX3 F = MatX3::Zero(n, 3);
      for (Index i : set) F.row(i) << 0.3 * load * U(rng), 0.3 * load * U(rng), -load;
      R.positions(F, x, b, u);
      const std::uint64_t all = count_inverted(m.volume, x);
      EXPECT_EQ(R.count_inverted(F, x), all) << set.size() << " loaded nodes, " << load << " N";
      if (load == 0.0) {
        EXPECT_EQ(all, 0u);
      }
      most = std::max(most, all);
      std::cout << "[ count ] " << set.size() << " nodes, " << load << " N: " << all << " inverted\n";
    }
  EXPECT_GT(most, 0u) << "the largest loads invert tetrahedra";
}

TEST(LinearResponse, StepsQuasiStatically) {
  const Model& m = kidney().body->model();
  const Index n = m.num_nodes(), top = kidney().top;
  StepSettings s;
  s.integrator = Integrator::LinearStatic;
  EXPECT_EQ(parse_integrator("linear_static"), Integrator::LinearStatic);
  EXPECT_EQ(to_string(Integrator::LinearStatic), "linear_static");
  EXPECT_EQ(effective_threads(m, {.integrator = Integrator::LinearStatic, .threads = 2}), 1);
  State st = make_state(m, s);
  ASSERT_TRUE(st.linear != nullptr);
  st.linear->precompute(std::vector<Index>{top});
  std::vector<PointLoad> loads{{.node = top, .force = Vec3(0, 0, -0.5), .t_ramp = 5.0, .t_release = 10.0}};
  MatX3 expected(n, 3);
  VecX b, u;
  for (int f = 0; f < 30; ++f) {
    const double t = st.t;
    const MatX3 before = st.x;
    const StepStatus r = step(m, st, s, &loads);
    ASSERT_EQ(r.code, StepCode::Ok);
    EXPECT_EQ(r.substeps, 1);
    st.linear->positions(load_on(n, top, loads[0].at(t)), expected, b, u);
    EXPECT_LT((st.x - expected).cwiseAbs().maxCoeff(), 1e-12) << "frame " << f;
    EXPECT_LT((st.v - (st.x - before) / s.dt).cwiseAbs().maxCoeff(), 1e-12);
  }
  EXPECT_DOUBLE_EQ(st.t, 15.0);
  EXPECT_EQ(st.x, m.x0) << "released: back at rest exactly";
  EXPECT_EQ(st.warnings.total(), 0u);
  EXPECT_EQ(st.linear->cached_nodes(), 1u);
  // a copy shares the response; a non-finite force fails the frame and keeps the positions
  State copy = st;
  EXPECT_EQ(copy.linear, st.linear);
  copy.f_ext.setZero();
  copy.f_ext(top, 2) = std::nan("");
  const MatX3 kept = copy.x;
  EXPECT_EQ(step(m, copy, s).code, StepCode::Failed);
  EXPECT_EQ(copy.x, kept);
  EXPECT_EQ(copy.warnings.nonfinite, 1u);
  EXPECT_EQ(copy.warnings.failed, 1u);
}

TEST(LinearResponse, RefusesFreeRigidMotionAndBadIndices) {
  // a free tetrahedron of springs and a volume term, no pins, no return springs: rigid motion is free
  ModelBuilder mb("loose");
  const MatX3 X = medspring::testing::irregular_tet();
  for (Index i = 0; i < 4; ++i) mb.add_node(X.row(i).transpose(), 1.0, 0.5, 0.0);
  for (Index i = 0; i < 4; ++i)
    for (Index j = i + 1; j < 4; ++j) mb.add_spring(i, j, 1.0, DuffingSettings{});
  mb.add_volume(0, 1, 2, 3, 0.01);
  const Model loose = mb.build();
  try {
    LinearResponse R(loose);
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("loose"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rigid motion"), std::string::npos) << e.what();
  }
  // the same with return springs: positive definite
  ModelBuilder held("held");
  for (Index i = 0; i < 4; ++i) held.add_node(X.row(i).transpose(), 1.0, 0.5, 0.02);
  for (Index i = 0; i < 4; ++i)
    for (Index j = i + 1; j < 4; ++j) held.add_spring(i, j, 1.0, DuffingSettings{});
  EXPECT_NO_THROW(LinearResponse{held.build()});
  LinearResponse R(kidney().body->model());
  const Index n = kidney().body->model().num_nodes();
  EXPECT_THROW(R.precompute(std::vector<Index>{0, n}), InvalidInput);
  EXPECT_THROW(R.block(-1, 0), InvalidInput);
}

TEST(LinearResponse, StaysNearTheNonlinearStaticsUnderDiskLoads) {
  // The accuracy tables' load (a 6 mm disk over the top, docs/accuracy-volumetric.md) on the 600-node body
  // with its default compression term: the linear response against fem::spring_displacement (the nonlinear
  // static solve), RMS and max over the surface, in units of the nonlinear peak. Measured: 0.35 / 5.6 % at
  // 0.2 N, 1.8 / 28 % at 1 N (2,012 nodes: 0.17 / 1.2 % and 1.1 / 5.9 %; docs/linear-response.md).
  const SurfaceMesh s = kidney_phantom();
  const Index top = kidney().top;
  double rms[2], max[2];
  int k = 0;
  for (double F : {0.2, 1.0}) {
    const fem::ContactLoad L{.centre = s.V.row(top).transpose(), .force = Vec3(0, 0, -F), .radius = 6.0};
    const MatX3 un = fem::spring_displacement(*kidney().body, L);
    const MatX3 ul = fem::spring_displacement_linear(*kidney().body, {L})[0];
    const double pk = un.rowwise().norm().maxCoeff();
    rms[k] = std::sqrt((ul - un).rowwise().squaredNorm().mean()) / pk;
    max[k] = (ul - un).rowwise().norm().maxCoeff() / pk;
    std::cout << "[ disk load ] " << F << " N: peak " << pk << " mm; linear against nonlinear: RMS " << rms[k]
              << ", max " << max[k] << " of it\n";
    ++k;
  }
  EXPECT_LT(rms[0], 0.01);
  EXPECT_LT(rms[1], 0.03);
  EXPECT_GT(rms[1], 2.0 * rms[0]) << "the difference grows with the load";
  EXPECT_LT(max[0], 0.1);
}
