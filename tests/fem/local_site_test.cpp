// The local overlay of eq. (6) as a calibrated site family of the volumetric kind (fem/local_site.hpp,
// docs/accuracy-calibration.md, "The local overlay as a site family").
#include "medspring/fem/local_site.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <vector>

#include "medspring/core/error.hpp"
#include "medspring/geometry/topology.hpp"
#include "volumetric_box.hpp"

using namespace medspring;

// A 20 mm cube on its base, a 0.3 N disk of 5 mm radius on the top face: the disk's nodal forces sum to the
// load (1e-12 N) and all reach free patch nodes; the overlay is the solution of L_ff U = F assembled
// independently from the surface edges (1e-12 mm), zero off the patch's free nodes (the ring is fixed), and
// scales as 1 / k_loc (1e-12).
TEST(LocalSite, DiskOverlayIsThePatchSolveOfTheDiskLoad) {
  const std::vector<double> xs = {0, 2.5, 5, 7.5, 10, 12.5, 15, 17.5, 20};
  const VolumetricMesh mesh = medspring::testing::box(xs, xs, {0, 5, 10, 15, 20});
  VolumetricSettings s;
  for (Index i = 0; i < mesh.surface_nodes; ++i)
    if (mesh.X(i, 2) < 1e-9) s.fixed.push_back(i);
  const VolumetricBody body(mesh, s, "cube");
  const fem::ContactLoad load{Vec3(10, 10, 20), Vec3(0.02, 0, -0.3), 5.0};
  const double k = 0.04;
  const MatX3 v = fem::disk_local_overlay(body, load, k);
  const MatX3& S = body.rest_surface();
  ASSERT_EQ(v.rows(), S.rows());

  const MatX3 f = fem::disk_load_linear(S, body.faces(), load.centre, load.radius, load.force);
  std::vector<Index> loaded;
  Vec3 total = Vec3::Zero();
  for (Index i = 0; i < f.rows(); ++i)
    if (f.row(i).squaredNorm() > 0) loaded.push_back(i), total += f.row(i).transpose();
  ASSERT_GE(loaded.size(), 9u);
  EXPECT_LT((total - load.force).norm(), 1e-12);

  // independently: the patch = the loaded nodes and their neighbours; its free nodes = those with every
  // neighbour inside it; L_ff U = F over them, every other node held at 0
  const Adjacency adj = vertex_adjacency(body.num_surface_nodes(), unique_edges(body.faces()));
  std::vector<Index> patch = loaded;
  for (Index g : loaded)
    for (const Index* q = adj.begin(g); q != adj.end(g); ++q)
      if (std::find(patch.begin(), patch.end(), *q) == patch.end()) patch.push_back(*q);
  std::vector<Index> inner;
  for (Index g : patch)
    if (std::all_of(adj.begin(g), adj.end(g),
                    [&](Index q) { return std::find(patch.begin(), patch.end(), q) != patch.end(); }))
      inner.push_back(g);
  const Index n = static_cast<Index>(inner.size());
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n), F(n, 3);
  for (Index a = 0; a < n; ++a) {
    F.row(a) = f.row(inner[a]);
    for (const Index* q = adj.begin(inner[a]); q != adj.end(inner[a]); ++q) {
      L(a, a) += k;
      const auto it = std::find(inner.begin(), inner.end(), *q);
      if (it != inner.end()) L(a, it - inner.begin()) -= k;
    }
  }
  const Eigen::MatrixXd u = L.fullPivLu().solve(F);
  double err = 0;
  for (Index a = 0; a < n; ++a) err = std::max(err, (v.row(inner[a]) - u.row(a)).cwiseAbs().maxCoeff());
  EXPECT_LT(err, 1e-12);
  for (Index g : loaded)  // every loaded node is free: the whole load reaches the patch
    EXPECT_NE(std::find(inner.begin(), inner.end(), g), inner.end()) << "loaded node " << g;
  for (Index i = 0; i < v.rows(); ++i) {  // zero off the patch's free nodes
    if (std::find(inner.begin(), inner.end(), i) == inner.end()) {
      EXPECT_EQ(v.row(i).norm(), 0.0) << "surface node " << i << " is outside the patch's free nodes";
    }
  }
  EXPECT_LT((fem::disk_local_overlay(body, load, 0.5 * k) - 2.0 * v).cwiseAbs().maxCoeff(), 1e-12);

  EXPECT_THROW(fem::disk_local_overlay(body, load, 0.0), InvalidInput);
  EXPECT_THROW(fem::disk_local_overlay(body, {Vec3(10, 10, 60), Vec3(0, 0, -0.3), 5.0}, k), InvalidInput);
}

