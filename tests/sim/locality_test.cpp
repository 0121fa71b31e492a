// Issue 15, locality: reverse Cuthill-McKee node orders, a large mesh with scattered numbering simulated in
// that order behind SurfaceBody's surface <-> DOF map (results identical up to the permutation, users keep
// their node numbers), and lazily computed normals.
#include "medspring/geometry/locality.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <numeric>
#include <random>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/state.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring {
namespace {

std::vector<Index> shuffled(Index n, std::uint64_t seed) {
  std::vector<Index> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  std::mt19937_64 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  return order;
}

bool is_permutation_of_n(const std::vector<Index>& p, Index n) {
  std::vector<Index> s = p;
  std::sort(s.begin(), s.end());
  for (Index k = 0; k < n; ++k)
    if (s.size() != static_cast<std::size_t>(n) || s[static_cast<std::size_t>(k)] != k) return false;
  return true;
}

TEST(Locality, RcmOfAShuffledTubeRestoresASmallBandwidth) {
  const SurfaceMesh t = tube(60, 40);  // ring-by-ring numbering: bandwidth spokes + 1 = 41
  EXPECT_EQ(mesh_bandwidth(t), 41);
  const SurfaceMesh s = permute_vertices(t, shuffled(t.num_vertices(), 7));
  EXPECT_GT(mesh_bandwidth(s), 1000);
  const std::vector<Index> order = locality_order(s);
  ASSERT_TRUE(is_permutation_of_n(order, s.num_vertices()));
  const SurfaceMesh r = permute_vertices(s, order);
  EXPECT_LE(mesh_bandwidth(r), 2 * 41);  // RCM's level sets of a tube are its rings (up to a twist)
  // same geometry and faces, renumbered: vertex k of r is vertex order[k] of s
  for (Index k = 0; k < r.num_vertices(); ++k)
    EXPECT_EQ(r.V.row(k), s.V.row(order[static_cast<std::size_t>(k)]));
  const std::vector<Index> inv = inverse_permutation(order);
  for (Index f = 0; f < s.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(r.F(f, c), inv[static_cast<std::size_t>(s.F(f, c))]);
  EXPECT_EQ(locality_order(s), order);  // deterministic
}

TEST(Locality, DisconnectedAndIsolatedNodesArePlaced) {
  SurfaceMesh m;
  m.V.setZero(7, 3);
  for (Index k = 0; k < 7; ++k) m.V(k, 0) = static_cast<double>(k);
  m.F.resize(2, 3);
  m.F << 0, 5, 2, 6, 3, 1;  // two triangles, node 4 in none
  const std::vector<Index> order = locality_order(m);
  EXPECT_TRUE(is_permutation_of_n(order, 7));
}

TEST(Locality, BadPermutationsAreRefused) {
  const SurfaceMesh t = tube(4, 5);
  EXPECT_THROW(permute_vertices(t, {0, 1, 2}), InvalidInput);
  std::vector<Index> p(20);
  std::iota(p.begin(), p.end(), 0);
  p[3] = 4;
  EXPECT_THROW(permute_vertices(t, p), InvalidInput);
  p[3] = 20;
  EXPECT_THROW(inverse_permutation(p), InvalidInput);
}

// A tube with shuffled numbering (what a mesh from elsewhere may look like): SurfaceBody simulates it in
// reverse Cuthill-McKee order behind its surface <-> DOF map. Compared with the same mesh stepped directly
// in the user's numbering (make_surface_model + step, no reordering): the displayed surface and normals
// agree node for node (to rounding: each node's spring forces are summed in another order), and loads,
// fixed nodes, the tool node and the local patch are all given and reported in the user's numbering.
TEST(Locality, ShuffledLargeMeshSimulatesIdenticallyInTheUsersNumbering) {
  const Index rings = 160, spokes = 128;  // 20,480 nodes >= kLocalityReorderMinNodes
  const SurfaceMesh t = tube(rings, spokes, 2.5, 2.5 * spokes / (2 * 3.141592653589793));
  const std::vector<Index> old_of_new = shuffled(t.num_vertices(), 15);
  const std::vector<Index> new_of_old = inverse_permutation(old_of_new);
  const SurfaceMesh s = permute_vertices(t, old_of_new);
  auto user = [&](Index tube_node) { return new_of_old[static_cast<std::size_t>(tube_node)]; };

  SurfaceBodyParams pt, ps;
  for (Index j = 0; j < spokes; ++j)
    for (const Index v : {j, (rings - 1) * spokes + j}) {
      pt.fixed.push_back(v);
      ps.fixed.push_back(user(v));
    }
  EXPECT_TRUE(SurfaceBody(t, pt, "ordered").dof_of_surface().empty());  // already local: kept as it is
  auto bs = std::make_shared<SurfaceBody>(s, ps, "shuffled");
  ASSERT_FALSE(bs->dof_of_surface().empty());
  EXPECT_TRUE(is_permutation_of_n(bs->dof_of_surface(), s.num_vertices()));
  EXPECT_EQ(bs->rest_surface(), s.V);
  EXPECT_EQ(bs->faces(), s.F);
  const std::vector<std::uint8_t> fs = bs->fixed_surface_nodes();
  for (Index v = 0; v < s.num_vertices(); ++v) {
    const bool pinned = std::find(ps.fixed.begin(), ps.fixed.end(), v) != ps.fixed.end();
    EXPECT_EQ(fs[static_cast<std::size_t>(v)], pinned ? 1 : 0);
  }
  // the model itself is in locality order
  SurfaceMesh dof_mesh{bs->model().x0, MatX3i(s.F.rows(), 3)};
  for (Index f = 0; f < s.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) dof_mesh.F(f, c) = bs->dof_of(s.F(f, c));
  EXPECT_LT(mesh_bandwidth(dof_mesh), 4 * spokes);
  EXPECT_GT(mesh_bandwidth(s), 100 * spokes);

  // the reference: the same mesh in the user's numbering, stepped directly
  const Model ref = make_surface_model(s, ps, "reference");
  State rs = make_state(ref);
  const Index loaded = user((rings / 2) * spokes + spokes / 4), other = user((rings / 3) * spokes + 3);
  const Vec3 F(0, 0.2, -0.5);
  rs.f_ext.row(loaded) = F.transpose();
  rs.f_ext.row(other) = 0.1 * F.transpose();
  Simulation b(bs);
  b.set_loads({{.node = loaded, .force = F, .t_ramp = 0}, {.node = other, .force = 0.1 * F, .t_ramp = 0}});
  for (int k = 0; k < 30; ++k) {
    step(ref, rs, b.settings().step);
    b.update();
  }
  EXPECT_EQ(rs.substeps, b.state().substeps);
  const double scale = (rs.x - ref.x0).cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0.05);  // the load moved the tube
  EXPECT_LT((b.surface() - rs.x).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + scale));
  MatX3 n_ref;
  vertex_normals(rs.x, s.F, n_ref);
  EXPECT_LT((b.normals() - n_ref).cwiseAbs().maxCoeff(), 1e-9);
  for (const Index v : {ps.fixed.front(), ps.fixed.back()}) EXPECT_EQ(b.surface().row(v), s.V.row(v));

