// Branching SMRM vessels (issue 17, docs/vessels.md): VMTK polylines sharing their start merged into a
// tree, shared junction atoms, exact rest reconstruction of every branch, forces that reach the loaded
// branch most, and bad trees refused naming the line / branch / atom.
#include "medspring/models/smrm_tree.hpp"

#include <gtest/gtest.h>

#include <chrono>

#include "medspring/core/error.hpp"
#include "medspring/io/centerline_io.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

std::vector<Centerline> vmr_lines() {
  return read_centerlines(testing::require_data_file("vmr-0159-aorta-centerline.vtp"),
                          LengthUnit::Centimetre);
}

TEST(SmrmTree, VmrPolylinesMergeIntoATreeWhoseBranchesMeetAtJunctions) {
  const CenterlineTree t = merge_centerlines(vmr_lines());
  // 4 outlets: every line ends in its own leaf, and at least one junction joins them.
  Index leaves = 0;
  std::vector<int> children(t.branches.size(), 0);
  for (const auto& b : t.branches)
    if (b.parent >= 0) ++children[static_cast<std::size_t>(b.parent)];
  for (int c : children) leaves += c == 0 ? 1 : 0;
  EXPECT_EQ(leaves, 4);
  EXPECT_GE(t.junctions(), 1);
  EXPECT_EQ(t.branches[0].parent, -1);
  for (std::size_t b = 1; b < t.branches.size(); ++b) {
    const auto& br = t.branches[b];
    ASSERT_GE(br.parent, 0);
    const Centerline& p = t.branches[static_cast<std::size_t>(br.parent)].line;
    EXPECT_EQ((br.line.points.row(0) - p.points.row(p.size() - 1)).norm(), 0.0) << "branch " << b;
  }
}

