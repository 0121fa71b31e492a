// ALGORITHMS.md §5.6-5.9 and §8.3 checks 13-14: rest binding, exact reconstruction, rigid motion,
// generic binding of an unstructured mesh, normals, validity check.
#include "medspring/medial/reconstruction.hpp"

#include <gtest/gtest.h>

#include "medial_fixtures.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/medial/vessel_phantoms.hpp"

namespace medspring {
namespace {

using testing::max_row_distance;
using testing::rigid;
using testing::rotation;
using testing::structured_rest_nodes;

const VesselPath kPaths[] = {VesselPath::StraightX, VesselPath::StraightZ, VesselPath::Arc,
                             VesselPath::Helix};
const CrossSectionShape kShapes[] = {CrossSectionShape::Circular, CrossSectionShape::Elliptical,
                                     CrossSectionShape::NonPlanar};

std::vector<Index> ring_atoms(Index n, Index M) {
  std::vector<Index> a(static_cast<std::size_t>(n * M));
  for (Index k = 0; k < n * M; ++k) a[static_cast<std::size_t>(k)] = k / M;
  return a;
}

// Binds P0 to the rest chain of ref, moves the atoms to C, and returns the reconstruction.
MatX3 rebuild(const FrameReference& ref, const SurfaceBinding& b, const MatX3& C) {
  FrameField F(ref.size());
  compute_frames(C, ref, F);
  ReconstructionScratch s(ref.size(), 0);
  MatX3 S;
  reconstruct(b, C, F, s, S);
  return S;
}

TEST(Reconstruction, ExactAtRestForEveryPhantomCombination) {  // §8.3-13, 1e-12 mm
  for (FrameMode mode : {FrameMode::RMF, FrameMode::PaperXOY})
    for (VesselPath p : kPaths)
      for (CrossSectionShape s : kShapes) {
        SCOPED_TRACE(to_string(mode) + " " + to_string(p) + " " + to_string(s));
        const FrameReference ref = make_frame_reference(vessel_phantom_atoms(p), {.mode = mode});
        const MatX3 O = cross_section_offsets(s);
        const MatX3 P0 = structured_rest_nodes(ref, O);
        const SurfaceBinding b = bind_to_atoms(P0, ring_atoms(40, 30), ref);
        EXPECT_FALSE(b.atom_begin.empty());  // sorted by atom: the grouped fast path is used
        EXPECT_LE(max_row_distance(rebuild(ref, b, ref.C0), P0), 1e-12);
        // D-13: the stored offsets are the cross-section offsets.
        for (Index k = 0; k < 1200; ++k) EXPECT_LE((b.offset.row(k) - O.row(k % 30)).norm(), 1e-12);
      }
}

TEST(Reconstruction, NodesOutsideTheNormalPlaneAreExactAtRest) {  // D-13: any offset, not only eq. (4)
  const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::Helix));
  MatX3 P0 = structured_rest_nodes(ref, cross_section_offsets(CrossSectionShape::NonPlanar));
  for (Index k = 0; k < P0.rows(); ++k) P0(k, 2) += 0.5 * std::sin(0.37 * k);  // arbitrary axial shifts
  const SurfaceBinding b = bind_to_atoms(P0, ring_atoms(40, 30), ref);
  EXPECT_LE(max_row_distance(rebuild(ref, b, ref.C0), P0), 1e-12);
}

TEST(Reconstruction, TranslationIsExact) {  // §8.3-14, 1e-12
  const Vec3 shift(12.5, -3.25, 40.0);
  for (VesselPath p : kPaths)
    for (FrameAnchor a : {FrameAnchor::OneEnd, FrameAnchor::TwoEnd}) {
      SCOPED_TRACE(to_string(p) + " " + to_string(a));
      const FrameReference ref = make_frame_reference(vessel_phantom_atoms(p), {FrameMode::RMF, a});
      const MatX3 P0 = structured_rest_nodes(ref, cross_section_offsets(CrossSectionShape::NonPlanar));
      const SurfaceBinding b = bind_to_atoms(P0, ring_atoms(40, 30), ref);
      const MatX3 S = rebuild(ref, b, rigid(ref.C0, Mat3::Identity(), shift));
      EXPECT_LE(max_row_distance(S, rigid(P0, Mat3::Identity(), shift)), 1e-12);
    }
}

