// Vessel trees from a segmentation or a closed surface mesh (issue 17, docs/vessels.md): build_vessel with
// all branches on a procedural Y (its mask, and the union of its tubes as a mesh) gives 3 branches and 1
// junction, one watertight surface exact at rest and within a voxel or two of the input; the real aorta
// mask gives one tube; bad input is refused (the skeleton itself: tests/skeleton/centerline_tree_test.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>

#include "medspring/builders/vessel_build.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/io/volume_io.hpp"
#include "medspring/meshing/mesh_repair.hpp"
#include "medspring/meshing/mesh_union.hpp"
#include "medspring/meshing/surface_distance.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/physics/state.hpp"
#include "medspring/skeleton/centerline_tree.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

// A Y: trunk (0,0,0) -> J = (30,0,0), two branches J -> B1, B2 out of the xy plane and of unequal length
// (a planar, mirror-symmetric Y puts the tube vertices of the union exactly on each other's edges: CGAL
// then leaves zero-area triangles, docs/vessels.md); radius 4 mm (trunk) and 3 mm (branches).
const Vec3 kJ(30.0, 0.0, 0.0), kA(0.0, 0.0, 0.0), kB1(55.0, 18.0, 4.0), kB2(53.0, -17.0, -3.0);

double capsule_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

bool inside_y(const Vec3& p) {
  return capsule_distance(p, kA, kJ) <= 4.0 || capsule_distance(p, kJ, kB1) <= 3.0 ||
         capsule_distance(p, kJ, kB2) <= 3.0;
}

MaskVolume y_mask(double h) {
  MaskVolume m;
  m.spacing = Vec3::Constant(h);
  m.origin = Vec3(-6.0, -24.0, -10.0);
  m.dims = {static_cast<Index>(std::ceil(68.0 / h)), static_cast<Index>(std::ceil(48.0 / h)),
            static_cast<Index>(std::ceil(20.0 / h))};
  m.data.assign(m.size(), 0);
  for (Index k = 0; k < m.dims[2]; ++k)
    for (Index j = 0; j < m.dims[1]; ++j)
      for (Index i = 0; i < m.dims[0]; ++i) m.at(i, j, k) = inside_y(m.to_world(Vec3(i, j, k))) ? 1 : 0;
  return m;
}

// The Y as a closed mesh: the union of its path tubes (flat caps at the three ends), 1.5 mm rings.
SurfaceMesh y_mesh() {
  MatX3 atoms(7, 3);
  atoms << 0, 0, 0, 15, 0, 0, 30, 0, 0, 42.5, 9, 2, 55, 18, 4, 41.5, -8.5, -1.5, 53, -17, -3;
  VecX radii(7);
  radii << 4, 4, 4, 3, 3, 3, 3;
  const CenterlineTree ct = tree_from_parents(atoms, {-1, 0, 1, 2, 3, 2, 5}, radii);
  SmrmTreeSettings ts;
  ts.vessel.spokes = 24;
  return blended_tree_surface(ct, SmrmTree(ct, ts), 1.5).mesh;
}

// Distances to the input of the rebuilt nodes away from the tree's ends: nodes farther than the end
// atom's radius + 2 mm from every end (the root's start, every leaf's end) of the tree.
VecX away_from_ends(const VesselBuild& v) {
  const MatX3& S = v.tree->rest_surface();
  std::vector<std::pair<Vec3, double>> ends{
      {v.centerlines[0].points.row(0).transpose(), v.centerlines[0].radii[0]}};
  for (std::size_t b = 0; b < v.centerlines.size(); ++b) {
    const Centerline& c = v.centerlines[b];
    bool leaf = true;
    for (Index q = 0; q < v.tree->num_branches(); ++q)
      leaf = leaf && v.tree->parent(q) != static_cast<Index>(b);
    if (leaf) ends.emplace_back(c.points.row(c.size() - 1).transpose(), c.radii[c.size() - 1]);
  }
  std::vector<Index> away;
  for (Index k = 0; k < S.rows(); ++k) {
    bool near_end = false;
    for (const auto& [e, r] : ends) near_end = near_end || (S.row(k).transpose() - e).norm() < r + 2.0;
    if (!near_end) away.push_back(k);
  }
  EXPECT_GT(away.size(), static_cast<std::size_t>(S.rows() / 2));
  MatX3 A(static_cast<Index>(away.size()), 3);
  for (std::size_t q = 0; q < away.size(); ++q) A.row(static_cast<Index>(q)) = S.row(away[q]);
  const VecX d = distances_to_surface(A, v.input);
  return d;
}