  // the local patch and the tool node are in the user's numbering
  SimulationSettings st;
  st.local.enabled = true;
  Simulation c(bs, st);
  c.set_tool_force(loaded, F);
  c.update();
  ASSERT_EQ(c.local_nodes().size(), 25u);
  EXPECT_EQ(c.local_nodes().front(), loaded);
  const std::vector<int> hops = hop_distances(vertex_adjacency(s.num_vertices(), unique_edges(s.F)), loaded);
  for (const Index v : c.local_nodes()) EXPECT_LE(hops[static_cast<std::size_t>(v)], 3) << v;
  const MatX3 U = c.surface() - c.global_surface();
  EXPECT_NEAR(U.row(loaded).normalized().dot(F.normalized()), 1.0, 1e-9);
  EXPECT_GT((c.global_surface().row(loaded) - s.V.row(loaded)).norm(), 0.0);

  // bad numbers are refused naming the user's numbering
  SurfaceBodyParams bad = ps;
  bad.fixed.push_back(s.num_vertices());
  try {
    SurfaceBody x(s, bad, "shuffled");
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("fixed["), std::string::npos) << e.what();
  }
}

// The hybrid kidney does the same from kLocalityReorderMinNodes surface nodes on (by default): a shuffled
// 20,480-node tube with atoms on its axis is simulated in RCM order (atoms after the surface nodes), a
// well-numbered one as it is. (The real kidney against its unrenumbered twin: builders_tests,
// kidney_locality_test.cpp.)
TEST(Locality, LargeShuffledHybridIsRenumberedByDefault) {
  const Index rings = 160, spokes = 128;
  const double radius = 2.5 * spokes / (2 * 3.141592653589793);
  const SurfaceMesh t = tube(rings, spokes, 2.5, radius);
  const SurfaceMesh s = permute_vertices(t, shuffled(t.num_vertices(), 16));
  MatX3 atoms(30, 3);
  for (Index a = 0; a < 30; ++a)  // on the tube's axis (x)
    atoms.row(a) =
        Vec3(2.5 * static_cast<double>(rings - 1) * (static_cast<double>(a) + 0.5) / 30.0, 0, 0).transpose();
  EXPECT_TRUE(HybridKidney(t, atoms, {}, "ordered").dof_of_surface().empty());
  const HybridKidney h(s, atoms, {}, "shuffled");
  ASSERT_EQ(static_cast<Index>(h.dof_of_surface().size()), s.num_vertices());
  SurfaceMesh dof_mesh{h.model().x0.topRows(s.num_vertices()), MatX3i(s.F.rows(), 3)};
  for (Index f = 0; f < s.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) dof_mesh.F(f, c) = h.dof_of(s.F(f, c));
  EXPECT_LT(mesh_bandwidth(dof_mesh), 4 * spokes);
  EXPECT_EQ(h.model().x0.bottomRows(30), atoms);
  EXPECT_EQ(h.atom_dof(0), s.num_vertices());
  // a force on a user's node lands on its DOF
  MatX3 f = MatX3::Zero(h.model().num_nodes(), 3);
  h.transfer_force(77, Vec3(1, 2, 3), f);
  EXPECT_EQ(f.row(h.dof_of(77)), Vec3(1, 2, 3).transpose());
}