TEST(Reconstruction, RotationPerpendicularToTheFirstTangentIsExactWithOneEnd) {  // §8.3-14, 1e-12
  for (VesselPath p : kPaths) {
    SCOPED_TRACE(to_string(p));
    const FrameReference ref =
        make_frame_reference(vessel_phantom_atoms(p), {FrameMode::RMF, FrameAnchor::OneEnd});
    const MatX3 P0 = structured_rest_nodes(ref, cross_section_offsets(CrossSectionShape::Elliptical));
    const SurfaceBinding b = bind_to_atoms(P0, ring_atoms(40, 30), ref);
    for (double angle : {0.4, 1.7, -2.9}) {
      const Vec3 axis =
          std::cos(angle) * ref.F0.u.row(0).transpose() + std::sin(angle) * ref.F0.v.row(0).transpose();
      const Mat3 R = rotation(axis, angle);
      const Vec3 shift(-4, 9, 1);
      EXPECT_LE(max_row_distance(rebuild(ref, b, rigid(ref.C0, R, shift)), rigid(P0, R, shift)), 1e-12)
          << "angle " << angle;
    }
  }
}

TEST(Reconstruction, BestFitOnTheHelixMakesAnyRotationExact) {  // §8.3-14 (prototype 1.5e-14)
  const FrameReference ref =
      make_frame_reference(vessel_phantom_atoms(VesselPath::Helix), {FrameMode::RMF, FrameAnchor::BestFit});
  const MatX3 P0 = structured_rest_nodes(ref, cross_section_offsets(CrossSectionShape::NonPlanar));
  const SurfaceBinding b = bind_to_atoms(P0, ring_atoms(40, 30), ref);
  for (const Vec3& axis : {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0.3, -0.5, 0.8), Vec3(-1, 2, 0.1)}) {
    const Mat3 R = rotation(axis, 2.3);
    const Vec3 shift(7, -2, 3);
    EXPECT_LE(max_row_distance(rebuild(ref, b, rigid(ref.C0, R, shift)), rigid(P0, R, shift)), 1e-12);
  }
  // OneEnd cannot see a rotation about t_0^0: it is not exact there (documents why BestFit exists).
  const FrameReference one =
      make_frame_reference(vessel_phantom_atoms(VesselPath::Helix), {FrameMode::RMF, FrameAnchor::OneEnd});
  const SurfaceBinding b1 = bind_to_atoms(P0, ring_atoms(40, 30), one);
  const Mat3 R = rotation(one.F0.t.row(0).transpose(), 0.5);
  EXPECT_GT(max_row_distance(rebuild(one, b1, rigid(one.C0, R, Vec3::Zero())), rigid(P0, R, Vec3::Zero())),
            0.1);
}

TEST(Reconstruction, CircularRingsStayPerpendicularToTheDeformedTangent) {  // §5.7: o_t = 0 stays in plane
  const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::Arc));
  const SurfaceBinding b =
      bind_to_atoms(structured_rest_nodes(ref, cross_section_offsets(CrossSectionShape::Circular)),
                    ring_atoms(40, 30), ref);
  MatX3 C = ref.C0;
  for (Index i = 1; i < 39; ++i) C(i, 2) += 5.0 * std::sin(std::numbers::pi * i / 39.0);
  FrameField F(40);
  compute_frames(C, ref, F);
  ReconstructionScratch s(40, 0);
  MatX3 S;
  reconstruct(b, C, F, s, S);
  for (Index k = 0; k < 1200; ++k) {
    const Index i = k / 30;
    EXPECT_NEAR((S.row(k) - C.row(i)).dot(F.t.row(i)), 0.0, 1e-12);
    EXPECT_NEAR((S.row(k) - C.row(i)).norm(), 3.0, 1e-12);  // shape and size never change
  }
}

TEST(Reconstruction, ClosestPointOnPolylineClampsAndNamesTheBracket) {  // §5.9
  MatX3 C(3, 3);
  C << 0, 0, 0, 2, 0, 0, 2, 2, 0;
  PolylinePoint q = closest_point_on_polyline(C, Vec3(0.5, 1, 0));
  EXPECT_EQ(q.segment, 0);
  EXPECT_DOUBLE_EQ(q.lambda, 0.25);
  EXPECT_DOUBLE_EQ(q.distance, 1.0);
  q = closest_point_on_polyline(C, Vec3(-1, 0, 0));  // before the start: clamped
  EXPECT_EQ(q.segment, 0);
  EXPECT_EQ(q.lambda, 0.0);
  q = closest_point_on_polyline(C, Vec3(3, -1, 0));  // at the interior atom: reported as (1, 0)
  EXPECT_EQ(q.segment, 1);
  EXPECT_EQ(q.lambda, 0.0);
  q = closest_point_on_polyline(C, Vec3(2, 5, 0));  // past the end: (1, 1)
  EXPECT_EQ(q.segment, 1);
  EXPECT_EQ(q.lambda, 1.0);
}

