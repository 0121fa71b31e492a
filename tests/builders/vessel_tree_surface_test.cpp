// The watertight junction surface of a vessel tree (issue 17, docs/vessels.md): the union of the closed
// path tubes of the real VMR 0159 tree is one closed, manifold, outward, self-intersection-free surface,
// bound to the branch atoms (exact at rest), that follows the deformed tree and survives a model package.
#include <gtest/gtest.h>

#include <algorithm>

#include "medspring/builders/vessel_build.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/meshing/mesh_repair.hpp"
#include "medspring/meshing/mesh_union.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/physics/integrators.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

VesselBuildSettings vmr_tree_settings(bool blend) {
  VesselBuildSettings st;
  st.centerline = testing::require_data_file("vmr-0159-aorta-centerline.vtp");
  st.centerline_unit = LengthUnit::Centimetre;
  st.all_branches = true;
  st.blend = blend;
  return st;
}

TEST(VesselTreeSurface, PathTubesAreClosedAndOutward) {
  const VesselBuild plain = build_vessel(vmr_tree_settings(false));
  std::vector<std::vector<Index>> paths;
  const auto tubes = tree_path_tubes(plain.tree->centerline_tree(), 30, 4.0, &paths);
  ASSERT_EQ(tubes.size(), paths.size());
  EXPECT_EQ(tubes.size(), 4u);  // one path per outlet
  Index covered = 0;
  for (const auto& p : paths) covered += static_cast<Index>(p.size());
  EXPECT_EQ(covered, plain.tree->num_branches());  // every branch in exactly one path
  for (std::size_t k = 0; k < tubes.size(); ++k) {
    const ClosedManifoldReport r = check_closed_manifold(tubes[k]);
    EXPECT_TRUE(r.ok()) << "tube " << k << ": " << r.mesh.summary();
    EXPECT_GT(signed_volume(tubes[k].V, tubes[k].F), 0.0) << "tube " << k;
    EXPECT_EQ(self_intersections(tubes[k]), 0) << "tube " << k;
  }
}

TEST(VesselTreeSurface, VmrTreeSurfaceIsOneClosedManifoldWithoutSelfIntersection) {
  const VesselBuild v = build_vessel(vmr_tree_settings(true));
  const VesselSummary& s = v.summary;
  std::cout << "[ surface  ] " << s.surface_nodes << " nodes, " << s.faces << " triangles, " << s.path_tubes
            << " tubes, volume " << s.surface_volume_mm3 << " mm^3, rest error " << s.rest_error_mm
            << " mm, built in " << s.seconds << " s\n";
  ASSERT_TRUE(v.tree);
  const SmrmTree& t = *v.tree;
  EXPECT_TRUE(t.blended());
  EXPECT_TRUE(s.blended);
  EXPECT_TRUE(s.surface_closed);
  EXPECT_EQ(s.surface_components, 1);
  EXPECT_EQ(s.self_intersections, 0);
  EXPECT_GT(s.surface_volume_mm3, 0.0);
  // The tree's own surface: closed, manifold, consistently oriented, outward, one component.
  const SurfaceMesh m{t.rest_surface(), t.faces()};
  const ClosedManifoldReport r = check_closed_manifold(m);
  EXPECT_TRUE(r.ok()) << r.mesh.summary();
  EXPECT_EQ(r.mesh.components, 1);
  EXPECT_GT(signed_volume(m.V, m.F), 0.0);
  EXPECT_EQ(self_intersections(m), 0);
  // Exact rest reconstruction (§5.9 binding) and every branch carries part of the surface.
  EXPECT_LE(s.rest_error_mm, 1e-9);
  std::vector<Index> per_branch(static_cast<std::size_t>(t.num_branches()), 0);
  for (Index k = 0; k < t.num_surface_nodes(); ++k) ++per_branch[static_cast<std::size_t>(t.node_branch(k))];
  for (Index b = 0; b < t.num_branches(); ++b) EXPECT_GT(per_branch[static_cast<std::size_t>(b)], 0) << b;
}