namespace {

// An analytic volumetric kind: u(m) = A_i / m0 + B_i / m1 on 6 rows per load i (springs and volume terms),
// the overlay V_i (load i is told by its centre's x), and the target u(m*) + a* V_i.
struct Analytic {
  std::vector<MatX3> A, B, V;
  MatX3 u(const VecX& m, Index i) const { return A[i] / m(0) + B[i] / m(1); }
  Analytic() {
    for (int i = 0; i < 3; ++i) {
      MatX3 a(6, 3), b(6, 3), v = MatX3::Zero(6, 3);
      for (int r = 0; r < 6; ++r) {
        a.row(r) << 0.1 * std::sin(r + i), 0.05 * std::cos(2 * r), -1.0 / (1 + r + i);
        b.row(r) << 0.02 * r, -0.04 * std::sin(r * i + 1.0), -0.3 - 0.05 * r;
      }
      v.row(i) << 0, 0, -0.6;  // the load's own node (and its neighbour) under the disk
      v.row(i + 1) << 0.05, 0, -0.2;
      A.push_back(a), B.push_back(b), V.push_back(v);
    }
  }
  std::vector<fem::CalibrationCase> training(const VecX& m, double a_true) const {
    std::vector<fem::CalibrationCase> t;
    for (Index i = 0; i < 3; ++i) {
      fem::CalibrationCase c;
      c.load.centre = Vec3(double(i), 0, 0);
      c.u_fem = u(m, i) + a_true * V[i];
      c.contact = i;
      t.push_back(c);
    }
    return t;
  }
  fem::BatchResponse batch() const {
    return [this](const VecX& m, const std::vector<fem::ContactLoad>& ls) {
      std::vector<MatX3> out;
      for (const auto& l : ls) out.push_back(u(m, static_cast<Index>(l.centre.x())));
      return out;
    };
  }
  std::function<MatX3(const fem::ContactLoad&)> overlay() const {
    return [this](const fem::ContactLoad& l) { return V[static_cast<std::size_t>(l.centre.x())]; };
  }
};

}  // namespace

// The overlay compliance is fitted jointly with the scale and the ratio: a target with a* = 0.8 at springs
// x 1.3, volume x 0.78 is recovered to 2 % (the ratio's golden section ends within 0.5 %), with the
// nonlinear refine (c has no effect here) as without it; the cost falls to < 1e-3 of the overlay-free fit's.
TEST(LocalSite, CalibrationRecoversAKnownOverlayCompliance) {
  const Analytic an;
  VecX m_true(2);
  m_true << 1.3, 0.78;
  const auto training = an.training(m_true, 0.8);
  const fem::OverlayFit fit = fem::calibrate_volumetric_overlay(an.batch(), nullptr, an.overlay(), training);
  ASSERT_EQ(fit.m.size(), 4);
  EXPECT_NEAR(fit.m(0) / 1.3, 1.0, 0.02);
  EXPECT_NEAR(fit.m(1) / 0.78, 1.0, 0.02);
  EXPECT_EQ(fit.m(2), 1.0);
  EXPECT_NEAR(fit.m(3) / 0.8, 1.0, 0.02);
  const VecX base = fem::calibrate_scale_and_ratio(an.batch(), training);
  const fem::Response plain = [&](const VecX& m, const fem::ContactLoad& l) {
    return an.u(m, static_cast<Index>(l.centre.x()));
  };
  const double base_cost = fem::calibration_cost(plain, base, training);
  EXPECT_LT(fit.cost, 1e-3 * base_cost);

  const fem::OverlayFit nl = fem::calibrate_volumetric_overlay(an.batch(), &plain, an.overlay(), training);
  EXPECT_NEAR(nl.m(0) / 1.3, 1.0, 0.02);
  EXPECT_NEAR(nl.m(1) / 0.78, 1.0, 0.02);
  EXPECT_NEAR(nl.m(3) / 0.8, 1.0, 0.02);
  EXPECT_LE(nl.cost, fit.cost * (1 + 1e-9) + 1e-12);
  EXPECT_GT(nl.evaluations, 0);
}

// Overlay off is reachable: a target the overlay can only worsen (a* < 0) gives a = 0 exactly, and then the
// scale and ratio are calibrate_scale_and_ratio's (1e-12): the kind without the overlay.
TEST(LocalSite, OverlayOffIsReachableAndThenTheFitIsThePlainOne) {
  const Analytic an;
  VecX m_true(2);
  m_true << 0.9, 1.4;
  const auto training = an.training(m_true, -0.5);
  const fem::OverlayFit fit = fem::calibrate_volumetric_overlay(an.batch(), nullptr, an.overlay(), training);
  EXPECT_EQ(fit.m(3), 0.0);
  const VecX base = fem::calibrate_scale_and_ratio(an.batch(), training);
  EXPECT_NEAR(fit.m(0) / base(0), 1.0, 0.01);
  EXPECT_NEAR(fit.m(1) / base(1), 1.0, 0.01);
  // at the plain fit's multipliers, the closed form of a alone is 0 too
  std::vector<MatX3> u, v;
  for (Index i = 0; i < 3; ++i) u.push_back(an.u(base, i)), v.push_back(an.V[static_cast<std::size_t>(i)]);
  EXPECT_EQ(fem::fit_overlay_coefficients(u, v, training, false).a, 0.0);
  EXPECT_THROW(fem::fit_overlay_coefficients(u, {}, training, true), InvalidInput);
}
