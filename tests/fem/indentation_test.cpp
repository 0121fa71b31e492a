// Reaction forces from CalculiX and the rigid-sphere indentation of the FEM reference (issue 18,
// fem/indentation.hpp): the FORC block of the .frd, force balance of the reactions, Hertz on a coarse
// half-space block, the first-touch and curvature helpers, and bad settings.
#include "medspring/fem/indentation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "medspring/core/error.hpp"
#include "medspring/fem/calculix.hpp"
#include "medspring/fem/frd.hpp"
#include "medspring/fem/tet_mesh.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "test_support.hpp"

using namespace medspring;
using namespace medspring::fem;

namespace {

const char* kFrd =
    "    2C                             2                                     1\n"
    " -1         1 0.00000E+00 0.00000E+00 0.00000E+00\n"
    " -1         2 1.00000E+00 0.00000E+00 0.00000E+00\n"
    " -3\n"
    "  100CL  101 1.00000E+00           2                     0    1           1\n"
    " -4  DISP        4    1\n"
    " -5  D1          1    2    1    0\n"
    " -1         1 0.00000E+00 0.00000E+00 0.00000E+00\n"
    " -1         2 1.50000E-01-2.00000E-02 3.00000E-03\n"
    " -3\n"
    "  100CL  101 1.00000E+00           2                     0    1           1\n"
    " -4  FORC        4    1\n"
    " -5  F1          1    2    1    0\n"
    " -5  ALL         1    2    0    0    1ALL\n"
    " -1         1-2.50000E-01 1.00000E-03 7.00000E+00\n"
    " -3\n"
    " 9999\n";

FemSettings no_cache() {
  FemSettings s;
  s.use_cache = false;
  return s;
}

}  // namespace

TEST(FrdReader, ReadsReactionForceBlocks) {
  const FrdData d = parse_frd(kFrd, "t.frd");
  ASSERT_EQ(d.disp.size(), 1u);
  ASSERT_EQ(d.forc.size(), 1u);
  const MatX3 f = last_reaction(d, 2, 1.0);
  EXPECT_DOUBLE_EQ(f(0, 0), -0.25);
  EXPECT_DOUBLE_EQ(f(0, 2), 7.0);
  EXPECT_EQ(f.row(1).norm(), 0.0);  // absent from the block: no reaction
  EXPECT_THROW(last_reaction(d, 2, 0.5), IoError);
  const std::string text = kFrd;
  const std::string no_forc = text.substr(0, text.rfind("  100CL")) + " 9999\n";
  EXPECT_TRUE(parse_frd(no_forc, "t.frd").forc.empty());
  EXPECT_THROW(last_reaction(parse_frd(no_forc, "t.frd"), 2, 1.0), IoError);  // no FORC block
}

// The reactions at the supports balance the applied loads (and come back from the cache).
TEST(Calculix, ReactionForcesBalanceTheLoads) {
  FemProblem p{box_mesh(graded(0, 4, 2), graded(0, 2, 1), graded(0, 2, 1)), Material::from_kpa(10, 0.45)};
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 0) == 0) p.fixed.push_back(i);
  Vec3 total = Vec3::Zero();
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 0) == 4) {
      p.loads.push_back({i, Vec3(1e-5, 0, -2e-5)});
      total += Vec3(1e-5, 0, -2e-5);
    }
  FemSettings s;
  s.cache_dir = medspring::testing::temp_dir("fem_rf_cache").string();
  s.reaction_forces = true;
  const FemResult a = solve(p, s);
  ASSERT_EQ(a.rf.rows(), p.mesh.num_nodes());
  Vec3 sum = Vec3::Zero();
  for (Index v : p.fixed) sum += a.rf.row(v).transpose();
  EXPECT_LT((sum + total).norm(), 1e-3 * total.norm()) << sum.transpose() << " vs " << total.transpose();
  const FemResult b = solve(p, s);
  EXPECT_TRUE(b.from_cache);
  EXPECT_EQ(a.u, b.u);
  EXPECT_EQ(a.rf, b.rf);
  s.reaction_forces = false;  // another deck: no reactions asked, none returned
  const FemResult c = solve(p, s);
  EXPECT_EQ(c.rf.rows(), 0);
  EXPECT_LT((c.u - a.u).norm(), 1e-9);
}

