// ALGORITHMS.md §5.3-5.5 and §8.3 checks 15-16: tangents, rotation-minimising frames, PaperXOY.
#include "medspring/medial/frames.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "medial_fixtures.hpp"
#include "medspring/core/error.hpp"
#include "medspring/medial/vessel_phantoms.hpp"

namespace medspring {
namespace {

using testing::rotation;

const VesselPath kPaths[] = {VesselPath::StraightX, VesselPath::StraightZ, VesselPath::Arc,
                             VesselPath::Helix};
const FrameAnchor kAnchors[] = {FrameAnchor::OneEnd, FrameAnchor::TwoEnd, FrameAnchor::BestFit};

// A smooth, non-rigid deformation of the atoms (ends kept), mm.
MatX3 bend(const MatX3& C0, double amp) {
  MatX3 C = C0;
  const Index n = static_cast<Index>(C0.rows());
  for (Index i = 1; i + 1 < n; ++i) {
    const double s = static_cast<double>(i) / static_cast<double>(n - 1);
    C(i, 0) += amp * std::sin(3.1 * s) * std::sin(std::numbers::pi * s);
    C(i, 1) += 0.7 * amp * std::sin(std::numbers::pi * s);
    C(i, 2) += 0.4 * amp * std::sin(2.0 * std::numbers::pi * s);
  }
  return C;
}

void expect_orthonormal_right_handed(const FrameField& F, double tol) {
  for (Index i = 0; i < F.size(); ++i) {
    const Mat3 R = F.frame(i);
    EXPECT_LE((R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff(), tol) << "atom " << i;
    EXPECT_NEAR(R.determinant(), 1.0, tol) << "atom " << i;
    EXPECT_LE((R.col(0).cross(R.col(1)) - R.col(2)).norm(), tol) << "atom " << i;  // u x v = t
  }
}

TEST(Tangents, InteriorChordsAndOneSidedEnds) {  // §5.3, D-10
  MatX3 C(4, 3);
  C << 0, 0, 0, 1, 0, 0, 1, 1, 0, 1, 1, 2;
  MatX3 T(4, 3);
  EXPECT_EQ(compute_tangents(C, T), 0);
  EXPECT_LE((T.row(0) - Eigen::RowVector3d(1, 0, 0)).norm(), 1e-15);
  EXPECT_LE((T.row(1) - Eigen::RowVector3d(1, 1, 0).normalized()).norm(), 1e-15);
  EXPECT_LE((T.row(2) - Eigen::RowVector3d(0, 1, 2).normalized()).norm(), 1e-15);
  EXPECT_LE((T.row(3) - Eigen::RowVector3d(0, 0, 1)).norm(), 1e-15);
}

TEST(Tangents, DegenerateChordsUseTheDocumentedFallbacks) {  // §5.3
  MatX3 C(4, 3);                                             // folded back: the chord at atom 1 vanishes
  C << 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 1;
  MatX3 T(4, 3);
  EXPECT_EQ(compute_tangents(C, T), 1);
  EXPECT_LE((T.row(1) - Eigen::RowVector3d(-1, 0, 0)).norm(), 1e-15);  // C_2 - C_1
  MatX3 D(3, 3);  // atoms 0 and 1 coincide: atom 0 takes the given rest tangent
  D << 0, 0, 0, 0, 0, 0, 0, 0, 1;
  const Vec3 rest(0, 1, 0);
  MatX3 U(3, 3);
  EXPECT_EQ(compute_tangents(D, U, &rest), 1);
  EXPECT_LE((U.row(0) - Eigen::RowVector3d(0, 1, 0)).norm(), 1e-15);
}

TEST(Frames, RestFramesStartWithThePaperCompatibleSpoke) {  // §5.5
  const FrameReference x = make_frame_reference(vessel_phantom_atoms(VesselPath::StraightX));
  EXPECT_LE((x.F0.u.row(0) - Eigen::RowVector3d(0, 1, 0)).norm(), 1e-15);  // e_z x e_x
  const FrameReference z = make_frame_reference(vessel_phantom_atoms(VesselPath::StraightZ));
  EXPECT_LE((z.F0.u.row(0) - Eigen::RowVector3d(1, 0, 0)).norm(), 1e-15);  // e_x projected
  EXPECT_EQ(z.report.degenerate, 0);                                       // RMF is fine on straight-z
}

TEST(Frames, RmfFramesAreOrthonormalAndRightHanded) {  // §8.3-15, 1e-12
  for (VesselPath p : kPaths)
    for (FrameAnchor a : kAnchors) {
      SCOPED_TRACE(to_string(p) + " " + to_string(a));
      const FrameReference ref = make_frame_reference(vessel_phantom_atoms(p), {FrameMode::RMF, a});
      expect_orthonormal_right_handed(ref.F0, 1e-12);
      FrameField F(ref.size());
      compute_frames(bend(ref.C0, 4.0), ref, F);
      expect_orthonormal_right_handed(F, 1e-12);
    }
}

TEST(Frames, PlanarCurveWithInPlaneFirstSpokeHasNoTwist) {  // §8.3-15: v_i = +-e_z, 1e-12
  const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::Arc));
  EXPECT_NEAR(ref.F0.u(0, 2), 0.0, 1e-15);  // u_0 in the xy-plane
  for (Index i = 0; i < ref.size(); ++i) {
    EXPECT_NEAR(std::abs(ref.F0.v(i, 2)), 1.0, 1e-12) << "atom " << i;
    EXPECT_NEAR(ref.F0.u(i, 2), 0.0, 1e-12) << "atom " << i;
  }
}

TEST(Frames, TwoEndAtRestGivesZeroGammaAndTheRestFrames) {  // §8.3-15
  for (VesselPath p : kPaths) {
    SCOPED_TRACE(to_string(p));
    const FrameReference ref =
        make_frame_reference(vessel_phantom_atoms(p), {FrameMode::RMF, FrameAnchor::TwoEnd});
    FrameField F(ref.size());
    const FrameReport r = compute_frames(ref.C0, ref, F);
    EXPECT_NEAR(r.gamma, 0.0, 1e-12);
    EXPECT_LE((F.u - ref.F0.u).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_LE((F.v - ref.F0.v).cwiseAbs().maxCoeff(), 1e-14);
  }
}

TEST(Frames, TwoEndMatchesTheMinimalRotationAtTheLastAtom) {  // §5.5: the roll mismatch is removed
  const FrameReference ref =
      make_frame_reference(vessel_phantom_atoms(VesselPath::Helix), {FrameMode::RMF, FrameAnchor::TwoEnd});
  const MatX3 C = bend(ref.C0, 6.0);
  FrameField F(ref.size());
  const FrameReport r = compute_frames(C, ref, F);
  EXPECT_GT(std::abs(r.gamma), 1e-6);  // the deformation does create a mismatch
  const Index l = ref.size() - 1;
  const Vec3 ustar = min_rotation(ref.F0.t.row(l).transpose(), F.t.row(l).transpose(),
                                  ref.F0.u.row(l).transpose(), ref.F0.u.row(l).transpose());
  EXPECT_LE((F.u.row(l).transpose() - ustar).norm(), 1e-12);
}

TEST(Frames, MinimalRotationMapsAToBAndFixesTheirCommonNormal) {  // §5.5 MinRot
  const Vec3 a = Vec3(1, 2, 3).normalized(), b = Vec3(-2, 0.5, 1).normalized();
  EXPECT_LE((min_rotation(a, b, a, Vec3::UnitX()) - b).norm(), 1e-15);
  const Vec3 k = a.cross(b).normalized();
  EXPECT_LE((min_rotation(a, b, k, Vec3::UnitX()) - k).norm(), 1e-15);
  const Vec3 axis = Vec3(0, 3, -2).normalized();                // perpendicular to (1, 2, 3)
  EXPECT_LE((min_rotation(a, -a, a, axis) + a).norm(), 1e-15);  // antiparallel: 180 degrees about axis
}

TEST(Frames, BestFitRotationRecoversARigidRotation) {  // Kabsch
  const MatX3 C0 = vessel_phantom_atoms(VesselPath::Helix);
  const Mat3 R = rotation(Vec3(0.3, -1, 2), 2.1);
  const MatX3 C = testing::rigid(C0, R, Vec3(5, -7, 11));
  const Vec3 c0 = C0.colwise().mean().transpose();
  EXPECT_LE((best_fit_rotation(C0, c0, C) - R).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(Frames, OneEndFramesRotateWithARotationPerpendicularToTheFirstTangent) {  // §5.5 rigid motion
  for (VesselPath p : kPaths) {
    SCOPED_TRACE(to_string(p));
    const FrameReference ref =
        make_frame_reference(vessel_phantom_atoms(p), {FrameMode::RMF, FrameAnchor::OneEnd});
    const Vec3 axis = 0.6 * ref.F0.u.row(0).transpose() - 0.8 * ref.F0.v.row(0).transpose();
    const Mat3 R = rotation(axis, 1.3);
    FrameField F(ref.size());
    compute_frames(testing::rigid(ref.C0, R, Vec3(1, 2, 3)), ref, F);
    for (Index i = 0; i < ref.size(); ++i)
      EXPECT_LE((F.frame(i) - R * ref.F0.frame(i)).cwiseAbs().maxCoeff(), 1e-13);
  }
}

TEST(Frames, PaperXoyFlipDocumentsTheDefect) {  // §8.3-16: t = (-+0.001, 0, 1) -> u = (0, -+1, 0)
  Vec3 u;
  ASSERT_TRUE(paper_xoy_spoke(Vec3(-0.001, 0, 1), u));
  EXPECT_LE((u - Vec3(0, -1, 0)).norm(), 1e-15);
  ASSERT_TRUE(paper_xoy_spoke(Vec3(0.001, 0, 1), u));
  EXPECT_LE((u - Vec3(0, 1, 0)).norm(), 1e-15);
  // The same through the chain: end tangents (-0.001, 0, 1) and (0.001, 0, 1); the middle chord is e_z.
  MatX3 C(3, 3);
  C << 0, 0, 0, -0.001, 0, 1, 0, 0, 2;
  const FrameReference ref = make_frame_reference(C, {.mode = FrameMode::PaperXOY});
  EXPECT_LE((ref.F0.u.row(0) - Eigen::RowVector3d(0, -1, 0)).norm(), 1e-15);
  EXPECT_LE((ref.F0.u.row(2) - Eigen::RowVector3d(0, 1, 0)).norm(), 1e-15);  // flipped by 180 degrees
  EXPECT_EQ(ref.report.degenerate, 1);  // the middle atom is reported, not flipped silently
  EXPECT_EQ(ref.report.first_degenerate, 1);
  EXPECT_LE((ref.F0.u.row(1) - Eigen::RowVector3d(0, -1, 0)).norm(), 1e-15);  // fallback: u_0 projected
}

TEST(Frames, PaperXoyReportsStraightZDegenerate) {  // §8.2-11 / §5.4 defect 1
  const FrameReference ref =
      make_frame_reference(vessel_phantom_atoms(VesselPath::StraightZ), {.mode = FrameMode::PaperXOY});
  EXPECT_EQ(ref.report.degenerate, 40);
  EXPECT_EQ(ref.report.first_degenerate, 0);
  EXPECT_FALSE(ref.report.ok());
  expect_orthonormal_right_handed(ref.F0, 1e-15);  // the fallback still gives usable frames
  FrameField F(ref.size());
  EXPECT_EQ(compute_frames(ref.C0, ref, F).degenerate, 40);
  // A horizontal vessel is not degenerate in PaperXOY mode.
  EXPECT_TRUE(
      make_frame_reference(vessel_phantom_atoms(VesselPath::Arc), {.mode = FrameMode::PaperXOY}).report.ok());
}

TEST(Frames, RmfOnStraightZDoesNotFlipUnderTransverseBending) {  // §8.2-11 (no flip)
  const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::StraightZ));
  MatX3 C = ref.C0;
  for (Index i = 1; i + 1 < ref.size(); ++i)
    C(i, 0) = 3.0 * std::sin(std::numbers::pi * i / 39.0);  // bend in x
  FrameField F(ref.size());
  const FrameReport r = compute_frames(C, ref, F);
  EXPECT_EQ(r.degenerate, 0);
  for (Index i = 0; i + 1 < ref.size(); ++i) EXPECT_GT(F.u.row(i).dot(F.u.row(i + 1)), std::cos(0.1)) << i;
  // PaperXOY on the same bend flips u between the two sides of the crest.
  const FrameReference paper = make_frame_reference(ref.C0, {.mode = FrameMode::PaperXOY});
  FrameField P(ref.size());
  compute_frames(C, paper, P);
  double min_dot = 1.0;
  for (Index i = 0; i + 1 < ref.size(); ++i) min_dot = std::min(min_dot, P.u.row(i).dot(P.u.row(i + 1)));
  EXPECT_LT(min_dot, -0.99);
}

TEST(Frames, ComputeFramesDoesNotAllocateOrResize) {  // buffers are the caller's
  const FrameReference ref = make_frame_reference(vessel_phantom_atoms(VesselPath::Helix));
  FrameField F(ref.size());
  const double* pu = F.u.data();
  compute_frames(bend(ref.C0, 2.0), ref, F);
  EXPECT_EQ(F.u.data(), pu);
}

TEST(Frames, BadReferenceInputIsRejected) {
  EXPECT_THROW(make_frame_reference(MatX3::Zero(1, 3)), InvalidInput);
  MatX3 C(3, 3);
  C << 0, 0, 0, 0, 0, 0, 1, 0, 0;
  EXPECT_THROW(make_frame_reference(C), InvalidInput);
  EXPECT_THROW(parse_frame_mode("xoy"), InvalidInput);
  EXPECT_EQ(parse_frame_anchor("best_fit"), FrameAnchor::BestFit);
}

}  // namespace
}  // namespace medspring
