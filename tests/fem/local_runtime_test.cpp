// The run-time local overlay of the volumetric kind (issue 23, docs/local-deformation.md "The volumetric
// kind: the calibrated disk overlay"): on the real kidney (the 458-node balloon surface of
// kidney_left_hubmap_vhm.obj, meshed inside at about 700 nodes, held on its lowest 20 %), a disk load given
// to the Simulation as surface forces gets the calibration's overlay (fem::disk_local_overlay) at the body's
// overlay_compliance a; a = 0 is the run without overlay; a single loaded node is today's single-node solve;
// a model package keeps a.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "medspring/builders/kidney_build.hpp"
#include "medspring/core/binary.hpp"
#include "medspring/core/params.hpp"
#include "medspring/fem/local_site.hpp"
#include "medspring/fem/matching.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/local/distributed.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/sim/simulation.hpp"
#include "test_support.hpp"

using namespace medspring;

namespace {

constexpr double kA = 0.183;  // the overlay compliance fitted on the real kidney (nu 0.45, disk-mean fit)

const VolumetricMesh& kidney_mesh() {
  static const VolumetricMesh vm = [] {
    const KidneyBuild k = build_kidney_model(
        {.source = {.mesh = medspring::testing::require_data_file("kidney_left_hubmap_vhm.obj"),
                    .unit = LengthUnit::Metre}});
    return fem::volumetric_mesh({k.model->rest_surface(), k.model->faces()}, {.target_nodes = 700});
  }();
  return vm;
}

std::shared_ptr<const VolumetricBody> kidney(
    double a = VolumetricSettings{}.overlay_compliance,
    VolumePrecision precision = VolumetricSettings{}.volume_precision) {
  const VolumetricMesh& vm = kidney_mesh();
  const MatX3 S = vm.X.topRows(vm.surface_nodes);
  const double zmin = S.col(2).minCoeff(), zmax = S.col(2).maxCoeff();
  VolumetricSettings st;
  st.fixed = fem::support_nodes(S, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
  st.overlay_compliance = a;
  st.volume_precision = precision;
  return std::make_shared<VolumetricBody>(vm, st, "real kidney");
}

// A 0.5 N disk load of radius 8 mm along the inward normal at the highest surface node.
fem::ContactLoad top_load(const Body& b) {
  Index top = 0;
  b.rest_surface().col(2).maxCoeff(&top);
  MatX3 N;
  vertex_normals(b.rest_surface(), b.faces(), N);
  return {b.rest_surface().row(top).transpose(), -0.5 * N.row(top).transpose(), 8.0};
}

// The load's consistent nodal forces as the Simulation's surface forces.
SurfaceForces surface_forces_of(const Body& b, const fem::ContactLoad& load) {
  SurfaceForces sf;
  sf.force = fem::disk_load_linear(b.rest_surface(), b.faces(), load.centre, load.radius, load.force);
  for (Index i = 0; i < sf.force.rows(); ++i)
    if (sf.force.row(i).squaredNorm() > 0) {
      sf.nodes.push_back(i);
      sf.total += sf.force.row(i).transpose();
      if (sf.centre < 0 || sf.force.row(i).squaredNorm() > sf.force.row(sf.centre).squaredNorm())
        sf.centre = i;
    }
  return sf;
}

SimulationSettings with_local(bool on) {
  SimulationSettings s;
  s.local.enabled = on;
  return s;
}

}  // namespace

// The displayed surface minus the global one after an update under the disk load equals a x the calibration's
// overlay at k_ref = local_stiffness() (fem::disk_local_overlay, the same patch and nodal forces) to 1e-9 mm;
// the overlay is not trivial (> 1e-3 mm) and spans the loaded nodes plus their ring.
TEST(LocalRuntime, DiskLoadOverlayOnTheRealKidneyEqualsTheCalibrationsOverlay) {
  const auto body = kidney(kA);
  const fem::ContactLoad load = top_load(*body);
  const SurfaceForces sf = surface_forces_of(*body, load);
  ASSERT_GE(sf.nodes.size(), 5u);
  Simulation sim(body, with_local(true));
  sim.set_surface_forces(&sf);
  sim.update();
  const MatX3 overlay = sim.surface() - sim.global_surface();
  const MatX3 expected = kA * fem::disk_local_overlay(*body, load, body->local_stiffness());
  EXPECT_GT(expected.cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_LT((overlay - expected).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT(sim.local_nodes().size(), sf.nodes.size());
  EXPECT_EQ(sim.local_displacement().rows(), static_cast<Index>(sim.local_nodes().size()));
  sim.update();  // the same loaded set: the factor reused, the same overlay
  EXPECT_LT(((sim.surface() - sim.global_surface()) - expected).cwiseAbs().maxCoeff(), 1e-9);
}

// a = 0 with the overlay on is the run with it off, bit for bit, over 40 updates (a does not touch the
// model: same fingerprint); no patch is reported. a = 0 is the default: a body built with the default
// settings is that run (the uncalibrated overlay, a = 1, left the load site far too soft).
TEST(LocalRuntime, ZeroComplianceIsTheRunWithoutOverlayAndTheDefault) {
  EXPECT_EQ(VolumetricSettings{}.overlay_compliance, 0.0);
  const auto off = kidney(), calibrated = kidney(kA);
  EXPECT_EQ(off->local_compliance(), 0.0);
  EXPECT_EQ(model_fingerprint(off->model()), model_fingerprint(calibrated->model()));
  const SurfaceForces sf = surface_forces_of(*off, top_load(*off));
  Simulation a0(off, with_local(true)), plain(calibrated, with_local(false));
  a0.set_surface_forces(&sf);
  plain.set_surface_forces(&sf);
  for (int i = 0; i < 40; ++i) {
    a0.update();
    plain.update();
  }
  EXPECT_TRUE(a0.surface() == plain.surface());
  EXPECT_TRUE(a0.local_nodes().empty());
  EXPECT_GT((a0.surface() - off->rest_surface()).cwiseAbs().maxCoeff(), 1e-3);  // the load did move it
}

// A single loaded node is today's single-node solve: the Simulation gives surface forces on one node exactly
// the surface of set_tool_force with the same force (20 updates, bit for bit, the same 25-node patch), and on
// that patch solve_local_distributed with the force on the contact alone equals the single-node solver's U
// (1e-12 relative).
TEST(LocalRuntime, OneLoadedNodeIsTheSingleNodeSolve) {
  const auto body = kidney(kA);
  const SurfaceForces disk = surface_forces_of(*body, top_load(*body));
  const Index c = disk.centre;
  const Vec3 F = disk.total;
  SurfaceForces one;
  one.force = MatX3::Zero(body->num_surface_nodes(), 3);
  one.force.row(c) = F.transpose();
  one.nodes = {c};
  one.total = F;
  one.centre = c;
  Simulation by_forces(body, with_local(true)), by_tool(body, with_local(true));
  by_forces.set_surface_forces(&one);
  by_tool.set_tool_force(c, F);
  for (int i = 0; i < 20; ++i) {
    by_forces.update();
    by_tool.update();
  }
  EXPECT_TRUE(by_forces.surface() == by_tool.surface());
  ASSERT_EQ(by_forces.local_nodes(), by_tool.local_nodes());
  EXPECT_EQ(by_tool.local_nodes().size(), 25u);

  LocalDeformationSettings ls;
  ls.patch.k_loc = body->local_stiffness() / kA;
  LocalDeformer d =
      LocalDeformer::mesh(vertex_adjacency(body->num_surface_nodes(), unique_edges(body->faces())),
                          body->rest_surface(), ls, body->fixed_surface_nodes());
  MatX3 U, Ud;
  d.compute(c, F, U);
  MatX3 Fp = MatX3::Zero(d.patch().size(), 3);
  Fp.row(d.patch().contact_local) = F.transpose();
  solve_local_distributed(d.patch(), Fp, Ud);
  EXPECT_LT((Ud - U).cwiseAbs().maxCoeff(), 1e-12 * U.cwiseAbs().maxCoeff());
  EXPECT_LT((MatX3(by_tool.local_displacement()) - U).cwiseAbs().maxCoeff(), 1e-15);
}

// A model package keeps a (version 9) and rebuilds the same body; a version-8 package (no a) reads as a = 1,
// the overlay as before. Negative or non-finite a is refused by the body and by the declaration, naming it.
TEST(LocalRuntime, PackageKeepsTheComplianceAndBadValuesAreRefused) {
  const auto body = kidney(kA);
  const std::string bytes = encode_model_package(package_of(*body, "kidney"));
  const ModelPackage p = decode_model_package(bytes, "kidney.msm");
  EXPECT_EQ(p.volumetric.overlay_compliance, kA);
  EXPECT_EQ(make_body(p)->local_compliance(), kA);
  // version 8: a double-precision body's payload (the precision every version <= 9 package ran with) without
  // a and the precision (version 9's f64 and version 10's i64, before the trailing fingerprint)
  const auto body8 = kidney(kA, VolumePrecision::Double);
  std::string payload = encode_model_package(package_of(*body8, "kidney")).substr(kFrameHeaderSize);
  payload.erase(payload.size() - 24, 16);
  const ModelPackage v8 =
      decode_model_package(frame_payload(kModelPackageMagic, 8, payload), "kidney_v8.msm");
  EXPECT_EQ(v8.volumetric.overlay_compliance, 1.0);
  EXPECT_EQ(v8.volumetric.spring_scale, body->settings().spring_scale);
  EXPECT_EQ(v8.volumetric.volume_precision, VolumePrecision::Double);
  EXPECT_TRUE(check_fingerprint(v8, *make_body(v8)));

  for (double bad : {-0.1, std::nan(""), -std::numeric_limits<double>::infinity()}) {
    try {
      kidney(bad);
      ADD_FAILURE() << "overlay_compliance " << bad << " not refused";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("real kidney: overlay_compliance must be >= 0"), std::string::npos)
          << e.what();
    }
  }
  VolumetricSettings s;
  try {
    set_param(s, "overlay_compliance", "-1");
    ADD_FAILURE() << "overlay_compliance -1 not refused by the declaration";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("overlay_compliance"), std::string::npos) << e.what();
  }
  set_param(s, "overlay_compliance", "0.25");
  EXPECT_EQ(s.overlay_compliance, 0.25);
}