TEST(Reconstruction, InterpolatedFrameIsTheGeodesicBetweenNeighbours) {  // §5.9 slerp
  const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::Helix));
  EXPECT_EQ(interpolated_frame(ref.F0, 5, 0.0), ref.F0.frame(5));
  EXPECT_EQ(interpolated_frame(ref.F0, 5, 1.0), ref.F0.frame(6));
  const Mat3 H = interpolated_frame(ref.F0, 5, 0.5);
  EXPECT_LE((H.transpose() * H - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-14);
  const Eigen::AngleAxisd whole(ref.F0.frame(5).transpose() * ref.F0.frame(6));
  const Eigen::AngleAxisd half(ref.F0.frame(5).transpose() * H);
  EXPECT_NEAR(half.angle(), 0.5 * whole.angle(), 1e-14);
}

TEST(Reconstruction, GenericBindingIsExactAtRestOnANonCircularTubeMesh) {  // §5.9, 1e-9 mm
  for (VesselPath p : kPaths) {
    SCOPED_TRACE(to_string(p));
    const FrameReference ref = make_frame_reference(vessel_phantom_atoms(p));
    const SurfaceMesh mesh = testing::closed_tube_around(ref, 3, 24, 3.0, 1.8, 0.3);
    VecX dist;
    const SurfaceBinding b = bind_to_polyline(mesh.V, ref, &dist);
    EXPECT_TRUE(b.generic());
    EXPECT_LE(dist.maxCoeff(), 3.0 + 0.3 + 1e-9);
    ReconstructionScratch s(ref.size(), 0);
    EXPECT_LE(max_row_distance(rebuild(ref, b, ref.C0), mesh.V), 1e-9);
    // And rigidly moved with BestFit on the non-collinear paths: still exact.
    if (p == VesselPath::Helix || p == VesselPath::Arc) {
      const FrameReference bf = make_frame_reference(ref.C0, {FrameMode::RMF, FrameAnchor::BestFit});
      const SurfaceBinding bb = bind_to_polyline(mesh.V, bf);
      const Mat3 R = rotation(Vec3(1, 1, 1), 0.8);
      EXPECT_LE(
          max_row_distance(rebuild(bf, bb, rigid(bf.C0, R, Vec3(1, 0, 0))), rigid(mesh.V, R, Vec3(1, 0, 0))),
          1e-9);
    }
  }
}

TEST(Reconstruction, GenericNodesFollowTheInterpolatedFrames) {  // §5.9 under deformation
  const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::StraightX));
  const SurfaceMesh mesh = testing::closed_tube_around(ref, 2, 16, 3.0, 3.0);
  const SurfaceBinding b = bind_to_polyline(mesh.V, ref);
  MatX3 C = ref.C0;
  for (Index i = 1; i < 39; ++i) C(i, 1) += 4.0 * std::sin(std::numbers::pi * i / 39.0);
  FrameField F(40);
  compute_frames(C, ref, F);
  ReconstructionScratch s(40, 0);
  MatX3 S;
  reconstruct(b, C, F, s, S);
  for (Index k = 0; k < mesh.num_vertices(); ++k) {
    const Index i = b.atom[static_cast<std::size_t>(k)];
    const double lam = b.lambda[static_cast<std::size_t>(k)];
    const Vec3 c = (1 - lam) * C.row(i).transpose() + lam * C.row(i + 1).transpose();
    const Vec3 expect = c + interpolated_frame(F, i, lam) * b.offset.row(k).transpose();
    EXPECT_LE((S.row(k).transpose() - expect).norm(), 1e-12);
  }
}

