// Calibration of the volumetric kind on the nonlinear response (issue 23, docs/accuracy-nonlinear.md
// "Calibration of the nonlinear response"): fem::refine_multipliers on an analytic response, then the
// compression coefficient c recovered from a synthetic target (the model itself with a known c under large
// local compression), which the small-strain fit cannot see.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "medspring/core/error.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/loads.hpp"
#include "volumetric_fixtures.hpp"

using namespace medspring;
using medspring::testing::box_surface;

namespace {

// One training case of a response u(m) = A diag(g(m)) with a known minimum at m*.
fem::CalibrationCase analytic_case(const fem::Response& r, const VecX& m_true) {
  fem::CalibrationCase c;
  c.u_fem = r(m_true, {});
  c.contact = 0;
  return c;
}

}  // namespace

// Three families with distinct effects on a 4-node "surface": the descent finds each within its span, a
// held family (span 1) stays where it starts, a family the start lacks starts at 1, and the cost never
// rises above the start's.
TEST(Calibration, RefineFindsEachFamilyWithinItsSpan) {
  const fem::Response r = [](const VecX& m, const fem::ContactLoad&) {
    MatX3 u(4, 3);
    u << 1.0 / m(0), 0, 0,                    //
        0, 1.0 / (m(0) + m(1)), 0,            //
        0, 0, 1.0 / (1.0 + std::sqrt(m(2))),  //
        0.5 / m(1), 0.2, 0;
    return u;
  };
  VecX truth(3);
  truth << 1.2, 0.7, 9.0;
  const std::vector<fem::CalibrationCase> training = {analytic_case(r, truth)};
  VecX start(2);
  start << 1.0, 1.0;  // c's multiplier absent: starts at 1
  const fem::RefineResult res = fem::refine_multipliers(r, start, {1.5, 2.0, 32.0}, training, 14, 2);
  EXPECT_NEAR(res.m(0), 1.2, 0.02);
  EXPECT_NEAR(res.m(1), 0.7, 0.02);
  EXPECT_NEAR(res.m(2), 9.0, 0.5);
  EXPECT_LT(res.cost, 1e-3 * res.start_cost);
  EXPECT_EQ(res.evaluations, 1 + 2 * 3 * 14);

  const fem::RefineResult held = fem::refine_multipliers(r, start, {1.5, 1.0, 32.0}, training, 10, 1);
  EXPECT_EQ(held.m(1), 1.0);
  EXPECT_LE(held.cost, held.start_cost);

  EXPECT_THROW(fem::refine_multipliers(r, VecX::Constant(2, -1.0), {1.5, 2.0}, training), InvalidInput);
  EXPECT_THROW(fem::refine_multipliers(r, start, {}, training), InvalidInput);
}

