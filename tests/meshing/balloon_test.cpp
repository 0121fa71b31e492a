#include "medspring/meshing/balloon.hpp"

#include <gtest/gtest.h>

#include <iostream>
#include <string>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/meshing/isosurface.hpp"
#include "medspring/meshing/mesh_repair.hpp"
#include "medspring/meshing/surface_distance.hpp"
#include "meshing_test_util.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

using testing::expect_closed_genus0;
using testing::expect_invalid_input_naming;

const SurfaceMesh& kidney() {
  static const SurfaceMesh m =
      read_mesh(testing::require_data_file("kidney_left_hubmap_vhm.obj"), {.unit = LengthUnit::Metre});
  return m;
}

// ctest runs every test in its own process: the 458-node claims share one test to build the
// kidney surface once (about 1-2 s).
TEST(Balloon, KidneyBalloonMeetsThePaperTargets) {
  const BalloonResult r = build_balloon_surface(kidney());
  std::cout << r.report.summary();

  // Exactly 458 nodes on a closed, manifold, genus-0, outward surface.
  EXPECT_EQ(r.mesh.num_vertices(), 458);
  EXPECT_EQ(r.mesh.num_faces(), 912);  // 2V - 4 on a closed genus-0 surface
  expect_closed_genus0(r.mesh);
  EXPECT_EQ(r.report.nodes, 458);
  EXPECT_EQ(r.report.edges, 1368);  // 3V - 6
  EXPECT_TRUE(r.report.warnings.empty());
  const double v_organ = signed_volume(kidney().V, kidney().F);  // 198 cm^3
  EXPECT_GT(signed_volume(r.mesh.V, r.mesh.F), 0.0);
  EXPECT_NEAR(signed_volume(r.mesh.V, r.mesh.F) / v_organ, 1.0, 0.03);  // chords lose a little

  // At least 85 % of the nodes have six neighbours (measured: 90.8 %), none fewer than 4 or more than 8.
  const auto hist = valence_histogram(vertex_adjacency(458, unique_edges(r.mesh.F)));
  EXPECT_EQ(hist, r.report.valence_histogram);
  ASSERT_GT(hist.size(), 6u);
  EXPECT_GE(hist[6], 390) << "valence-6 fraction " << r.report.valence6_fraction;  // 390 / 458 = 85.2 %
  EXPECT_GE(r.report.valence6_fraction, 0.85);
  EXPECT_LE(hist.size(), 9u);
  EXPECT_EQ(hist[0] + hist[1] + hist[2] + hist[3], 0);

  // Within 2.5 mm (symmetric Hausdorff) of the organ (measured: 1.55 mm), nodes on its surface.
  EXPECT_LE(r.report.hausdorff_mm, 2.5);
  EXPECT_LE(r.report.mean_distance_mm, 0.4);
  const SurfaceDistance d = surface_distance(r.mesh, kidney(), {.sample_spacing = 0.4});  // report: 0.62
  EXPECT_LE(d.hausdorff, 2.5);
  EXPECT_NEAR(d.hausdorff, r.report.hausdorff_mm, 0.3);
  EXPECT_NEAR(d.mean, r.report.mean_distance_mm, 0.05);
  EXPECT_LE(distances_to_surface(r.mesh.V, kidney()).maxCoeff(), 1e-9);
}

TEST(Balloon, KidneyBalloonIsBitIdenticalOnASecondRun) {
  const BalloonResult first = build_balloon_surface(kidney(), {.measure_distance = false});
  const BalloonResult again = build_balloon_surface(kidney(), {.measure_distance = false});
  ASSERT_EQ(again.mesh.V.rows(), first.mesh.V.rows());
  ASSERT_EQ(again.mesh.F.rows(), first.mesh.F.rows());
  EXPECT_TRUE((again.mesh.V.array() == first.mesh.V.array()).all()) << "vertex positions differ";
  EXPECT_TRUE((again.mesh.F.array() == first.mesh.F.array()).all()) << "triangles differ";
  EXPECT_EQ(again.report.valence_histogram, first.report.valence_histogram);
}

TEST(Balloon, OtherTargetCountsAreHitExactly) {
  for (const Index n : {300, 1000}) {
    const BalloonResult r = build_balloon_surface(kidney(), {.target_nodes = n, .measure_distance = false});
    EXPECT_EQ(r.mesh.num_vertices(), n);
    EXPECT_EQ(r.mesh.num_faces(), 2 * n - 4);
    expect_closed_genus0(r.mesh);
    EXPECT_GE(r.report.valence6_fraction, 0.8) << n << " nodes";
    EXPECT_LT(r.report.hausdorff_mm, 0.0) << "not measured when measure_distance is off";
  }
}

