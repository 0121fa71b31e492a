// Rest binding of surface nodes to the centerline atoms and runtime reconstruction of the surface
// (ALGORITHMS.md §5.6 D-13, §5.7, §5.9), plus vertex normals of the reconstructed surface.
//
//   SurfaceBinding b = bind_to_atoms(P0, atom_of_node, ref);   // o = F0^T (p0 - C0), once
//   ReconstructionScratch scratch(n, F.rows(), rings, spokes);  // buffers, sized once
//   NormalPlan plan = make_normal_plan(P0.rows(), F, rings, spokes);
//   compute_frames(C, ref, frames);                            // every update ...
//   reconstruct(b, C, frames, scratch, S);                     // S = C + F o, no allocation
//   vertex_normals(plan, S, scratch, N);                       // for rendering
#pragma once

#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/medial/frames.hpp"

namespace medspring {

/// How every surface node is attached to the atoms. Structured (D-13): node k rides on atom[k] with a
/// constant offset in that atom's frame. Generic (§5.9): node k rides on the bracket (atom[k],
/// atom[k] + 1) at parameter lambda[k], with its offset in the slerp-interpolated frame.
struct SurfaceBinding {
  std::vector<Index> atom;        // (#S) the atom (structured) or the first atom of the bracket (generic)
  std::vector<double> lambda;     // (#S) bracket parameter in [0, 1]; empty for a structured binding
  MatX3 offset;                   // (#S x 3) local offsets (o_u, o_v, o_t), mm
  std::vector<Index> atom_begin;  // (#n + 1) structured and sorted by atom: nodes of atom a are
                                  // [atom_begin[a], atom_begin[a+1]); empty otherwise
  Index num_atoms = 0;
  // Derived by finalize_binding (call it after editing the fields above): the offsets as a struct of
  // arrays for the vectorised structured path.
  std::vector<double> ou, ov, ot;  // (#S) structured and sorted only
  bool planar = false;             // every o_t is 0 (the tangent term is skipped)

  Index size() const { return static_cast<Index>(atom.size()); }
  bool generic() const { return !lambda.empty(); }
};

/// Recomputes the derived fields of a binding (atom_begin, the SoA offsets, planar).
void finalize_binding(SurfaceBinding& b);

/// Structured binding from given local offsets (e.g. eq. (4) / D-11: o_ij = (rho cos th_j, rho sin th_j, 0)).
/// Throws InvalidInput for an atom index out of [0, n) or non-finite offsets (naming the node).
SurfaceBinding bind_offsets(const std::vector<Index>& atom, const MatX3& offsets, Index num_atoms);

/// Structured rest binding (D-13): o_k = F0_a^T (p0_k - C0_a) with a = atom[k]. Exact at rest for any
/// cross-section shape. Throws InvalidInput naming the node for a bad atom index or coordinates.
SurfaceBinding bind_to_atoms(const MatX3& P0, const std::vector<Index>& atom, const FrameReference& ref);

/// The closest point of a polyline to p: segment i, parameter lambda in [0, 1] (clamped at the ends;
/// lambda = 1 on an interior atom is reported as (i + 1, 0)), distance in mm. Ties: lowest segment.
struct PolylinePoint {
  Index segment = 0;
  double lambda = 0.0;
  double distance = 0.0;
};
PolylinePoint closest_point_on_polyline(const MatX3& C, const Vec3& p);

/// Generic rest binding of an unstructured mesh (§5.9): every node to the closest point of the rest
/// polyline, offset o = F0(lambda)^T (p0 - C0(lambda)). Exact at rest by construction. `distance`
/// (if given) receives every node's distance to the polyline, mm.
SurfaceBinding bind_to_polyline(const MatX3& P0, const FrameReference& ref, VecX* distance = nullptr);

/// Geodesic interpolation of the frames of atoms i and i + 1 (§5.9): F_i Exp(lambda Log(F_i^T F_{i+1})),
/// i.e. quaternion slerp; exactly F_i at lambda = 0 and F_{i+1} at lambda = 1.
Mat3 interpolated_frame(const FrameField& F, Index i, double lambda);

/// Per-update buffers of reconstruct and vertex_normals (sized once; never reallocated by them).
struct ReconstructionScratch {
  MatX3 axis;                // (#n-1 x 3) unit axis of F_i^T F_{i+1} (generic bindings)
  VecX angle;                // (#n-1) its angle, rad
  MatX3 face_normals;        // (#F x 3) unnormalised face normals (2 x area), generic meshes
  std::vector<double> tube;  // struct-of-arrays buffers of the structured tube normals
  ReconstructionScratch() = default;
  /// Sized for a chain of num_atoms atoms and a mesh of num_faces triangles; tube_rings x tube_spokes
  /// also sizes the structured-tube buffers (see NormalPlan).
  ReconstructionScratch(Index num_atoms, Index num_faces, Index tube_rings = 0, Index tube_spokes = 0);
};

/// Axis and angle of the relative rotation F_i^T F_{i+1} of every segment (generic reconstruction).
void segment_rotations(const FrameField& F, MatX3& axis, VecX& angle);

/// Runtime reconstruction (§5.7): S_k = C_a + o_u u_a + o_v v_a + o_t t_a (structured) or
/// C(lambda) + F(lambda) o (generic). S must have b.size() rows (it is resized otherwise). No heap
/// allocation once S and the scratch have their sizes.
void reconstruct(const SurfaceBinding& b, const MatX3& C, const FrameField& F, ReconstructionScratch& scratch,
                 MatX3& S);
/// The same into b.size() rows of 3 doubles at `S` (e.g. a branch's rows of a larger row-major surface).
void reconstruct(const SurfaceBinding& b, const MatX3& C, const FrameField& F, ReconstructionScratch& scratch,
                 double* S);

/// Validity of the cross-sections (§5.6): rho_i kappa_i < 1 with the discrete curvature
/// kappa_i = 2 sin(alpha_i / 2) / h_i (alpha_i the turning angle at atom i, h_i the mean adjacent
/// segment length; 0 at the ends) and rho_i the largest spoke of atom i.
struct CurvatureCheck {
  Index violations = 0;   // atoms with rho_i kappa_i >= 1
  Index first_atom = -1;  // first violating atom, -1 if none
  double max_rho_kappa = 0.0;
  bool ok() const { return violations == 0; }
};
VecX discrete_curvature(const MatX3& C);
CurvatureCheck check_curvature(const MatX3& C, const VecX& rho_max);

/// Precomputed face/vertex incidence for area-weighted vertex normals of a fixed triangle list.
struct NormalPlan {
  MatX3i F;                    // (#F x 3) triangles
  std::vector<Index> offsets;  // (#V + 1) CSR: faces incident to vertex i are faces[offsets[i]..offsets[i+1])
  std::vector<Index> faces;    // (3 #F)
  Index num_vertices = 0;
  Index tube_rings = 0, tube_spokes = 0;  // set when F is exactly tube_grid_faces(rings, spokes): the
                                          // structured, vectorised kernel is used
};
/// Builds the incidence; if rings x spokes is given and F equals tube_grid_faces(rings, spokes), the
/// plan also enables the structured-tube kernel.
NormalPlan make_normal_plan(Index num_vertices, const MatX3i& F, Index rings = 0, Index spokes = 0);

/// Area-weighted unit vertex normals of V (zero for a vertex whose incident faces have no area), same
/// convention as geometry's vertex_normals. Uses the scratch buffers (resized only if their size is wrong).
void vertex_normals(const NormalPlan& plan, const MatX3& V, ReconstructionScratch& scratch, MatX3& N);

}  // namespace medspring