// A 20 mm cube of 150 nodes on its base, pressed by 0.25 N disks of 5 mm on its top (local compressive
// strain ~ 30 %), ν = 0.3. The target is the model itself with c = 16; the model starts at c = 2. The
// small-strain fit is the same for any c (the term is zero to second order at rest); the refinement on
// the full response recovers c and keeps the scales near 1.
TEST(Calibration, NonlinearFitRecoversAKnownCompressionCoefficient) {
  const double L = 20, c_true = 16, c_start = 2;
  const VolumetricMesh mesh = fem::volumetric_mesh(box_surface(4, L), {.target_nodes = 150});
  std::vector<Index> base;
  for (Index i = 0; i < mesh.surface_nodes; ++i)
    if (mesh.X(i, 2) < 1e-9) base.push_back(i);
  auto body = [&](const VecX& m, double c0) {
    VolumetricSettings s;
    s.nu = 0.3;
    s.return_k = 0.0;
    s.fixed = base;
    s.spring_scale = m(0);
    s.volume_scale = m(1);
    s.compression = c0 * (m.size() > 2 ? m(2) : 1.0);
    return VolumetricBody(mesh, s, "cube");
  };
  std::vector<fem::CalibrationCase> training;
  for (const Vec3& centre : {Vec3(10, 10, L), Vec3(5, 13, L)}) {
    fem::CalibrationCase t;
    t.load = {centre, Vec3(0, 0, -0.25), 5.0};
    t.u_fem = fem::spring_displacement(body(VecX::Ones(2), c_true), t.load);
    t.contact = nearest_node(mesh.X.topRows(mesh.surface_nodes), centre);
    training.push_back(t);
  }
  // the target is nonlinear: c changes the contact displacement by more than 10 %
  const MatX3 u_start = fem::spring_displacement(body(VecX::Ones(2), c_start), training[0].load);
  const double u_true = training[0].u_fem.row(training[0].contact).norm(),
               u_off = u_start.row(training[0].contact).norm();
  ASSERT_GT(u_off, 1.1 * u_true) << "the load does not reach the nonlinear range";

  // the small-strain fit cannot see c: identical for c = 2 and c = 64
  auto small_strain = [&](double c0) {
    return fem::calibrate_scale_and_ratio(
        [&](const VecX& mm, const std::vector<fem::ContactLoad>& ls) {
          return fem::spring_displacement_linear(body(mm, c0), ls);
        },
        training);
  };
  const VecX lin = small_strain(c_start);
  EXPECT_LT((lin - small_strain(64)).norm(), 1e-9 * lin.norm());

  const fem::Response full = [&](const VecX& mm, const fem::ContactLoad& l) {
    return fem::spring_displacement(body(mm, c_start), l);
  };
  const fem::VolumetricFit f = fem::calibrate_volumetric_nonlinear(full, lin, training);
  const fem::RefineResult& r = f.refine;
  const double c_fit = c_start * f.m(2);
  std::cout << "cube: small-strain fit springs x " << lin(0) << ", volume x " << lin(1) << " (cost "
            << f.small_strain_cost << "; closed forms " << f.closed_forms_cost << "); refined springs x "
            << f.m(0) << ", volume x " << f.m(1) << ", c " << c_start << " -> " << c_fit << " (true "
            << c_true << "); cost " << r.start_cost << " -> " << r.cost << " in " << r.evaluations
            << " evaluations\n";
  EXPECT_NEAR(c_fit / c_true, 1.0, 0.25);
  EXPECT_NEAR(f.m(0), 1.0, 0.1);
  EXPECT_NEAR(f.m(1), 1.0, 0.25);
  EXPECT_LT(r.cost, 0.1 * r.start_cost);
}