TEST(VesselTreeSkeleton, BuildVesselFromAYSegmentationAndMeshIsATreeCloseToTheInput) {
  const std::filesystem::path dir = testing::temp_dir("vessel-tree-skeleton");
  {  // the Y as a label volume
    const MaskVolume m = y_mask(0.5);
    LabelVolume l;
    l.dims = m.dims;
    l.spacing = m.spacing;
    l.origin = m.origin;
    l.direction = m.direction;
    l.data.assign(m.data.begin(), m.data.end());
    write_label_volume(dir / "y.mha", l);
  }
  write_mesh(dir / "y.vtp", y_mesh());
  for (const bool from_mask : {true, false}) {
    SCOPED_TRACE(from_mask ? "segmentation" : "mesh");
    VesselBuildSettings st;
    if (from_mask)
      st.source.mask = dir / "y.mha";
    else
      st.source.mesh = dir / "y.vtp";
    st.all_branches = true;
    st.blend = true;
    st.smrm.atoms = 16;
    const VesselBuild v = build_vessel(st);
    ASSERT_TRUE(v.tree);
    const VesselSummary& s = v.summary;
    EXPECT_EQ(s.branches, 3);
    EXPECT_EQ(s.junctions, 1);
    EXPECT_LE(s.rest_error_mm, 1e-9);
    EXPECT_TRUE(s.blended && s.surface_closed);
    EXPECT_EQ(s.surface_components, 1);
    ASSERT_TRUE(s.has_distance);
    // every rebuilt node away from the ends lies on the input wall; the Hausdorff distance also counts the
    // ends, extended to the input's tips (a rounded tip of the mask Y: the flat cap 0.24 r short of its apex;
    // the mesh Y's flat caps: reached). Measured before the fit to the wall: mask 0.83 / 0.075 mm, mesh
    // 1.30 / 0.029 mm (before the ends were extended: 4.09 / 0.16 and 6.08 / 0.40 mm)
    const VecX d = away_from_ends(v);
    std::cout << (from_mask ? "  mask" : "  mesh") << " Y: " << s.branches << " branches, " << s.junctions
              << " junction(s), rest error " << s.rest_error_mm << " mm, Hausdorff " << s.hausdorff_mm
              << " mm, mean " << s.mean_distance_mm << " mm; nodes away from the ends to the input: max "
              << d.maxCoeff() << " mm, mean " << d.mean() << " mm\n";
    // with the surface fitted to the wall (relaxed, projected, long edges split): mask 0.81 / 0.021 mm, mesh
    // 1.00 / 0.015 mm; the nodes away from the ends: max 0.28 / 0.81 mm; away from the cut ends 0.30 / 1.00
    // mm
    std::cout << "    away from the cut ends: Hausdorff " << s.away.hausdorff_mm << " mm, mean "
              << s.away.mean_mm << " mm\n";
    EXPECT_LT(d.maxCoeff(), from_mask ? 0.5 : 1.0);
    EXPECT_LT(d.mean(), 0.01);
    EXPECT_LT(s.hausdorff_mm, from_mask ? 1.0 : 1.3);
    EXPECT_LT(s.mean_distance_mm, 0.03);
    EXPECT_LE(s.away.hausdorff_mm, s.hausdorff_mm);
    EXPECT_LT(s.away.hausdorff_mm, from_mask ? 0.5 : 1.2);  // measured 0.30 / 1.00 mm
    EXPECT_GT(s.hausdorff_mm, 0.0);
    write_vessel_files(dir, v);  // the package of a tree from a mask / mesh: the fitted surface is stored
    const ModelPackage pkg = read_model_package(dir / "vessel.msm");
    EXPECT_EQ(pkg.kind, "smrm_tree");
    const BodyPtr body = make_body(pkg);
    EXPECT_TRUE(check_fingerprint(pkg, *body));
    ASSERT_EQ(body->rest_surface().rows(), v.tree->rest_surface().rows());
    EXPECT_EQ(body->faces(), v.tree->faces());
    EXPECT_LE((body->rest_surface() - v.tree->rest_surface()).cwiseAbs().maxCoeff(), 1e-12);
    const State rest = make_state(body->model());
    MatX3 S;
    body->map_to_surface(rest, S);
    EXPECT_LE((S - v.tree->rest_surface()).rowwise().norm().maxCoeff(), 1e-9);
  }
}

