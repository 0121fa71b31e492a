// "No allocation in the update loop" (DESIGN.md, issue 22), proven for every model kind: 10^4 updates
// of a Simulation with the local deformation on and a sphere tool in contact that moves to another
// surface node every 100 updates (so the contact node, its local patch and the tool's contact set
// change), after a warm-up that visits every contact site once. Counted by the replaced global
// operator new and malloc family of tests/support/alloc_counter.hpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <memory>
#include <vector>

#include "alloc_counter.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/medial/chain.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_tree.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/models/tube_hybrid.hpp"
#include "medspring/sim/tool_sim.hpp"
#ifdef MEDSPRING_NO_ALLOC_HAVE_FEM
#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/linear_response.hpp"
#include "medspring/physics/parallel.hpp"
#endif

namespace medspring {
namespace {

constexpr int kUpdates = 10000;  // counted updates
constexpr int kHold = 100;       // updates per contact site
constexpr double kRadius = 4.0;  // sphere tool, mm
constexpr double kDepth = 0.6;   // how far the sphere starts inside the rest surface, mm

struct Result {
  long allocations = 0;
  std::size_t distinct_patches = 0;  // local patches (by their first node) met while counting
  double max_local = 0;              // largest |U| of the overlay while counting, mm
  std::size_t largest_patch = 0;     // most nodes of a local patch while counting (a volumetric body's
                                     // distributed patch: the tool's contact nodes plus one ring)
  Index tool_contacts = 0;           // nodes in contact with the tool at the end
  int failed_updates = 0;
};

/// Presses a sphere on each of `sites` (surface nodes) in turn, kHold updates each: `updates` counted
/// updates (kUpdates unless given) after a warm-up of two rounds over the sites.
/// ring_spokes > 0: a structured tube of rings of that many nodes, pressed along the direction from its
/// ring's centre (the vertex normals of an open tube may point into the lumen).
Result run(const BodyPtr& body, const std::vector<Index>& sites, Index ring_spokes,
           StableStep rule = StableStep::Bound, int updates = kUpdates, int threads = 1) {
  SimulationSettings settings;
  settings.step.stable_step = rule;
  settings.step.threads = threads;
  settings.local.enabled = true;
  Simulation sim(body, settings);
  ToolSimulation tools(sim, {.friction = 0.2});
  const MatX3& X = body->rest_surface();
  MatX3 N;
  vertex_normals(X, body->faces(), N);
  if (ring_spokes > 0)
    for (Index node : sites) {
      const Index ring = node / ring_spokes;
      const Vec3 centre = X.middleRows(ring * ring_spokes, ring_spokes).colwise().mean().transpose();
      N.row(node) = (X.row(node).transpose() - centre).normalized().transpose();
    }
  const auto pose_at = [&](Index node, double offset) {
    Pose p;
    p.position = X.row(node).transpose() + (kRadius + offset) * N.row(node).transpose();
    return p;
  };
  const Index k = tools.add_tool(Tool::sphere(kRadius), pose_at(sites[0], 2.0));  // starts outside
  Result r;
  std::vector<Index> patches;
  patches.reserve(4096);  // before counting
  const auto one = [&](int i, bool counting) {
    if (i % kHold == 0)
      tools.set_pose(k, pose_at(sites[static_cast<std::size_t>(i / kHold) % sites.size()], -kDepth));
    if (!tools.update().ok()) ++r.failed_updates;
    if (!counting || sim.local_nodes().empty()) return;
    const Index first = sim.local_nodes().front();
    r.largest_patch = std::max(r.largest_patch, sim.local_nodes().size());
    if (std::find(patches.begin(), patches.end(), first) == patches.end() &&
        patches.size() < patches.capacity())
      patches.push_back(first);
    for (Index row = 0; row < sim.local_displacement().rows(); ++row)
      r.max_local = std::max(r.max_local, sim.local_displacement().row(row).norm());
  };
  const int warm = static_cast<int>(sites.size()) * kHold * 2;
  for (int i = 0; i < warm; ++i) one(i, false);
  const long before = testing::heap_allocations();
  for (int i = warm; i < warm + updates; ++i) one(i, true);
  r.allocations = testing::heap_allocations() - before;
  r.distinct_patches = patches.size();
  r.tool_contacts = tools.contact().state(k).contacts;
  return r;
}

void expect_no_allocation(const char* kind, const BodyPtr& body, const std::vector<Index>& sites,
                          Index ring_spokes = 0, StableStep rule = StableStep::Bound, int updates = kUpdates,
                          int threads = 1) {
  SCOPED_TRACE(kind);
  const Result r = run(body, sites, ring_spokes, rule, updates, threads);
  std::cout << "[ " << kind << " ] " << r.allocations << " allocations in " << updates << " updates; "
            << r.distinct_patches << " local patches (the largest " << r.largest_patch << " nodes), max |U| "
            << r.max_local << " mm, " << r.tool_contacts << " tool contacts at the end\n";
  EXPECT_EQ(r.allocations, 0) << kind << ": heap allocations in " << updates << " updates after warm-up";
  EXPECT_EQ(r.failed_updates, 0);
  // the loop did what it claims: the tool touched, the overlay moved nodes, the contact moved
  EXPECT_GT(r.tool_contacts, 0);
  EXPECT_GT(r.max_local, 1e-4);
  EXPECT_GE(r.distinct_patches, sites.size());
}

TEST(UpdateNoAllocation, TheCounterSeesOperatorNewAndEigen) {  // so that the tests below can fail
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  long before = testing::heap_allocations();
  auto p = std::make_unique<int>(3);
  EXPECT_GE(testing::heap_allocations() - before, 1);
  before = testing::heap_allocations();
  MatX3 m(100, 3);
  m.setZero();
  EXPECT_GE(testing::heap_allocations() - before, 1);
}

TEST(UpdateNoAllocation, HybridKidney) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  expect_no_allocation("hybrid", std::make_shared<HybridKidney>(hybrid_kidney_phantom()),
                       {223, 40, 300, 120});
}

TEST(UpdateNoAllocation, SurfaceTube) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  SurfaceBodyParams p;
  p.fixed = {};
  for (Index s = 0; s < 30; ++s) {  // pin both end rings
    p.fixed.push_back(s);
    p.fixed.push_back(39 * 30 + s);
  }
  auto body = std::make_shared<SurfaceBody>(tube(40, 30), p, "tube", GridLayout{40, 30});
  expect_no_allocation("surface", body, {20 * 30 + 7, 12 * 30 + 20, 28 * 30 + 3, 16 * 30 + 15}, 30);
}