TEST(SmrmTree, VmrTreeIsExactAtRestAndBendsTheLoadedBranchMost) {
  const CenterlineTree t = merge_centerlines(vmr_lines());
  const auto t0 = std::chrono::steady_clock::now();
  const SmrmTree tree(t);
  const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "[ tree     ] " << tree.num_branches() << " branches, " << tree.num_junctions()
            << " junctions, " << tree.num_atoms() << " atoms, " << tree.num_surface_nodes()
            << " surface nodes, built in " << build_s << " s\n";
  EXPECT_EQ(tree.num_branches(), static_cast<Index>(t.branches.size()));
  // Junction atoms are shared: a child's first atom is its parent's last.
  for (Index b = 1; b < tree.num_branches(); ++b)
    EXPECT_EQ(tree.branch_atoms(b).front(), tree.branch_atoms(tree.parent(b)).back());
  // Fixed: the inlet and the 4 outlets.
  Index fixed = 0;
  for (auto f : tree.model().fixed) fixed += f ? 1 : 0;
  EXPECT_EQ(fixed, 5);
  // Exact rest reconstruction and no force at rest.
  State s = make_state(tree.model());
  MatX3 S;
  tree.map_to_surface(s, S);
  EXPECT_LE((S - tree.rest_surface()).rowwise().norm().maxCoeff(), 1e-9);
  MatX3 f(tree.num_atoms(), 3);
  internal_forces(tree.model(), tree.model().x0, MatX3::Zero(tree.num_atoms(), 3), f);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-9);
  // 0.5 N on the middle of the last leaf: its atoms move most; the run is stable and returns to rest.
  const Index leaf = tree.num_branches() - 1;
  const std::vector<Index>& ids = tree.branch_atoms(leaf);
  const Index a = ids[ids.size() / 2];
  const Index node =
      tree.branch_vessel(leaf).contact_node(static_cast<Index>(ids.size() / 2), Vec3(1, 0, 0)) +
      tree.node_begin(leaf);
  EXPECT_EQ(tree.node_atom(node), a);
  MatX3 fe = MatX3::Zero(tree.num_atoms(), 3);
  tree.transfer_force(node, Vec3(0.5, 0, 0), fe);
  EXPECT_EQ(fe.row(a).norm(), 0.5);
  const std::vector<PointLoad> loads{{.node = a, .force = Vec3(0.5, 0, 0), .t_ramp = 20, .t_release = 300}};
  for (int k = 0; k < 600; ++k) step(tree.model(), s, {.dt = 0.5}, &loads);
  const VecX u = (s.x - tree.model().x0).rowwise().norm();
  Index peak = -1;
  u.maxCoeff(&peak);
  EXPECT_EQ(tree.node_atom(node), a);
  EXPECT_TRUE(std::find(ids.begin(), ids.end(), peak) != ids.end()) << "peak at atom " << peak;
  EXPECT_GT(u[a], 0.1);
  EXPECT_EQ(s.warnings.total(), 0u);
  for (int k = 0; k < 1000; ++k) step(tree.model(), s, {.dt = 0.5}, &loads);
  EXPECT_LT((s.x - tree.model().x0).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(SmrmTree, TreeFromParentIndicesHasItsJunctions) {
  // A Y: trunk 0-1-2-3, branch 3-4-5-6 and 3-7-8-9.
  MatX3 X(10, 3);
  X << 0, 0, 0, 5, 0, 0, 10, 0, 0, 15, 0, 0, 20, 3, 0, 25, 6, 0, 30, 9, 0, 20, -3, 0, 25, -6, 0, 30, -9, 0;
  const std::vector<Index> parent{-1, 0, 1, 2, 3, 4, 5, 3, 7, 8};
  const CenterlineTree t = tree_from_parents(X, parent, VecX::Constant(10, 1.0));
  ASSERT_EQ(t.branches.size(), 3u);
  EXPECT_EQ(t.junctions(), 1);
  EXPECT_EQ(t.branches[0].line.size(), 4);
  EXPECT_EQ(t.branches[1].parent, 0);
  EXPECT_EQ(t.branches[2].parent, 0);
  const SmrmTree tree(t, {.vessel = {.atoms = 7}});
  State s = make_state(tree.model());
  MatX3 S;
  tree.map_to_surface(s, S);
  EXPECT_LE((S - tree.rest_surface()).rowwise().norm().maxCoeff(), 1e-9);
  EXPECT_EQ(tree.num_junctions(), 1);
}

TEST(SmrmTree, BadTreesAreRefusedNamingThePart) {
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  Centerline a{MatX3(4, 3), VecX::Constant(4, 1.0), "a"};
  a.points << 0, 0, 0, 5, 0, 0, 10, 0, 0, 15, 0, 0;
  Centerline b = a;
  b.name = "b";
  b.points.rowwise() += Eigen::RowVector3d(0, 50, 0);
  EXPECT_NE(message([&] {
              merge_centerlines({a, b});
            }).find("'b': starts 50 mm from the start of 'a'"),
            std::string::npos);
  Centerline c = a;
  c.radii[2] = std::nan("");
  EXPECT_NE(message([&] {
              merge_centerlines({a, c});
            }).find("point 2: radius must be > 0"),
            std::string::npos);
  Centerline one{MatX3(1, 3), VecX::Constant(1, 1.0), "one"};
  one.points << 0, 0, 0;
  EXPECT_NE(message([&] { merge_centerlines({one}); }).find("'one': has 1 point(s)"), std::string::npos);
  Centerline loop{MatX3(6, 3), VecX::Constant(6, 0.5), "loop"};
  loop.points << 0, 0, 0, 5, 0, 0, 5, 5, 0, 0, 5, 0, 0, 0, 0, -5, 0, 0;
  EXPECT_NE(message([&] { merge_centerlines({loop}); }).find("'loop': point 4 comes back to point 0"),
            std::string::npos);
  MatX3 X(3, 3);
  X << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  EXPECT_NE(message([&] {
              tree_from_parents(X, {-1, 0, 5}, VecX::Constant(3, 1.0));
            }).find("atom 2: parent 5"),
            std::string::npos);
  EXPECT_NE(message([&] {
              tree_from_parents(X, {-1, 0, 1}, VecX::Constant(3, -1.0));
            }).find("atom 0: radius"),
            std::string::npos);
  // A branch shorter than two atoms at the tree's spacing.
  CenterlineTree t;
  t.branches.push_back({a, -1});
  Centerline stub{MatX3(2, 3), VecX::Constant(2, 1.0), "stub"};
  stub.points << 15, 0, 0, 15.1, 0, 0;
  t.branches.push_back({stub, 0});
  EXPECT_NE(message([&] { SmrmTree tree(t, {.vessel = {.atoms = 4}}); }).find("branch 1 ('stub') is 0.1"),
            std::string::npos);
  t.branches[1].line.points.row(0) << 14, 0, 0;
  EXPECT_NE(
      message([&] { SmrmTree tree(t); }).find("branch 1 ('stub') starts 1 mm from the end of its parent"),
      std::string::npos);
}

}  // namespace
}  // namespace medspring