// A planar, mirror-symmetric Y (the case CGAL's union left zero-area triangles in, refused before): the
// blended surface is one closed manifold, exact at rest.
TEST(VesselTreeSkeleton, PlanarSymmetricYBlendsIntoOneWatertightSurface) {
  MatX3 atoms(7, 3);
  atoms << 0, 0, 0, 15, 0, 0, 30, 0, 0, 42, 10, 0, 54, 20, 0, 42, -10, 0, 54, -20, 0;
  VecX radii(7);
  radii << 4, 4, 4, 3, 3, 3, 3;
  const CenterlineTree ct = tree_from_parents(atoms, {-1, 0, 1, 2, 3, 2, 5}, radii);
  SmrmTreeSettings ts;
  ts.vessel.atoms = 9;
  TreeSurface r;
  const auto tree = make_blended_tree(ct, ts, 0.0, &r);
  for (const auto& n : r.notes) std::cout << "  " << n << "\n";
  EXPECT_TRUE(r.closed);
  EXPECT_EQ(r.components, 1);
  EXPECT_EQ(r.self_intersections, 0);
  EXPECT_GT(r.volume_mm3, 0.0);
  EXPECT_TRUE(validate_mesh(r.mesh).valid()) << validate_mesh(r.mesh).first_problem;
  State st = make_state(tree->model());
  MatX3 S;
  tree->map_to_surface(st, S);
  EXPECT_LE((S - tree->rest_surface()).rowwise().norm().maxCoeff(), 1e-9);
}

// The real TotalSegmentator aorta (arch + descending aorta, no branch stubs; ../shared/data/README.md), from
// its mask and from its surface mesh: the tree of every endpoint is one branch without junctions, and its
// watertight surface (skeleton re-centred, mask holes filled, surface fitted to the wall) is within 2 mm of
// the input away from the cut ends for the mesh (the target), a little over it for the mask.
TEST(VesselTreeSkeleton, RealAortaIsOneBranchWithinTwoMillimetresOfTheInputAwayFromTheCutEnds) {
  for (const bool from_mask : {true, false}) {
    SCOPED_TRACE(from_mask ? "mask" : "mesh");
    VesselBuildSettings st;
    if (from_mask) {
      st.source.mask = testing::require_data_file("aorta_totalseg_mask.nii.gz");
      st.source.label = 1;
    } else {
      st.source.mesh = testing::require_data_file("aorta_totalseg_ct.obj");
      st.source.unit = LengthUnit::Millimetre;
    }
    st.all_branches = true;
    const VesselBuild v = build_vessel(st);
    const VesselSummary& s = v.summary;
    EXPECT_EQ(s.branches, 1);
    EXPECT_EQ(s.junctions, 0);
    EXPECT_LE(s.rest_error_mm, 1e-9);
    EXPECT_TRUE(s.blended && s.surface_closed);
    EXPECT_EQ(s.self_intersections, 0);
    EXPECT_LT(s.max_rho_kappa, 1.0);  // re-centred: 0.98 (mask) / 0.93 (mesh); 1.01 before
    ASSERT_TRUE(s.has_distance && s.away.measured);
    const VecX d = away_from_ends(v);
    std::cout << "  aorta " << (from_mask ? "mask" : "mesh") << ": " << s.surface_nodes
              << " nodes, Hausdorff " << s.hausdorff_mm << " mm, mean " << s.mean_distance_mm
              << " mm; away from the cut ends: Hausdorff " << s.away.hausdorff_mm << " mm, mean "
              << s.away.mean_mm << " mm, nodes over 2 mm " << s.away.nodes_over_2mm << " of " << s.away.nodes
              << " (max " << s.away.node_max_mm << " mm); the test's nodes away from the ends: max "
              << d.maxCoeff() << " mm\n";
    // measured: mesh 1.69 mm / 0.071 mm, 0 nodes over 2 mm; mask 2.92 / 0.073 mm, 1 node (2.28 mm) at
    // the descending aorta's bend (atom 23). Before (circles marched along rays from an off-centre skeleton,
    // the mask's 4 enclosed holes kept): mesh 3.84, mask 11.8 mm; 4 and 3 nodes over 2 mm (up to 9.2 mm).
    if (from_mask) {
      EXPECT_LT(s.away.hausdorff_mm, 3.5);
      EXPECT_LE(s.away.nodes_over_2mm, 2);
      EXPECT_LT(s.away.node_max_mm, 3.0);
    } else {
      EXPECT_LE(s.away.hausdorff_mm, 2.0);  // the target
      EXPECT_EQ(s.away.nodes_over_2mm, 0);
    }
    EXPECT_LT(s.away.mean_mm, 0.1);
    EXPECT_LT(d.mean(), 0.02);
    // with the cut ends (the scan's cuts: flat caps the tree's ends reach): measured 2.92 (mask) / 3.06 mm
    EXPECT_LT(s.hausdorff_mm, 3.5);
    EXPECT_LT(s.mean_distance_mm, 0.1);
  }
  // the tubes (--no-blend): circles of the skeleton's inscribed radius, open at the cut ends
  VesselBuildSettings st;
  st.source.mask = testing::require_data_file("aorta_totalseg_mask.nii.gz");
  st.source.label = 1;
  st.all_branches = true;
  st.no_blend = true;
  const VesselBuild v = build_vessel(st);
  EXPECT_FALSE(v.summary.blended);
  EXPECT_LE(v.summary.rest_error_mm, 1e-9);
  const VecX d = away_from_ends(v);
  std::cout << "  aorta mask, tubes: Hausdorff " << v.summary.hausdorff_mm << " mm, away from the cut ends "
            << v.summary.away.hausdorff_mm << " mm; nodes away from the ends: mean " << d.mean() << " mm\n";
  EXPECT_LT(d.mean(), 3.0);
  EXPECT_LT(v.summary.hausdorff_mm, 16.0);
}