TEST(UpdateNoAllocation, SmrmVessel) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  auto body = std::make_shared<SmrmVessel>(smrm_phantom(VesselPath::Helix, CrossSectionShape::NonPlanar));
  const Index s = body->grid().valid() ? body->grid().spokes : 30;
  expect_no_allocation("smrm", body, {20 * s + 7, 12 * s + 20, 28 * s + 3, 16 * s + 15}, s);
}

TEST(UpdateNoAllocation, SmrmTree) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  // A Y: a trunk along x, two branches from its end.
  const int n = 9;
  MatX3 atoms(3 * n - 2, 3);
  std::vector<Index> parent;
  VecX radii = VecX::Constant(3 * n - 2, 3.0);
  for (int i = 0; i < n; ++i) {
    atoms.row(i) = Vec3(5.0 * i, 0, 0).transpose();
    parent.push_back(i - 1);
  }
  for (int b = 0; b < 2; ++b)
    for (int i = 1; i < n; ++i) {
      const Index a = n + b * (n - 1) + (i - 1);
      atoms.row(a) = Vec3(40.0 + 4.5 * i, (b ? -1 : 1) * 2.5 * i, 0).transpose();
      parent.push_back(i == 1 ? n - 1 : a - 1);
    }
  auto body = std::make_shared<SmrmTree>(tree_from_parents(atoms, parent, radii));
  const Index m = body->num_surface_nodes();
  expect_no_allocation("smrm_tree", body, {m / 7, m / 3, m / 2, (5 * m) / 6});
}

TEST(UpdateNoAllocation, TubeHybrid) {  // the paper's "MS" vessel (Tables I and II)
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
  auto body = std::make_shared<TubeHybridBody>(TubeHybridSettings{.nonlinear = true});
  const Index s = body->settings().spokes;
  expect_no_allocation("tube_hybrid", body, {20 * s + 7, 12 * s + 20, 28 * s + 3, 16 * s + 15}, s);
}

