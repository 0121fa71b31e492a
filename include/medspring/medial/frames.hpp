// Tangents and orthonormal frames along a chain of centerline atoms (ALGORITHMS.md §5.3–5.5).
//
//   FrameReference ref = make_frame_reference(C0, {.mode = FrameMode::RMF, .anchor = FrameAnchor::TwoEnd});
//   FrameField F(n);                                   // buffers owned by the caller
//   FrameReport r = compute_frames(C, ref, F);         // no heap allocation
//   // atom i: u = F.u.row(i), v = F.v.row(i), t = F.t.row(i); spoke j: cos(th_j) u + sin(th_j) v
#pragma once

#include <string>

#include "medspring/core/types.hpp"

namespace medspring {

/// How the first spoke u_i of every atom is chosen.
enum class FrameMode {
  RMF,       // default (D-12): rotation-minimising frames by double reflection, anchored per FrameAnchor
  PaperXOY,  // eq. (3) literally: u_i = normalize(e_z x t_i), per atom; degenerate atoms are reported
};

/// How the roll about the tangent of the RMF frames is fixed (§5.5). Ignored by PaperXOY.
enum class FrameAnchor {
  OneEnd,   // r_0 = MinRot(t_0^0 -> t_0) u_0^0 (default when atom 0 is free)
  TwoEnd,   // OneEnd, then the roll mismatch at the last atom spread along the chain (vessel default)
  BestFit,  // r_0 from the Kabsch rotation between rest and current atoms (option; undefined roll for
            // a collinear rest chain)
};

FrameMode parse_frame_mode(const std::string& text);      // "rmf" | "paper_xoy"
FrameAnchor parse_frame_anchor(const std::string& text);  // "one_end" | "two_end" | "best_fit"
std::string to_string(FrameMode mode);
std::string to_string(FrameAnchor anchor);
inline FrameMode parse_enum(const std::string& text, FrameMode*) {
  return parse_frame_mode(text);
}
inline FrameAnchor parse_enum(const std::string& text, FrameAnchor*) {
  return parse_frame_anchor(text);
}

struct FrameSettings {
  FrameMode mode = FrameMode::RMF;
  FrameAnchor anchor = FrameAnchor::TwoEnd;
};

/// One orthonormal right-handed frame (u_i, v_i, t_i) per atom, as a struct of arrays, plus the scratch
/// used by compute_frames. Sized once; compute_frames never reallocates it.
struct FrameField {
  MatX3 u, v, t;  // (#n x 3) first spoke, second spoke v = t x u, unit tangent
  VecX sigma;     // (#n) scratch: cumulative chord length from atom 0 (TwoEnd), mm

  FrameField() = default;
  explicit FrameField(Index n) { resize(n); }
  void resize(Index n);
  Index size() const { return static_cast<Index>(t.rows()); }
  /// The frame of atom i as a rotation matrix with columns [u v t].
  Mat3 frame(Index i) const;
};

/// What compute_frames met (never thrown: numerical trouble inside an update is reported).
struct FrameReport {
  Index degenerate = 0;           // PaperXOY: atoms with |e_z x t_i| < 1e-6 (the fallback was used)
  Index first_degenerate = -1;    // first such atom, -1 if none
  Index degenerate_chords = 0;    // tangents taken from a fallback of §5.3 (chord < 1e-9 mm)
  Index transport_fallbacks = 0;  // RMF: transported spoke parallel to the tangent; MinRot used instead
  double gamma = 0.0;             // TwoEnd: roll mismatch at the last atom that was spread (rad)
  bool ok() const { return degenerate == 0; }
};

/// Unit tangents (§5.3, D-10): interior t_i = normalize(C_{i+1} - C_{i-1}), ends one-sided. A chord
/// shorter than 1e-9 mm falls back to C_{i+1} - C_i, then to t_{i-1}; for atom 0 to `t0_fallback`
/// (or e_x when null). T must have C's shape. Returns the number of fallbacks used.
Index compute_tangents(const MatX3& C, MatX3& T, const Vec3* t0_fallback = nullptr);

/// Eq. (3): writes u = normalize(e_z x t) and returns true, or returns false (u untouched) when
/// |e_z x t| < 1e-6 |t| (t parallel to the scanner axis). t need not be unit.
bool paper_xoy_spoke(const Vec3& t, Vec3& u);

/// The minimal rotation taking unit a to unit b, applied to w (§5.5):
/// c w + k x w + (k.w)/(1+c) k with c = a.b, k = a x b; for c <= -1 + 1e-12 the 180 degree rotation
/// about `axis` (a unit vector perpendicular to a).
Vec3 min_rotation(const Vec3& a, const Vec3& b, const Vec3& w, const Vec3& axis);

/// Double-reflection transport (D-12, Wang et al. 2008) of the first spoke u_0 along the chain C with
/// unit tangents T: writes U and V = T x U (row 0 = u_0, which must be unit and perpendicular to
/// T.row(0)). The two reflections of a step form an orthogonal map taking t_i to t_{i+1}; the
/// re-orthonormalisation of §5.5 is applied once per atom after the transport (equal to the per-step
/// form up to rounding, and keeps the serial chain to one 3 x 3 product per atom). Returns the number of
/// re-orthonormalisation fallbacks (numerical trouble only).
Index rmf_transport(const MatX3& C, const MatX3& T, const Vec3& u0, MatX3& U, MatX3& V);

/// The rest configuration that runtime frames are anchored to (§5.5): rest atoms and rest frames,
/// computed with the paper-compatible start u_0^0 = normalize(e_z x t_0^0) if |e_z x t_0^0| >= 0.1,
/// else normalize(e_x - (e_x.t_0^0) t_0^0).
struct FrameReference {
  FrameSettings settings;
  MatX3 C0;            // (#n x 3) rest atoms, mm
  FrameField F0;       // rest frames
  Vec3 centroid0;      // BestFit: centroid of C0
  FrameReport report;  // of the rest frames (PaperXOY: degenerate rest atoms, e.g. straight-z)
  Index size() const { return static_cast<Index>(C0.rows()); }
};

/// Builds the reference. Throws InvalidInput for fewer than 2 atoms, non-finite coordinates, or a rest
/// chain whose first segment is shorter than 1e-9 mm (its tangent would be undefined).
FrameReference make_frame_reference(const MatX3& C0, const FrameSettings& settings = {});

/// Frames of the current atoms C (same atom count as the reference) into F (sized by the caller to
/// ref.size(); not reallocated). No heap allocation, no exception. PaperXOY reports degenerate atoms
/// (fallback u_i = normalize(u_{i-1} - (u_{i-1}.t_i) t_i), or e_x projected for atom 0); never a silent
/// flip of the degenerate atoms. At rest, RMF frames equal the rest frames and TwoEnd gives gamma = 0.
FrameReport compute_frames(const MatX3& C, const FrameReference& ref, FrameField& F);

/// The best-fit rotation R (Kabsch) minimising sum |R (C0_i - c0) + c - C_i|^2, proper (det = +1).
Mat3 best_fit_rotation(const MatX3& C0, const Vec3& centroid0, const MatX3& C);

}  // namespace medspring