TEST(Reconstruction, NormalsMatchTheGeometryLayerAndPointOutward) {
  const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::Helix));
  const MatX3 P0 = structured_rest_nodes(ref, cross_section_offsets(CrossSectionShape::Elliptical));
  const MatX3i F = tube_grid_faces(40, 30);
  const NormalPlan plan = make_normal_plan(1200, F);
  ReconstructionScratch s(40, static_cast<Index>(F.rows()));
  MatX3 N, Ref;
  vertex_normals(plan, P0, s, N);
  vertex_normals(P0, F, Ref);
  EXPECT_LE((N - Ref).cwiseAbs().maxCoeff(), 1e-12);
  for (Index k = 0; k < 1200; ++k) EXPECT_GT(N.row(k).dot(P0.row(k) - ref.C0.row(k / 30)), 0.0) << k;
}

TEST(Reconstruction, StructuredTubeNormalKernelMatchesTheGeometryLayer) {  // vectorised fast path
  for (Index n : {2, 3, 40})
    for (Index M : {3, 7, 30}) {
      SCOPED_TRACE(::testing::Message() << n << " x " << M);
      const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::Helix, n));
      MatX3 O = cross_section_offsets(CrossSectionShape::NonPlanar, M);
      const MatX3 P0 = structured_rest_nodes(ref, O);
      const MatX3i F = tube_grid_faces(n, M);
      const NormalPlan plan = make_normal_plan(n * M, F, n, M);
      ASSERT_EQ(plan.tube_rings, n);
      ReconstructionScratch s(n, static_cast<Index>(F.rows()), n, M);
      MatX3 N, Ref;
      vertex_normals(plan, P0, s, N);
      vertex_normals(P0, F, Ref);
      EXPECT_LE((N - Ref).cwiseAbs().maxCoeff(), 1e-12);
    }
  MatX3i G = tube_grid_faces(4, 5);
  G.row(3).reverseInPlace();  // not the tube grid any more: the generic path is used
  EXPECT_EQ(make_normal_plan(20, G, 4, 5).tube_rings, 0);
}

TEST(Reconstruction, UnsortedAndNonPlanarStructuredBindingsUseTheGeneralLoop) {
  const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::Arc));
  const MatX3 P0 = structured_rest_nodes(ref, cross_section_offsets(CrossSectionShape::NonPlanar));
  std::vector<Index> atoms = ring_atoms(40, 30);
  MatX3 Q = P0;
  std::swap(atoms[3], atoms[1000]);  // node 3 now rides on atom 33 and node 1000 on atom 0
  Q.row(3) = P0.row(1000);
  Q.row(1000) = P0.row(3);
  const SurfaceBinding b = bind_to_atoms(Q, atoms, ref);
  EXPECT_TRUE(b.atom_begin.empty());
  EXPECT_FALSE(bind_to_atoms(P0, ring_atoms(40, 30), ref).planar);
  MatX3 C = ref.C0;
  C.col(2).array() += 2.0 * C.col(0).array().sin();
  const MatX3 S = rebuild(ref, b, C);
  const MatX3 Ssorted = rebuild(ref, bind_to_atoms(P0, ring_atoms(40, 30), ref), C);
  EXPECT_LE((S.row(3) - Ssorted.row(1000)).norm(), 1e-12);
  EXPECT_LE((S.row(1000) - Ssorted.row(3)).norm(), 1e-12);
  EXPECT_LE((S.row(500) - Ssorted.row(500)).norm(), 1e-12);
}

TEST(Reconstruction, CurvatureValidityIsReported) {  // §5.6: rho kappa < 1
  const MatX3 arc = vessel_phantom_atoms(VesselPath::Arc);
  const VecX kappa = discrete_curvature(arc);
  EXPECT_EQ(kappa[0], 0.0);
  EXPECT_NEAR(kappa[20], 1.0 / 40.0, 1e-5);  // 2 sin(h / 2R) / h
  EXPECT_TRUE(check_curvature(arc, VecX::Constant(40, 3.0)).ok());
  const CurvatureCheck bad = check_curvature(arc, VecX::Constant(40, 45.0));
  EXPECT_EQ(bad.violations, 38);
  EXPECT_EQ(bad.first_atom, 1);
  EXPECT_GT(bad.max_rho_kappa, 1.0);
}

TEST(Reconstruction, BadBindingInputIsRejected) {
  const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::StraightX));
  EXPECT_THROW(bind_to_atoms(MatX3::Zero(2, 3), {0, 40}, ref), InvalidInput);
  EXPECT_THROW(bind_to_atoms(MatX3::Zero(2, 3), {0}, ref), InvalidInput);
  try {
    bind_offsets({0, 1, 7}, MatX3::Zero(3, 3), 5);
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("node 2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace medspring