TEST(VesselTreeSurface, SurfaceFollowsTheLoadedTreeAndSurvivesAPackage) {
  const VesselBuild v = build_vessel(vmr_tree_settings(true));
  const SmrmTree& t = *v.tree;
  // Load a surface node of the last leaf's middle: its atoms move, the surface follows them.
  const Index leaf = t.num_branches() - 1;
  const Index a = t.branch_atoms(leaf)[t.branch_atoms(leaf).size() / 2];
  Index node = -1;
  for (Index k = 0; k < t.num_surface_nodes() && node < 0; ++k)
    if (t.node_atom(k) == a) node = k;
  ASSERT_GE(node, 0);
  State st = make_state(t.model());
  t.transfer_force(node, Vec3(0.5, 0.0, 0.0), st.f_ext);
  EXPECT_GT(st.f_ext.rowwise().norm().maxCoeff(), 0.0);
  for (int f = 0; f < 200; ++f) step(t.model(), st, {.dt = 0.5});
  MatX3 S;
  t.map_to_surface(st, S);
  ASSERT_TRUE(S.allFinite());
  const VecX u = (S - t.rest_surface()).rowwise().norm();
  EXPECT_GT(u[node], 0.1);  // mm: the loaded node moved
  // The loaded leaf moves more than the root (whose inlet is fixed).
  double on_leaf = 0.0, on_root = 0.0;
  for (Index k = 0; k < t.num_surface_nodes(); ++k) {
    if (t.node_branch(k) == leaf) on_leaf = std::max(on_leaf, u[k]);
    if (t.node_branch(k) == 0) on_root = std::max(on_root, u[k]);
  }
  EXPECT_GT(on_leaf, 2.0 * on_root);
  // A model package rebuilds the same blended tree.
  const ModelPackage p = decode_model_package(encode_model_package(package_of(t, "tree")), "tree");
  const BodyPtr b = make_body(p);
  const auto* back = dynamic_cast<const SmrmTree*>(b.get());
  ASSERT_NE(back, nullptr);
  EXPECT_TRUE(back->blended());
  ASSERT_EQ(back->rest_surface().rows(), t.rest_surface().rows());
  EXPECT_EQ(back->faces(), t.faces());
  MatX3 S2;
  back->map_to_surface(st, S2);
  EXPECT_LE((S2 - S).cwiseAbs().maxCoeff(), 1e-12);
}

// The union's numbering is canonical (vertices in coordinate order, faces sorted): the same solids give
// the same mesh, node for node, whatever the parts' own numbering -- a scene's load on a node index of a
// watertight tree presses the same point in every run.
TEST(VesselTreeSurface, UnionNumberingIsCanonical) {
  SurfaceMesh a = icosphere(2, 10.0), b = icosphere(2, 8.0);
  for (Index v = 0; v < b.num_vertices(); ++v) b.V.row(v) += Vec3(9.0, 1.0, 0.5).transpose();
  const SurfaceMesh u = union_of_closed_meshes({a, b}, "two balls");
  SurfaceMesh c = b;  // b with its vertices numbered backwards
  const Index n = b.num_vertices();
  for (Index v = 0; v < n; ++v) c.V.row(n - 1 - v) = b.V.row(v);
  for (Index f = 0; f < b.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) c.F(f, k) = static_cast<int>(n - 1 - b.F(f, k));
  const SurfaceMesh again = union_of_closed_meshes({a, b}, "two balls"),
                    relabelled = union_of_closed_meshes({a, c}, "two balls");
  ASSERT_EQ(again.V.rows(), u.V.rows());
  EXPECT_EQ(again.V, u.V);
  EXPECT_EQ(again.F, u.F);
  ASSERT_EQ(relabelled.V.rows(), u.V.rows());
  EXPECT_EQ(relabelled.V, u.V);
  EXPECT_EQ(relabelled.F, u.F);
  for (Index v = 1; v < u.num_vertices(); ++v) EXPECT_LE(u.V(v - 1, 0), u.V(v, 0));  // coordinate order
  EXPECT_GT(signed_volume(u.V, u.F), 0.0);
}

TEST(VesselTreeSurface, BlendNeedsATree) {
  VesselBuildSettings st = vmr_tree_settings(true);
  st.all_branches = false;
  EXPECT_THROW(build_vessel(st), InvalidInput);
  st = vmr_tree_settings(true);
  st.blend_spacing = -1.0;
  EXPECT_THROW(build_vessel(st), InvalidInput);
}

}  // namespace
}  // namespace medspring