// The disk-mean site read-out of the calibration objective (docs/accuracy-calibration.md): with
// mean_weights, the site term is |sum_i w_i u_i - fem_mean|^2 instead of the contact node's, the weights
// may reach rows beyond the FEM-sampled ones (a refined model surface), and a fit on it matches the disk
// mean where a fit on the node chases a node artefact.
TEST(Calibration, DiskMeanReadoutIsTheObjectivesSiteTerm) {
  // 4 FEM-sampled rows + 1 row of a refined model surface (only the disk mean reads it)
  MatX3 A(5, 3);
  A << 0, 0, -2.0,   //
      0.1, 0, -1.5,  //
      0, 0.2, -1.0,  //
      0, 0, -0.3,    //
      0, 0, -1.8;
  const double s_true = 1.25;
  const fem::Response r = [&](const VecX& m, const fem::ContactLoad&) -> MatX3 { return A / m(0); };
  const fem::BatchResponse batch = [&](const VecX& m, const std::vector<fem::ContactLoad>& ls) {
    return std::vector<MatX3>(ls.size(), A / m(0));
  };
  fem::CalibrationCase node;
  node.u_fem = A.topRows(4) / s_true;
  node.u_fem.row(0) *= 1.3;  // a node artefact: the FEM's contact node is off the model's family
  node.contact = 0;
  fem::CalibrationCase mean = node;
  mean.mean_weights = {{0, 0.4}, {1, 0.2}, {4, 0.4}};
  mean.fem_mean = (0.4 * A.row(0) + 0.2 * A.row(1) + 0.4 * A.row(4)).transpose() / s_true;

  // the objective: the surface term over the 4 sampled rows plus the disk-mean term, by hand
  VecX m(1);
  m << 1.0;
  const double scale = node.u_fem.rowwise().norm().maxCoeff();
  const double surface = (A.topRows(4) - node.u_fem).squaredNorm() / (4 * scale * scale);
  const Vec3 dm = (0.4 * A.row(0) + 0.2 * A.row(1) + 0.4 * A.row(4)).transpose() - mean.fem_mean;
  EXPECT_NEAR(fem::calibration_cost(r, m, {mean}), surface + dm.squaredNorm() / (scale * scale), 1e-12);
  const Vec3 dn = (A.row(0) - node.u_fem.row(0)).transpose();
  EXPECT_NEAR(fem::calibration_cost(r, m, {node}), surface + dn.squaredNorm() / (scale * scale), 1e-12);
  EXPECT_NEAR((fem::site_readout(mean, A) - fem::fem_site_readout(mean)).norm(), dm.norm(), 1e-12);

  // fits on the two read-outs: the optimum of the scale s (u = A / s) in closed form, a = 1 / s minimising
  // wn sum_i |a A_i - U_i|^2 + wc |a S - S_fem|^2 over the sampled rows i and the site read-out S. The
  // artefact pulls the node fit far off s_true; the disk-mean fit only through row 0 of the surface term.
  auto optimum = [&](const Vec3& S, const Vec3& S_fem) {
    const double wn = 1.0 / 4, wc = 1.0;
    const double num = wn * (A.topRows(4).array() * node.u_fem.array()).sum() + wc * S.dot(S_fem),
                 den = wn * A.topRows(4).squaredNorm() + wc * S.squaredNorm();
    return den / num;
  };
  const double s_mean = optimum(fem::site_readout(mean, A), mean.fem_mean),
               s_node = optimum(A.row(0).transpose(), node.u_fem.row(0).transpose());
  ASSERT_GT(std::abs(s_mean - s_node), 0.1);  // the two objectives differ
  const VecX fm = fem::calibrate_scale_and_ratio(batch, {mean}),
             fn = fem::calibrate_scale_and_ratio(batch, {node});
  EXPECT_NEAR(fm(0), s_mean, 1e-9 * s_mean);  // closed form in the scale
  EXPECT_NEAR(fn(0), s_node, 1e-9 * s_node);
  EXPECT_NEAR(fem::calibrate_multipliers(r, 1, {mean})(0), s_mean, 1e-3 * s_mean);  // golden section
  EXPECT_NEAR(fem::calibrate_multipliers(r, 1, {node})(0), s_node, 1e-3 * s_node);
  EXPECT_LT(std::abs(s_mean - s_true), 0.5 * std::abs(s_node - s_true));

  // a weight on a row the response lacks is refused, naming the row
  fem::CalibrationCase bad = mean;
  bad.mean_weights.push_back({7, 0.1});
  EXPECT_THROW(fem::site_readout(bad, A), InvalidInput);
  EXPECT_THROW(fem::calibration_cost(r, m, {bad}), InvalidInput);
}

// The disk-mean weights of a disk on the top face of a box: they sum to 1, sit on the top face's nodes
// inside the disk's reach, and their centroid is the disk centre.
TEST(Calibration, DiskMeanWeightsSumToOneOnTheDisk) {
  const double L = 20;
  const SurfaceMesh box = box_surface(8, L);
  const fem::ContactLoad load{Vec3(10, 10, L), Vec3(0, 0, -0.5), 4.0};
  const auto w = fem::disk_mean_weights(box.V, box.F, load);
  double sum = 0;
  Vec3 centroid = Vec3::Zero();
  for (const auto& [i, wi] : w) {
    EXPECT_NEAR(box.V(i, 2), L, 1e-9);
    EXPECT_LT((box.V.row(i).transpose() - load.centre).norm(), load.radius + 2.5 * L / 8);
    sum += wi;
    centroid += wi * box.V.row(i).transpose();
  }
  EXPECT_NEAR(sum, 1.0, 1e-12);
  EXPECT_LT((centroid - load.centre).norm(), 0.01);
  EXPECT_THROW(fem::disk_mean_weights(box.V, box.F, {Vec3(100, 100, 100), Vec3(0, 0, -1), 1.0}),
               InvalidInput);
}

