// The SMRM vessel model kind (ALGORITHMS.md §5, §7.2) and checks §8.2-11/12, §8.3-13.
#include "medspring/models/smrm_vessel.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>

#include "../medial/medial_fixtures.hpp"
#include "medspring/core/error.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/static_solve.hpp"

namespace medspring {
namespace {

using testing::max_row_distance;

const VesselPath kPaths[] = {VesselPath::StraightX, VesselPath::StraightZ, VesselPath::Arc,
                             VesselPath::Helix};
const CrossSectionShape kShapes[] = {CrossSectionShape::Circular, CrossSectionShape::Elliptical,
                                     CrossSectionShape::NonPlanar};

// Static equilibrium of the vessel's chain under a force F on atom `atom`.
MatX3 loaded_atoms(const SmrmVessel& v, Index atom, const Vec3& F) {
  MatX3 f = MatX3::Zero(v.num_atoms(), 3);
  f.row(atom) = F.transpose();
  return static_equilibrium(v.model(), f).x;
}

std::string message_of(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "(no InvalidInput thrown)";
}

TEST(SmrmVessel, PhantomHasThePaperSizesAndDefaults) {  // §5.1, §9
  const SmrmVessel v = smrm_phantom(VesselPath::StraightX, CrossSectionShape::Circular);
  EXPECT_EQ(v.kind(), "smrm");
  EXPECT_EQ(v.num_surface_nodes(), 1200);
  EXPECT_EQ(v.faces().rows(), 2340);
  EXPECT_EQ(v.grid().rings, 40);
  EXPECT_EQ(v.grid().spokes, 30);
  EXPECT_EQ(v.model().num_nodes(), 40);
  EXPECT_EQ(v.model().num_springs(), 39);
  EXPECT_TRUE(v.model().fixed[0] && v.model().fixed[39]);
  EXPECT_EQ(v.local_stiffness(), 0.05);
  EXPECT_EQ(v.settings().frames.mode, FrameMode::RMF);
  EXPECT_EQ(v.settings().frames.anchor, FrameAnchor::TwoEnd);
  for (Index k = 0; k < 1200; ++k) EXPECT_NEAR(v.spoke_length(k), 3.0, 1e-12);
  EXPECT_TRUE(v.report().curvature.ok());
  EXPECT_TRUE(v.report().notes.empty());
}

TEST(SmrmVessel, ReconstructionIsExactAtRestForEveryCombination) {  // §8.3-13, 1e-12 mm
  for (VesselPath p : kPaths)
    for (CrossSectionShape s : kShapes) {
      SCOPED_TRACE(to_string(p) + " " + to_string(s));
      const SmrmVessel v = smrm_phantom(p, s);
      const MatX3 P0 = testing::structured_rest_nodes(v.frame_reference(), cross_section_offsets(s));
      EXPECT_LE(max_row_distance(v.rest_surface(), P0), 1e-12);
      auto ws = v.make_workspace();
      MatX3 S;
      v.map_to_surface(v.rest_atoms(), ws, S);
      EXPECT_LE(max_row_distance(S, P0), 1e-12);
    }
}

TEST(SmrmVessel, CenterlineBuilderGivesTheCircularPhantom) {  // eq. (4), D-11
  const SmrmVessel a = smrm_from_centerline(vessel_phantom_centerline(VesselPath::Helix));
  const SmrmVessel b = smrm_phantom(VesselPath::Helix, CrossSectionShape::Circular);
  EXPECT_LE(max_row_distance(a.rest_surface(), b.rest_surface()), 1e-9);
  EXPECT_EQ(a.grid().rings, 40);
  // Resampling: 7 input points with a repeated one -> 12 atoms at equal spacing, radii interpolated.
  Centerline line;
  line.name = "short";
  line.points.resize(7, 3);
  line.points << 0, 0, 0, 5, 0, 0, 5, 0, 0, 10, 0, 0, 15, 0, 0, 20, 0, 0, 22, 0, 0;
  line.radii.resize(7);
  line.radii << 2, 2, 2, 3, 3, 3, 4;
  const SmrmVessel c = smrm_from_centerline(line, {.atoms = 12, .spokes = 8});
  EXPECT_EQ(c.num_surface_nodes(), 96);
  EXPECT_EQ(c.report().removed_duplicates, 1);
  EXPECT_NEAR(c.rest_atoms()(11, 0), 22.0, 1e-12);
  EXPECT_NEAR(c.rest_atoms()(1, 0), 2.0, 1e-12);
  EXPECT_NEAR(c.atom_radius()[11], 4.0, 1e-12);
  EXPECT_NEAR(c.spoke_length(11 * 8 + 3), 4.0, 1e-12);
}

TEST(SmrmVessel, LongestCenterlineIsPicked) {  // VMTK files: several polylines sharing a trunk
  const std::vector<Centerline> lines{vessel_phantom_centerline(VesselPath::StraightX, 30),
                                      vessel_phantom_centerline(VesselPath::Arc, 35),
                                      vessel_phantom_centerline(VesselPath::StraightZ, 34)};
  EXPECT_EQ(&longest_centerline(lines), &lines[1]);  // 84.99 mm against 72.5 and 82.5 mm
  const std::vector<Centerline> tie{vessel_phantom_centerline(VesselPath::StraightZ, 20),
                                    vessel_phantom_centerline(VesselPath::StraightX, 20)};
  EXPECT_EQ(&longest_centerline(tie), &tie[0]);
  EXPECT_THROW(longest_centerline({}), InvalidInput);
}

TEST(SmrmVessel, StraightZWithForceAlongXMatchesStraightXWithForceAlongY) {  // §8.2-11, 1e-9
  for (bool nonlinear : {false, true}) {
    SmrmSettings st;
    st.chain.nonlinear = nonlinear;
    const SmrmVessel vx = smrm_phantom(VesselPath::StraightX, CrossSectionShape::NonPlanar, st);
    const SmrmVessel vz = smrm_phantom(VesselPath::StraightZ, CrossSectionShape::NonPlanar, st);
    const MatX3 Cx = loaded_atoms(vx, 20, Vec3(0, 0.5, 0));
    const MatX3 Cz = loaded_atoms(vz, 20, Vec3(0.5, 0, 0));
    for (Index i = 0; i < 40; ++i)
      EXPECT_NEAR((Cx.row(i) - vx.rest_atoms().row(i)).norm(), (Cz.row(i) - vz.rest_atoms().row(i)).norm(),
                  1e-9);
    // Congruent surfaces: the rotation (x, y, z) -> (y, z, x) maps straight-x onto straight-z (rest
    // frames included) and the force along y onto the force along x.
    Mat3 R;
    R << 0, 1, 0, 0, 0, 1, 1, 0, 0;
    auto wx = vx.make_workspace();
    auto wz = vz.make_workspace();
    MatX3 Sx, Sz;
    vx.map_to_surface(Cx, wx, Sx);
    vz.map_to_surface(Cz, wz, Sz);
    EXPECT_LE(max_row_distance(testing::rigid(Sx, R, Vec3::Zero()), Sz), 1e-9);
    EXPECT_GT(max_row_distance(Sz, vz.rest_surface()), 1.0);  // it did deform
  }
}

TEST(SmrmVessel, RingsStayPerpendicularToTheDeformedTangent) {  // §5.7
  for (VesselPath p : kPaths) {
    SCOPED_TRACE(to_string(p));
    const SmrmVessel v = smrm_phantom(p, CrossSectionShape::Circular);
    const Vec3 F = 0.5 * v.frame_reference().F0.v.row(20).transpose();
    const MatX3 C = loaded_atoms(v, 20, F);
    auto ws = v.make_workspace();
    MatX3 S;
    v.map_to_surface(C, ws, S);
    for (Index k = 0; k < 1200; ++k) {
      const Index i = k / 30;
      EXPECT_NEAR((S.row(k) - C.row(i)).dot(ws.frames.t.row(i)), 0.0, 1e-12);
      EXPECT_NEAR((S.row(k) - C.row(i)).norm(), 3.0, 1e-12);
    }
  }
}

// The paper-literal chain (no bending, k_b = 0): the kinks and the light/strong contrast of §5.2.
SmrmSettings paper_chain() {
  SmrmSettings s;
  s.bending = BendingMode::Constant;
  s.chain.kb = 0.0;
  return s;
}

TEST(SmrmVessel, StraightZDoesNotFlipInRmfModeAndIsDegenerateInPaperXoy) {  // §8.2-11
  const SmrmVessel v = smrm_phantom(VesselPath::StraightZ, CrossSectionShape::Elliptical, paper_chain());
  const MatX3 C = loaded_atoms(v, 20, Vec3(0.5, 0, 0));
  auto ws = v.make_workspace();
  MatX3 S;
  const FrameReport r = v.map_to_surface(C, ws, S);
  EXPECT_TRUE(r.ok());
  // The bend is planar (xz): each ring turns exactly with its tangent (u_{i+1} = MinRot(t_i -> t_{i+1}) u_i),
  // without twist and without a flip, even at the sharp kink under the loaded atom.
  for (Index i = 0; i + 1 < 40; ++i) {
    const Vec3 t0 = ws.frames.t.row(i).transpose(), t1 = ws.frames.t.row(i + 1).transpose();
    const Vec3 u0 = ws.frames.u.row(i).transpose(), u1 = ws.frames.u.row(i + 1).transpose();
    EXPECT_LE((min_rotation(t0, t1, u0, u0) - u1).norm(), 1e-9) << "atom " << i;
    EXPECT_GT(u0.dot(u1), 0.5) << "atom " << i;
  }
  EXPECT_LT(ws.frames.t.row(19).dot(ws.frames.t.row(20)), 0.7);  // the kink is sharp (about 51 degrees)

  SmrmSettings paper;
  paper.frames.mode = FrameMode::PaperXOY;
  const SmrmVessel vp = smrm_phantom(VesselPath::StraightZ, CrossSectionShape::Elliptical, paper);
  EXPECT_EQ(vp.report().rest_frames.degenerate, 40);
  ASSERT_FALSE(vp.report().notes.empty());
  EXPECT_NE(vp.report().notes[0].find("degenerate"), std::string::npos);
  auto wp = vp.make_workspace();
  EXPECT_EQ(vp.map_to_surface(vp.rest_atoms(), wp, S).degenerate, 40);
}

TEST(SmrmVessel, NonlinearChainIsStifferThanLinearUnderTheStrongForce) {  // §7.2, eq. (5), k_b = 0
  SmrmSettings lin = paper_chain();
  lin.chain.nonlinear = false;
  const SmrmVessel vn = smrm_phantom(VesselPath::StraightX, CrossSectionShape::Circular, paper_chain());
  const SmrmVessel vl = smrm_phantom(VesselPath::StraightX, CrossSectionShape::Circular, lin);
  const double strong_n = loaded_atoms(vn, 20, Vec3(0, 0.5, 0))(20, 1);
  const double strong_l = loaded_atoms(vl, 20, Vec3(0, 0.5, 0))(20, 1);
  const double light_n = loaded_atoms(vn, 20, Vec3(0, 0.05, 0))(20, 1);
  const double light_l = loaded_atoms(vl, 20, Vec3(0, 0.05, 0))(20, 1);
  EXPECT_LT(strong_n, strong_l - 0.01);
  EXPECT_GT(strong_n, 0.8 * strong_l);
  EXPECT_NEAR(light_n, light_l, 1e-3 * light_l);  // the cubic term is invisible at the light force
}

TEST(SmrmVessel, ExperimentHoldsTheStaticDeflectionAndReturnsToRest) {  // §7.2, §8.2-12, k_b = 0
  const SmrmVessel v = smrm_phantom(VesselPath::StraightX, CrossSectionShape::Circular, paper_chain());
  const VesselExperimentResult r = run_vessel_experiment(v);
  EXPECT_EQ(r.atom, 20);
  EXPECT_LE((r.direction - Vec3(0, 1, 0)).norm(), 1e-15);  // u_20^0 of straight-x
  EXPECT_EQ(r.contact_node, 20 * 30 + 15);                 // spoke at theta = pi faces -y
  EXPECT_EQ(v.node_atom(r.contact_node), 20);
  SmrmSettings lin = paper_chain();
  lin.chain.nonlinear = false;
  const SmrmVessel vl = smrm_phantom(VesselPath::StraightX, CrossSectionShape::Circular, lin);
  struct Case {
    const VesselRun* run;
    const SmrmVessel* model;
  };
  for (const Case& c : {Case{&r.light_linear, &vl}, Case{&r.light_nonlinear, &v}, Case{&r.strong_linear, &vl},
                        Case{&r.strong_nonlinear, &v}}) {
    const VesselRun& run = *c.run;
    SCOPED_TRACE(::testing::Message() << run.force << " N, nonlinear " << run.nonlinear);
    const MatX3 Cs = loaded_atoms(*c.model, 20, run.force * r.direction);
    EXPECT_NEAR(run.atom_hold, (Cs.row(20) - v.rest_atoms().row(20)).norm(), 1e-6);  // dynamics settled
    EXPECT_NEAR(run.contact_hold, run.atom_hold, 1e-3);  // the ring translates with its atom
    EXPECT_LT(run.return_time, 200.0);                   // §8.2-12
    EXPECT_LE(run.max_surface_displacement[run.max_surface_displacement.size() - 1], 1e-3);
    EXPECT_EQ(run.warnings, 0u);
    Index peak = 0;
    run.profile.rowwise().norm().maxCoeff(&peak);
    EXPECT_EQ(peak, 20);
  }
  EXPECT_LT(r.strong_nonlinear.atom_hold, r.strong_linear.atom_hold);
  // §5.2: a light force makes a local kink, a strong one spreads along the chain.
  for (const VesselRun* light : {&r.light_linear, &r.light_nonlinear})
    for (const VesselRun* strong : {&r.strong_linear, &r.strong_nonlinear})
      EXPECT_GT(strong->profile.row(19).norm() / strong->atom_hold,
                2.0 * light->profile.row(19).norm() / light->atom_hold);
}

TEST(SmrmVessel, TransferForceFollowsD14) {
  const SmrmVessel v = smrm_phantom(VesselPath::Arc, CrossSectionShape::Elliptical);
  MatX3 f = MatX3::Zero(40, 3);
  v.transfer_force(20 * 30 + 7, Vec3(1, 2, 3), f);
  EXPECT_EQ(f.row(20), Eigen::RowVector3d(1, 2, 3));
  EXPECT_EQ(f.cwiseAbs().sum(), 6.0);
  v.transfer_force(5, Vec3(1, 0, 0), f);  // ring 0: atom 0 is fixed, no global response
  v.transfer_force(39 * 30 + 2, Vec3(1, 0, 0), f);
  EXPECT_EQ(f.cwiseAbs().sum(), 6.0);
}

TEST(SmrmVessel, ReactionForceIsMinusTheLoadAtEquilibrium) {
  const SmrmVessel v = smrm_phantom(VesselPath::Helix, CrossSectionShape::Circular);
  const Index node = v.contact_node(20, Vec3(0, 0, -1));
  MatX3 f = MatX3::Zero(40, 3);
  const Vec3 F(0.1, -0.2, -0.4);
  v.transfer_force(node, F, f);
  State s = make_state(v.model());
  s.x = static_equilibrium(v.model(), f).x;
  EXPECT_LE((v.reaction_force(s, node) + F).norm(), 1e-9);
  EXPECT_LE(v.reaction_force(make_state(v.model()), node).norm(), 1e-15);  // none at rest
}

TEST(SmrmVessel, BodyMapEqualsTheExplicitAllocationFreeForm) {
  const SmrmVessel v = smrm_phantom(VesselPath::Helix, CrossSectionShape::NonPlanar);
  State s = make_state(v.model());
  s.f_ext.row(20) << 0.3, -0.2, 0.1;
  for (int k = 0; k < 100; ++k) step(v.model(), s, {.dt = 0.5});
  MatX3 A, B;
  v.map_to_surface(s, A);
  auto ws = v.make_workspace();
  B.resize(1200, 3);
  const double* before = B.data();
  v.map_to_surface(s.x, ws, B);
  EXPECT_EQ(B.data(), before);  // no reallocation
  EXPECT_EQ(A, B);
  MatX3 N, Ref;
  v.surface_normals(B, ws, N);
  vertex_normals(B, v.faces(), Ref);
  EXPECT_LE((N - Ref).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(SmrmVessel, GenericVesselFromAClosedTubeMeshIsExactAtRest) {  // §5.9, 1e-9 mm
  for (VesselPath p : kPaths) {
    SCOPED_TRACE(to_string(p));
    const Centerline line = vessel_phantom_centerline(p);
    const FrameReference ref = make_frame_reference(line.points);
    const SurfaceMesh mesh = testing::closed_tube_around(ref, 3, 20, 3.0, 1.8, 0.3);
    const SmrmVessel v = smrm_from_surface(mesh, line);
    EXPECT_FALSE(v.grid().valid());
    EXPECT_TRUE(v.binding().generic());
    EXPECT_EQ(v.num_surface_nodes(), mesh.num_vertices());
    EXPECT_LT(v.report().max_distance_ratio, 1.1);
    auto ws = v.make_workspace();
    MatX3 S;
    v.map_to_surface(v.rest_atoms(), ws, S);
    EXPECT_LE(max_row_distance(S, mesh.V), 1e-9);
    // D-14 bracket split, and a deformation moves the surface.
    const Index k = 4 * 20 + 3;  // ring 4 of the mesh: between atoms 1 and 2
    const double lam = v.binding().lambda[static_cast<std::size_t>(k)];
    const Index i = v.binding().atom[static_cast<std::size_t>(k)];
    ASSERT_GT(lam, 0.0);
    ASSERT_LT(lam, 1.0);
    MatX3 f = MatX3::Zero(40, 3);
    v.transfer_force(k, Vec3(0, 0, 1), f);
    EXPECT_NEAR(f(i, 2), 1.0 - lam, 1e-15);
    EXPECT_NEAR(f(i + 1, 2), lam, 1e-15);
    const MatX3 C = loaded_atoms(v, 20, 0.5 * v.frame_reference().F0.u.row(20).transpose());
    v.map_to_surface(C, ws, S);
    EXPECT_GT(max_row_distance(S, mesh.V), 1.0);
  }
}

TEST(SmrmVessel, GenericBindingRejectsAFarNodeNamingIt) {  // §5.9: > 3 x local radius
  const Centerline line = vessel_phantom_centerline(VesselPath::StraightX);
  SurfaceMesh mesh = testing::closed_tube_around(make_frame_reference(line.points), 2, 12, 3.0, 3.0);
  mesh.V(17, 1) += 20.0;
  const std::string msg = message_of([&] { smrm_from_surface(mesh, line); });
  EXPECT_NE(msg.find("node 17 "), std::string::npos) << msg;
  EXPECT_NE(msg.find("3 x the local radius"), std::string::npos) << msg;
}

TEST(SmrmVessel, MarchedSpokesFindTheBoundaryAndReportMisses) {  // §5.6, mesh input
  const Centerline inner = vessel_phantom_centerline(VesselPath::StraightX, 40, 2.0);
  const SurfaceMesh boundary =
      testing::closed_tube_around(make_frame_reference(inner.points), 4, 90, 3.0, 1.8);
  const SmrmVessel v = smrm_from_marched_spokes(inner, boundary);
  EXPECT_EQ(v.report().spokes_without_hit, 0);
  const double pi = std::numbers::pi;
  double worst = 0;
  for (Index k = 0; k < 1200; ++k) {
    const double th = 2 * pi * static_cast<double>(k % 30) / 30.0;
    const double rho = 1.0 / std::sqrt(std::pow(std::cos(th) / 3.0, 2) + std::pow(std::sin(th) / 1.8, 2));
    worst = std::max(worst, std::abs(v.spoke_length(k) - rho));
  }
  EXPECT_LT(worst, 5e-3);  // chordal error of the 90-gon

  // A centerline running past the end of the boundary: the atoms outside get rho = r_i, reported.
  const Centerline longer = vessel_phantom_centerline(VesselPath::StraightX, 50, 2.0);
  const SmrmVessel w = smrm_from_marched_spokes(longer, boundary);
  EXPECT_EQ(w.report().spokes_without_hit, 8 * 30);  // atoms 32..39 lie beyond x = 97.5
  EXPECT_EQ(w.report().first_spoke_without_hit, 32 * 30);
  EXPECT_NEAR(w.spoke_length(35 * 30 + 4), 2.0, 1e-12);
  ASSERT_FALSE(w.report().notes.empty());
}

TEST(SmrmVessel, BadInputNamesTheElementAtFault) {
  const Centerline ok = vessel_phantom_centerline(VesselPath::Arc);
  EXPECT_NE(message_of([&] { smrm_from_centerline(ok, {.atoms = 2}); }).find("atoms must be >= 3"),
            std::string::npos);
  Centerline bad_radius = ok;
  bad_radius.radii[3] = 0.0;
  EXPECT_NE(message_of([&] { smrm_from_centerline(bad_radius); }).find("centerline 'arc': point 3: radius"),
            std::string::npos);
  bad_radius.radii[3] = -1.0;
  EXPECT_THROW(smrm_from_centerline(bad_radius), InvalidInput);
  Centerline repeated;
  repeated.name = "stub";
  repeated.points.resize(5, 3);
  repeated.points << 0, 0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0;
  repeated.radii = VecX::Constant(5, 1.0);
  const std::string rep = message_of([&] { smrm_from_centerline(repeated); });
  EXPECT_NE(rep.find("centerline 'stub': fewer than 3 distinct points"), std::string::npos) << rep;
  EXPECT_THROW(smrm_from_offsets(MatX3::Zero(2, 3), cross_section_offsets(CrossSectionShape::Circular)),
               InvalidInput);
  MatX3 O = cross_section_offsets(CrossSectionShape::Circular);
  O.row(4).setZero();
  const std::string spoke =
      message_of([&] { smrm_from_offsets(vessel_phantom_atoms(VesselPath::Helix), O); });
  EXPECT_NE(spoke.find("atom 0 spoke 4"), std::string::npos) << spoke;
  MatX3 repeated_atoms = vessel_phantom_atoms(VesselPath::Helix);
  repeated_atoms.row(8) = repeated_atoms.row(7);
  EXPECT_NE(message_of([&] {
              smrm_from_offsets(repeated_atoms, cross_section_offsets(CrossSectionShape::Circular));
            }).find("atoms 7 and 8 coincide"),
            std::string::npos);
  SurfaceMesh open = testing::closed_tube_around(make_frame_reference(ok.points), 1, 12, 3.0, 3.0);
  open.F.conservativeResize(open.F.rows() - 1, 3);  // drop one cap triangle
  EXPECT_THROW(smrm_from_surface(open, ok), InvalidInput);
  EXPECT_THROW(
      run_vessel_experiment(smrm_phantom(VesselPath::Arc, CrossSectionShape::Circular), {.atom = 39}),
      InvalidInput);  // a fixed atom has no global response
}

}  // namespace
}  // namespace medspring