TEST(Balloon, IcosphereOrganGivesARegularBalloonOnTheSphere) {
  const SurfaceMesh sphere = icosphere(4, 25.0);  // 2562 nodes
  const BalloonResult r = build_balloon_surface(sphere, {.target_nodes = 458});
  EXPECT_EQ(r.mesh.num_vertices(), 458);
  expect_closed_genus0(r.mesh);
  // The nodes lie on the faceted sphere: radius 25 mm less at most the facets' sagitta (< 0.03 mm).
  for (Index i = 0; i < r.mesh.num_vertices(); ++i) {
    const double radius = r.mesh.V.row(i).norm();
    ASSERT_GT(radius, 24.97) << "node " << i;
    ASSERT_LT(radius, 25.0 + 1e-9) << "node " << i;
  }
  EXPECT_GE(r.report.valence6_fraction, 0.9);
  EXPECT_LE(r.report.hausdorff_mm, 1.0);
}

TEST(Balloon, InwardOrientedOrganGivesAnOutwardBalloon) {
  SurfaceMesh inward = icosphere(3, 25.0);
  inward.F.col(1).swap(inward.F.col(2));
  ASSERT_LT(signed_volume(inward.V, inward.F), 0.0);
  const BalloonResult r = build_balloon_surface(inward, {.target_nodes = 200, .measure_distance = false});
  EXPECT_EQ(r.mesh.num_vertices(), 200);
  expect_closed_genus0(r.mesh);
  EXPECT_GT(signed_volume(r.mesh.V, r.mesh.F), 0.0);
}

TEST(Balloon, OpenOrganIsRefusedNamingBoundaryEdgesAndTheHoleOption) {
  SurfaceMesh open = icosphere(3, 20.0);
  open.F.conservativeResize(open.num_faces() - 1, 3);
  expect_invalid_input_naming([&] { build_balloon_surface(open); },
                              {"organ", "open", "3 boundary edges in 1 hole", "close_small_holes"});
}

TEST(Balloon, NonManifoldOrganIsRefused) {
  SurfaceMesh m = icosphere(2, 20.0);
  const Index a = m.F(0, 0), b = m.F(0, 1);
  m.V.conservativeResize(m.num_vertices() + 1, 3);
  m.V.row(m.num_vertices() - 1) << 0.0, 0.0, 0.0;
  m.F.conservativeResize(m.num_faces() + 1, 3);
  m.F.row(m.num_faces() - 1) << b, a, m.num_vertices() - 1;  // a third triangle on edge (a, b)
  expect_invalid_input_naming([&] { build_balloon_surface(m); }, {"not manifold", "1 edge"});
}

TEST(Balloon, OrganOfTwoComponentsIsRefused) {
  const SurfaceMesh s = icosphere(2, 10.0);
  SurfaceMesh two;
  two.V.resize(2 * s.num_vertices(), 3);
  two.V << s.V, s.V.rowwise() + Eigen::RowVector3d(50.0, 0.0, 0.0);
  two.F.resize(2 * s.num_faces(), 3);
  two.F << s.F, s.F.array() + s.num_vertices();
  expect_invalid_input_naming([&] { build_balloon_surface(two); }, {"2 connected components"});
}

TEST(Balloon, TooFewNodesAreRefused) {
  expect_invalid_input_naming([&] { build_balloon_surface(kidney(), {.target_nodes = 12}); },
                              {"target_nodes 12 is too small", "at least 20"});
}

TEST(Balloon, OrganInMetresGetsAUnitWarning) {
  // The kidney read without --unit m would be 0.155 mm across; a 0.1 mm sphere stands in for it.
  const BalloonResult r = build_balloon_surface(icosphere(3, 0.05), {.target_nodes = 100});
  EXPECT_EQ(r.mesh.num_vertices(), 100);
  ASSERT_EQ(r.report.warnings.size(), 1u);
  EXPECT_NE(r.report.warnings[0].find("are the units metres? use --unit m"), std::string::npos)
      << r.report.warnings[0];
  EXPECT_NE(r.report.summary().find("warning: organ is 0.1"), std::string::npos) << r.report.summary();
}

TEST(Balloon, TargetTooSmallForTheShapeIsRefused) {
  // A hairpin: two 60 x 12 x 3 mm slabs 1 mm apart, joined at one end. With 30 nodes (edges of
  // ~15 mm) the two arms cannot be kept apart.
  MaskVolume m;
  m.dims = {70, 20, 14};
  m.data.assign(m.size(), 0);
  for (Index k = 3; k < 10; ++k)
    for (Index j = 4; j < 16; ++j)
      for (Index i = 4; i < 64; ++i)
        if (k != 6 || i >= 60) m.at(i, j, k) = 1;
  const SurfaceMesh hairpin = isosurface(m, {.blur_sigma_voxels = 0.6});
  expect_closed_genus0(hairpin);
  expect_invalid_input_naming(
      [&] { build_balloon_surface(hairpin, {.target_nodes = 30}); },
      {"target_nodes 30 is too small for this organ", "intersects itself", "more nodes"});
}

TEST(Balloon, OrganSizeWarningFlagsOnlyImplausibleSizes) {
  EXPECT_EQ(organ_size_warning(155.0), "");
  EXPECT_EQ(organ_size_warning(5.0), "");
  EXPECT_EQ(organ_size_warning(1000.0), "");
  EXPECT_NE(organ_size_warning(0.155).find("units metres"), std::string::npos);
  EXPECT_NE(organ_size_warning(155000.0).find("--unit um"), std::string::npos);
}

}  // namespace
}  // namespace medspring