// The coarse level of the Hertz validation (the finer levels are in docs/accuracy.md).
TEST(SphereIndentation, RigidSphereOnAHalfSpaceFollowsHertz) {
  const auto rs = validate_hertz(1, no_cache());
  ASSERT_EQ(rs.size(), 1u);
  std::printf("%s: FEM %.5g N, Hertz %.5g N, error %.2f %%\n", rs[0].name.c_str(), rs[0].fem, rs[0].analytic,
              100 * rs[0].rel_error);
  EXPECT_GT(rs[0].fem, 0);
  EXPECT_LT(rs[0].rel_error, 0.15) << rs[0].fem << " vs " << rs[0].analytic;
}

// A sphere pressed on a supported block along +x (a rotated frame): the force grows with the depth,
// the contact nodes sit on the sphere, and the reaction on the sphere points back along -x.
TEST(SphereIndentation, ActiveSetPutsTheContactNodesOnTheSphereInAnyDirection) {
  FemProblem p{box_mesh(graded(0, 8, 4), graded(-8, 8, 4), graded(-8, 8, 4)), Material::from_kpa(10, 0.45)};
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 0) == 8) p.fixed.push_back(i);
  SphereIndentation s;
  s.radius = 6;
  s.touch_centre = Vec3(-6, 0, 0);
  s.direction = Vec3(1, 0, 0);
  s.depths = {0.3, 0.6};
  const auto pts = sphere_indentation(p, s, no_cache());
  ASSERT_EQ(pts.size(), 2u);
  for (const auto& pt : pts) {
    EXPECT_TRUE(pt.converged) << pt.depth;
    EXPECT_GT(pt.contact_nodes, 0);
    EXPECT_GT(pt.force, 0);
    EXPECT_GT(-pt.reaction.x(), 0.99 * pt.reaction.norm());
    const Vec3 C = s.touch_centre + pt.depth * s.direction;
    for (Index i = 0; i < p.mesh.num_nodes(); ++i) {
      const Vec3 x = p.mesh.X.row(i).transpose() + pt.u.row(i).transpose();
      EXPECT_GE((x - C).norm(), s.radius - 1e-3 - 1e-6) << "node " << i << " inside the sphere";
    }
  }
  EXPECT_GT(pts[1].force, 2.0 * pts[0].force);  // stiffening: Hertz would give 2^1.5 = 2.83
}

TEST(SphereIndentation, BadSettingsAreRefused) {
  FemProblem p{box_mesh(graded(0, 2, 1), graded(0, 2, 1), graded(0, 2, 1)), Material::from_kpa(10, 0.45)};
  for (Index i = 0; i < p.mesh.num_nodes(); ++i)
    if (p.mesh.X(i, 2) == 0) p.fixed.push_back(i);
  SphereIndentation s;
  s.touch_centre = Vec3(1, 1, 2 + s.radius);
  s.depths = {0.1};
  auto refused = [&](SphereIndentation bad, const std::string& what) {
    try {
      sphere_indentation(p, bad, no_cache());
      ADD_FAILURE() << "accepted: " << what;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  SphereIndentation b = s;
  b.radius = 0;
  refused(b, "radius");
  b = s;
  b.depths = {0.2, 0.1};
  refused(b, "depths must increase");
  b = s;
  b.depths = {-1};
  refused(b, "depths[0]");
  b = s;
  b.direction = Vec3::Zero();
  refused(b, "direction");
  b = s;
  b.touch_centre(0) = std::nan("");
  refused(b, "touch_centre");
}

TEST(SphereIndentation, FirstTouchAndCurvatureOfKnownSurfaces) {
  // a flat square at z = 0 (two triangles): the sphere touches when its centre is at z = R
  MatX3 V(4, 3);
  V << -10, -10, 0, 10, -10, 0, 10, 10, 0, -10, 10, 0;
  MatX3i F(2, 3);
  F << 0, 1, 2, 0, 2, 3;
  const Vec3 c = first_touch_centre(V, F, 3.0, Vec3(1, 2, 50), Vec3(0, 0, -1));
  EXPECT_NEAR((c - Vec3(1, 2, 3)).norm(), 0, 1e-9);
  EXPECT_THROW(first_touch_centre(V, F, 3.0, Vec3(100, 0, 50), Vec3(0, 0, -1)), InvalidInput);
  // a sphere of radius 40: both principal curvatures 1/40 at its top
  const SurfaceMesh s = icosphere(3, 40.0);
  const auto [k1, k2] = principal_curvatures(s.V, Vec3(0, 0, 40), Vec3(0, 0, -1), 15.0);
  EXPECT_NEAR(k1, 1.0 / 40, 0.1 / 40);
  EXPECT_NEAR(k2, 1.0 / 40, 0.1 / 40);
}