// The read-out and training-force rules that `medspring calibrate --site-readout --train-force` and Python's
// medspring.calibrate(site_readout=, train_forces=) both call (docs/accuracy-calibration.md, "From Python").
TEST(Calibration, SiteReadoutAndTrainingForceRulesRoundTripAndRefuseWithTheDefectNamed) {
  for (fem::SiteReadout r : {fem::SiteReadout::Node, fem::SiteReadout::DiskMean})
    EXPECT_EQ(parse_enum(std::string(to_string(r)), static_cast<fem::SiteReadout*>(nullptr)), r);
  EXPECT_EQ(to_string(fem::SiteReadout::DiskMean), "disk-mean");
  const auto message = [](auto&& f) {
    try {
      f();
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message([] { parse_enum("centre", static_cast<fem::SiteReadout*>(nullptr)); }),
            "must be node or disk-mean (got 'centre')");
  EXPECT_EQ(fem::parse_train_forces("0.2,1"), (std::vector<double>{0.2, 1.0}));
  EXPECT_EQ(fem::parse_train_forces("0.5"), (std::vector<double>{0.5}));
  EXPECT_EQ(message([] { fem::parse_train_forces("0.5,x"); }), "must be > 0 N or a list of such (got 'x')");
  EXPECT_EQ(message([] { fem::parse_train_forces("0.5,"); }), "must be > 0 N or a list of such (got '')");
  EXPECT_EQ(message([] { fem::parse_train_forces("0.2,-1"); }), "must be > 0 N or a list of such (got '-1')");
  EXPECT_EQ(message([] { fem::parse_train_forces(""); }), "must list at least one force");
  EXPECT_EQ(message([] {
              fem::checked_train_forces({0.2, std::nan("")});
            }),
            "must be > 0 N or a list of such (got 'nan')");
  EXPECT_EQ(message([] { fem::checked_train_forces({0.0}); }), "must be > 0 N or a list of such (got '0')");
}

// The site weight w (CalibrationCase::site_weight, --site-weight, docs/accuracy-calibration.md "The site
// weight"): the cost is the surface term plus w times the site term, by hand (1e-12); w = 1 is the cost of
// a case that never set it, bit for bit; w = 0 leaves the surface term alone; the closed-form scale of
// calibrate_scale_and_ratio is the optimum of the weighted objective (1e-9) and moves towards the site's
// own optimum as w grows. The rule (>= 0, finite) refuses with the words the CLI and Python print.
TEST(Calibration, SiteWeightScalesTheSiteTermAgainstAHandComputation) {
  MatX3 A(4, 3);
  A << 0, 0, -2.0,   //
      0.1, 0, -1.5,  //
      0, 0.2, -1.0,  //
      0, 0, -0.3;
  const fem::Response r = [&](const VecX& m, const fem::ContactLoad&) -> MatX3 { return A / m(0); };
  const fem::BatchResponse batch = [&](const VecX& m, const std::vector<fem::ContactLoad>& ls) {
    return std::vector<MatX3>(ls.size(), A / m(0));
  };
  fem::CalibrationCase plain;
  plain.u_fem = A / 1.25;
  plain.u_fem.row(0) *= 1.3;  // the site wants a softer model than the rest of the surface
  plain.contact = 0;
  VecX m(1);
  m << 1.0;
  const double scale = plain.u_fem.rowwise().norm().maxCoeff();
  const double surface = (A - plain.u_fem).squaredNorm() / (4 * scale * scale),
               site = (A.row(0) - plain.u_fem.row(0)).squaredNorm() / (scale * scale);
  ASSERT_GT(site, 0.1 * surface);  // both terms matter
  fem::CalibrationCase one = plain;
  one.site_weight = 1.0;
  EXPECT_EQ(plain.site_weight, fem::kDefaultSiteWeight);
  EXPECT_EQ(fem::calibration_cost(r, m, {one}), fem::calibration_cost(r, m, {plain}));  // bit for bit
  EXPECT_EQ(fem::calibrate_scale_and_ratio(batch, {one}), fem::calibrate_scale_and_ratio(batch, {plain}));
  double last = 0;
  for (double w : {0.0, 0.25, 4.0, 16.0}) {
    fem::CalibrationCase c = plain;
    c.site_weight = w;
    EXPECT_NEAR(fem::calibration_cost(r, m, {c}), surface + w * site, 1e-12) << "w = " << w;
    // the optimum of s (u = A / s): a = 1 / s minimises sum_i |a A_i - U_i|^2 / 4 + w |a A_0 - U_0|^2
    const double num = (A.array() * plain.u_fem.array()).sum() / 4 + w * A.row(0).dot(plain.u_fem.row(0)),
                 den = A.squaredNorm() / 4 + w * A.row(0).squaredNorm();
    const double s_opt = den / num;
    EXPECT_NEAR(fem::calibrate_scale_and_ratio(batch, {c})(0), s_opt, 1e-9 * s_opt) << "w = " << w;
    if (w > 0) {
      EXPECT_LT(s_opt, last) << "a larger weight follows the (softer) site";
    }
    last = s_opt;
  }
  const auto message = [](auto&& f) {
    try {
      f();
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(fem::parse_site_weight("4"), 4.0);
  EXPECT_EQ(fem::parse_site_weight("0"), 0.0);
  EXPECT_EQ(message([] { fem::parse_site_weight("-1"); }), "must be a number >= 0 (got '-1')");
  EXPECT_EQ(message([] { fem::parse_site_weight("x"); }), "must be a number >= 0 (got 'x')");
  EXPECT_EQ(message([] { fem::parse_site_weight(""); }), "must be a number >= 0 (got '')");
  EXPECT_EQ(message([] { fem::checked_site_weight(std::nan("")); }), "must be a number >= 0 (got 'nan')");
}

// The surface-layer family's refinement (fem::refine_surface_springs) on an analytic response whose fourth
// multiplier scales one row: from the three-multiplier fit and q = 1 it finds q within its span, keeps the
// others, and its cost never rises above the start's (the three-multiplier fit's).
TEST(Calibration, SurfaceFamilyRefinementFindsTheFourthMultiplier) {
  const fem::Response r = [](const VecX& m, const fem::ContactLoad&) {
    EXPECT_EQ(m.size(), 4);
    MatX3 u(3, 3);
    u << 1.0 / m(0), 0, 0,          //
        0, 1.0 / (m(0) + m(1)), 0,  //
        0, 0, 1.0 / (m(0) * m(3));
    return u;
  };
  VecX truth(4), fit(3);
  truth << 1.0, 1.0, 1.0, 3.0;
  fit << 1.0, 1.0, 1.0;
  const std::vector<fem::CalibrationCase> training = {analytic_case(r, truth)};
  const fem::SurfaceSpringFit f = fem::refine_surface_springs(r, fit, training, 14, 2);
  EXPECT_NEAR(f.m(3), 3.0, 0.05);
  EXPECT_NEAR(f.m(0), 1.0, 0.02);
  EXPECT_NEAR(f.m(1), 1.0, 0.05);
  EXPECT_LE(f.refine.cost, f.refine.start_cost);
  EXPECT_LT(f.refine.cost, 1e-3 * f.refine.start_cost);
  EXPECT_THROW(fem::refine_surface_springs(r, VecX::Ones(2), training), InvalidInput);
}