TEST(LazyNormals, ComputedWhenReadAndCurrentAfterEveryUpdate) {
  auto body = std::make_shared<HybridKidney>(hybrid_kidney_phantom());
  Simulation sim(body);
  sim.set_loads({{.node = 223, .force = Vec3(0, 0, -1), .t_ramp = 0}});
  MatX3 expect;
  for (int k = 0; k < 3; ++k) {
    sim.advance(5);
    vertex_normals(sim.surface(), body->faces(), expect);
    EXPECT_EQ(sim.normals(), expect);  // the same function on the current surface: bit-identical
  }
  const MatX3* storage = &sim.normals();
  sim.update();
  EXPECT_EQ(storage, &sim.normals());  // same storage (a Python view keeps pointing at it)
  vertex_normals(sim.surface(), body->faces(), expect);
  EXPECT_EQ(*storage, expect);
  SimulationSettings off;
  off.normals = false;
  sim.set_settings(off);
  sim.update();
  EXPECT_EQ(sim.normals().rows(), 0);
}

// Bad input: a model too large for memory is refused up front with one line (no bad_alloc, no overflow).
TEST(TooLarge, ModelsBeyondMemoryOrIndexRangeAreRefusedUpFront) {
  try {
    tube(100000, 50000);  // 5e9 nodes: more than 32-bit indices hold
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("too large"), std::string::npos) << e.what();
  }
  ::setenv("MEDSPRING_MEMORY_LIMIT_MB", "100", 1);
  const SurfaceMesh t = tube(400, 500);  // 200,000 nodes: the mesh fits in 100 MB, the model does not
  std::string message;
  try {
    SurfaceBody b(t, SurfaceBodyParams{}, "big");
  } catch (const InvalidInput& e) {
    message = e.what();
  }
  try {
    HybridKidney h(t, kidney_phantom_atoms(), HybridSettings{}, "big kidney");
    message += " | never";
  } catch (const InvalidInput& e) {
    message += std::string(" | ") + e.what();
  }
  ::unsetenv("MEDSPRING_MEMORY_LIMIT_MB");
  EXPECT_EQ(message.find('\n'), std::string::npos);
  EXPECT_NE(message.find("big: a model of 200000 nodes: needs about 0.2 GB of memory, more than the 0.1 GB"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("big kidney: a hybrid model of 200000 surface nodes: needs about"),
            std::string::npos)
      << message;
  EXPECT_EQ(make_surface_model(tube(40, 30), SurfaceBodyParams{}).num_nodes(), 1200);  // limit lifted
}

}  // namespace
}  // namespace medspring