TEST(VesselTreeSkeleton, BadSegmentationsAreRefusedWithTheReason) {
  const std::filesystem::path dir = testing::temp_dir("vessel-tree-bad");
  auto label_file = [&](const std::string& name, const MaskVolume& m, std::int32_t label) {
    LabelVolume l;
    l.dims = m.dims;
    l.spacing = m.spacing;
    l.origin = m.origin;
    l.direction = m.direction;
    l.data.assign(m.data.begin(), m.data.end());
    for (auto& x : l.data) x *= label;
    write_label_volume(dir / name, l);
    return dir / name;
  };
  auto refused = [](const VesselBuildSettings& st, const std::string& words) {
    try {
      build_vessel(st);
      ADD_FAILURE() << "accepted; expected: " << words;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  VesselBuildSettings st;
  st.all_branches = true;
  MaskVolume y = y_mask(1.0);
  st.source.mask = label_file("y3.mha", y, 3);
  st.source.label = 5;  // absent
  refused(st, "5");
  MaskVolume empty = y;
  std::fill(empty.data.begin(), empty.data.end(), 0);
  st.source.mask = label_file("empty.mha", empty, 1);
  st.source.label = 1;
  refused(st, "");
  MaskVolume ball = y;  // a blob: its skeleton is only a spur
  for (Index k = 0; k < ball.dims[2]; ++k)
    for (Index j = 0; j < ball.dims[1]; ++j)
      for (Index i = 0; i < ball.dims[0]; ++i)
        ball.at(i, j, k) = (ball.to_world(Vec3(i, j, k)) - Vec3(20, 0, 0)).norm() <= 8.0 ? 1 : 0;
  st.source.mask = label_file("ball.mha", ball, 1);
  refused(st, "spur");
  MaskVolume two = y;  // two components
  for (Index k = 0; k < two.dims[2]; ++k)
    for (Index j = 0; j < two.dims[1]; ++j)
      for (Index i = 0; i < two.dims[0]; ++i)
        if (std::abs(two.to_world(Vec3(i, j, k)).x() - 15.0) < 1.5) two.at(i, j, k) = 0;
  st.source.mask = label_file("two.mha", two, 1);
  refused(st, "components");
}

}  // namespace
}  // namespace medspring