#ifdef MEDSPRING_NO_ALLOC_HAVE_FEM
// The volumetric kidney phantom of these tests: 10 kPa, nu = 0.45, supports on the bottom 20 %, the local
// overlay on (off by default), so that its patches are counted too; `edit` changes the settings.
template <class Edit>
std::shared_ptr<VolumetricBody> volumetric_kidney(Index nodes, const char* name, Edit&& edit) {
  const SurfaceMesh s = kidney_phantom();
  const double zmin = s.V.col(2).minCoeff(), zmax = s.V.col(2).maxCoeff();
  VolumetricSettings st;
  st.fixed = fem::support_nodes(s.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
  st.overlay_compliance = 1.0;
  edit(st);
  return std::make_shared<VolumetricBody>(fem::volumetric_mesh(s, {.target_nodes = nodes}), st, name);
}

// Four surface sites on the upper 40 % of the body, away from the supports.
std::vector<Index> upper_sites(const VolumetricBody& body) {
  const MatX3& S = body.rest_surface();
  const double zmin = S.col(2).minCoeff(), zmax = S.col(2).maxCoeff();
  std::vector<Index> sites;
  const Index ns = body.num_surface_nodes();
  for (Index i = 0; i < ns && sites.size() < 4; i += ns / 16 + 1)
    if (S(i, 2) > zmin + 0.6 * (zmax - zmin)) sites.push_back(i);
  return sites;
}
#endif

TEST(UpdateNoAllocation, VolumetricKidney) {  // issue 23: the fused tetrahedron pass, volume terms, supports
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
#ifdef MEDSPRING_NO_ALLOC_HAVE_FEM
  // the volume pass in double
  auto body = volumetric_kidney(
      700, "kidney", [](VolumetricSettings& st) { st.volume_precision = VolumePrecision::Double; });
  ASSERT_GT(body->model().volume.size(), 0);
  const std::vector<Index> sites = upper_sites(*body);
  ASSERT_EQ(sites.size(), 4u);
  expect_no_allocation("volumetric", body, sites);
  // the opt-in tangent refresh (StepSettings::stable_step): its scratch is sized before the counted updates
  expect_no_allocation("volumetric, stable_step refresh", body, sites, 0, StableStep::Refresh);
  // the single-precision volume pass (volume_precision float, the default): its float scratch sized with the
  // state
  auto body32 = volumetric_kidney(700, "kidney (float)", [](VolumetricSettings&) {});
  ASSERT_TRUE(body32->model().volume_f32 != nullptr);
  expect_no_allocation("volumetric, volume_precision float", body32, sites);
  // the threaded float passes (StepSettings::threads; threaded_volume.hpp): a finer interior, two threads'
  // worth of tetrahedra; the pool and its shares are made before the counted updates
  auto body_t = volumetric_kidney(1000, "kidney (threads)", [](VolumetricSettings&) {});
  ASSERT_EQ(effective_threads(body_t->model(), {.threads = 2}), threads_supported() ? 2 : 1);
  expect_no_allocation("volumetric, two threads", body_t, sites, 0, StableStep::Bound, kUpdates, 2);
#else
  GTEST_SKIP() << "built without the fem layer (TetGen)";
#endif
}

// issue 23: the quasi-static linear response (Integrator::LinearStatic, docs/linear-response.md): no tool (it
// refuses them); a tool force (Simulation::set_tool_force, the haptic coupling's path) that moves between
// four sites every 100 updates, on nodes whose response columns were cached beforehand
// (LinearResponse::precompute), with the local overlay on.
TEST(UpdateNoAllocation, VolumetricKidneyLinearStatic) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
#ifdef MEDSPRING_NO_ALLOC_HAVE_FEM
  auto body = volumetric_kidney(700, "kidney", [](VolumetricSettings&) {});
  const std::vector<Index> sites = upper_sites(*body);
  ASSERT_EQ(sites.size(), 4u);
  SimulationSettings ss;
  ss.step.integrator = Integrator::LinearStatic;
  Simulation sim(body, ss);
  ASSERT_TRUE(sim.state().linear != nullptr);
  sim.state().linear->precompute(sites);  // volumetric bodies: surface node i is model node i
  auto run = [&](int updates) {
    int failed = 0;
    double peak = 0;
    for (int u = 0; u < updates; ++u) {
      if (u % kHold == 0)
        sim.set_tool_force(sites[static_cast<std::size_t>((u / kHold) % 4)], Vec3(0.01 * (u % 3), 0.0, -0.1));
      failed += sim.update().ok() ? 0 : 1;
      peak = std::max(peak, (sim.state().x - body->model().x0).cwiseAbs().maxCoeff());
    }
    return std::pair{failed, peak};
  };
  run(2 * 4 * kHold);  // the warm-up: every site, the overlay's patches
  const long before = testing::heap_allocations();
  const auto [failed, peak] = run(kUpdates);
  const long allocations = testing::heap_allocations() - before;
  std::cout << "[ volumetric, linear_static ] " << allocations << " allocations in " << kUpdates
            << " updates; peak " << peak << " mm\n";
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(failed, 0);
  EXPECT_GT(peak, 0.1);
  EXPECT_EQ(sim.state().linear->cached_nodes(), 4u);
#else
  GTEST_SKIP() << "built without the fem layer (TetGen)";
#endif
}

// issue 23: the same kidney with the opt-in thin-tetrahedron terms (thin_tet_correction.hpp: fixed-size Eigen
// only; the model steps through internal_forces, no gather pass)
TEST(UpdateNoAllocation, VolumetricKidneyWithThinTetTerms) {
  if (!testing::counting_allocations()) GTEST_SKIP() << "allocation counting is off (sanitizer or not glibc)";
#ifdef MEDSPRING_NO_ALLOC_HAVE_FEM
  auto body = volumetric_kidney(700, "kidney", [](VolumetricSettings& st) {
    st.thin_tet = ThinTetMode::ScaleSprings;
    st.thin_tet_q_max = 0.5;
  });
  ASSERT_GT(body->model().thin.size(), 0);
  const std::vector<Index> sites = upper_sites(*body);
  ASSERT_EQ(sites.size(), 4u);
  // 400 counted updates (one round over the four sites after the two-round warm-up): the thin-tetrahedron
  // step is ~25x the plain volumetric one. 10,000 updates took 91 s, 2,000 still 23 s of the CI's two
  // cores (docs/reliability.md, "Build time in CI").
  expect_no_allocation("volumetric_thin_tet", body, sites, 0, StableStep::Bound, 400);
#else
  GTEST_SKIP() << "built without the fem layer (TetGen)";
#endif
}

}  // namespace
}  // namespace medspring
