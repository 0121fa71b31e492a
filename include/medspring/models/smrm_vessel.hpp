// The simplified medial representation (SMRM) vessel, ALGORITHMS.md §5: the physics integrates a chain
// of centerline atoms only; the visible surface is rebuilt every update from the deformed centerline
// (rotation-minimising frames, rest offsets: S = C + F o). Model kind "smrm".
//
//   SmrmVessel vessel = smrm_from_centerline(line);                // 40 atoms x 30 spokes, §9
//   State s = make_state(vessel.model());
//   vessel.transfer_force(node, F, s.f_ext);                       // D-14: to the node's atom
//   step(vessel.model(), s, {.dt = 0.5});
//   auto ws = vessel.make_workspace();
//   vessel.map_to_surface(s.x, ws, S);  vessel.surface_normals(S, ws, N);   // no allocation
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "medspring/geometry/polyline.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/medial/chain.hpp"
#include "medspring/medial/frames.hpp"
#include "medspring/medial/reconstruction.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/models/body.hpp"
#include "medspring/models/workspace_pool.hpp"

namespace medspring {

/// Bending of the centerline (an extension of the paper, ALGORITHMS.md §5.2 option, docs/vessels.md).
enum class BendingMode : std::uint8_t {
  Wall,      // default: k_b,i = E I_i / h_i^3 from the wall, I_i = pi/4 (r_o^4 - r_i^4) (hollow tube)
  Constant,  // chain.kb at every interior atom; chain.kb = 0 is the paper-literal chain (no bending)
};
BendingMode parse_bending_mode(const std::string& text);  // "wall" | "constant"
std::string to_string(BendingMode mode);
inline BendingMode parse_enum(const std::string& text, BendingMode*) {
  return parse_bending_mode(text);
}

/// The vessel wall that gives the default bending stiffness.
struct WallSettings {
  double E = 0.5;                // Young's modulus of the wall, MPa (= N/mm^2); aorta ~0.3-1 MPa
  double thickness_ratio = 0.1;  // wall thickness / lumen radius (large arteries ~0.1): r_o = 1.1 r_i
};

/// Bending stiffness per atom of a rest chain (#n x 3, mm) with lumen radii r (#n, mm): the discrete
/// form of (1/2) E I int |kappa - kappa0|^2 ds with Delta_i = C_{i-1} - 2 C_i + C_{i+1} ~ h_i^2 kappa_i
/// over the atom's length h_i = (|C_i - C_{i-1}| + |C_{i+1} - C_i|) / 2:
/// k_b,i = E pi/4 ((r_i (1 + thickness_ratio))^4 - r_i^4) / h_i^3 (N/mm); entries 0 and n-1 are 0.
/// Throws InvalidInput for E or thickness_ratio <= 0, a radius <= 0 or coincident atoms.
VecX wall_bending_stiffness(const MatX3& C0, const VecX& radius, const WallSettings& wall);

/// Settings of the SMRM vessel; defaults are the vessel column of ALGORITHMS.md §9.
struct SmrmSettings {
  Index atoms = 40;                // n, centerline atoms after resampling (>= 3)
  Index spokes = 30;               // M, spokes per atom of the structured builders (>= 3)
  FrameSettings frames{};          // RMF frames anchored at both ends (TwoEnd), D-12
  ChainSettings chain{};           // k_cl 0.2 N/mm, k_r 0.02 N/mm, 0.5 g, beta 0.5/ms, Duffing Strain
                                   // (chain.nonlinear), both end atoms fixed, no bending
  double k_loc = 0.05;             // N/mm, stiffness of the local patch (local_stiffness())
  double dedup_tolerance = 1e-3;   // mm: consecutive centerline points closer than this are merged
  double max_radius_factor = 3.0;  // generic binding / spoke marching limit, in local radii
  BendingMode bending = BendingMode::Wall;  // Wall (default): E I of the wall; Constant: chain.kb
  WallSettings wall{};                      // used by BendingMode::Wall
};

/// The declaration of SmrmSettings (core/params.hpp): the "parameters" of an smrm model in a scene, the
/// Python properties and keywords, `run --set model.parameters.NAME=VALUE`, the table in
/// docs/parameters.md. Flat names for the nested chain, wall and frame settings ("k_cl" is chain.k).
/// `atoms` is the model's "atoms" key and chain.nonlinear its "nonlinear" key, not parameters here.
/// In a scene file a "k_b" without "bending" means "bending": "constant" (scene.cpp).
template <ParamOf<SmrmSettings> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"spokes", "", "spokes per atom of the structured builders (M)"}.at_least(3), s.spokes);
  v(ParamSpec{"mass", "g", "mass of a centerline atom"}.positive(), s.chain.mass);
  v(ParamSpec{"beta", "1/ms", "mass-proportional damping of an atom, d = beta m"}.nonnegative(),
    s.chain.beta);
  v(ParamSpec{"k_cl", "N/mm", "centerline springs between consecutive atoms"}.positive(), s.chain.k);
  v(ParamSpec{"k_r", "N/mm", "return spring of an atom to its rest position"}.nonnegative(), s.chain.kr);
  v(ParamSpec{"bending", "", "wall (k_b from E I of the wall) or constant (k_b at every interior atom)"},
    s.bending);
  v(ParamSpec{"k_b", "N/mm", "bending stiffness of bending = constant (0: the paper's chain)"}.nonnegative(),
    s.chain.kb);
  v(ParamSpec{"wall_E", "MPa", "Young's modulus of the wall (bending = wall)"}.positive(), s.wall.E);
  v(ParamSpec{"wall_thickness_ratio", "", "wall thickness / lumen radius (bending = wall)"}.positive(),
    s.wall.thickness_ratio);
  v(ParamSpec{"fix_first", "", "atom 0 fixed"}, s.chain.fix_first);
  v(ParamSpec{"fix_last", "", "the last atom fixed"}, s.chain.fix_last);
  v(ParamSpec{"k_loc", "N/mm", "stiffness of the local deformation patch"}.positive(), s.k_loc);
  v(ParamSpec{"duffing", "", "Duffing law of the centerline springs (D-3)"}, s.chain.duffing);
  v(ParamSpec{"frame_mode", "", "rmf (D-12) or paper_xoy"}, s.frames.mode);
  v(ParamSpec{"frame_anchor", "", "RMF anchor: two_end, one_end or best_fit"}, s.frames.anchor);
  v(ParamSpec{"dedup_tolerance", "mm", "consecutive centerline points closer than this are merged"}
        .nonnegative(),
    s.dedup_tolerance);
  v(ParamSpec{"max_radius_factor", "", "spoke marching and generic binding limit, in local radii"}.positive(),
    s.max_radius_factor);
}

/// What the builders found (conditions that are reported, not thrown).
struct SmrmBuildReport {
  Index atoms = 0, surface_nodes = 0;
  Index removed_duplicates = 0;        // centerline points removed by deduplication
  FrameReport rest_frames;             // PaperXOY: degenerate rest atoms (e.g. straight-z)
  CurvatureCheck curvature;            // §5.6 validity rho_i kappa_i < 1
  Index spokes_without_hit = 0;        // spoke marching: no boundary within the limit, rho = r_i
  Index first_spoke_without_hit = -1;  // its surface node, -1 if none
  std::vector<Index> missed_spokes;    // the surface nodes of all such spokes
  double max_distance_ratio = 0.0;     // generic binding: max node distance / local radius
  std::vector<std::string> notes;      // one line per reported condition
};

/// The parts of an SMRM vessel, as assembled by the builders below.
struct SmrmParts {
  std::string name = "vessel";
  MatX3 atoms;             // rest atoms (#n x 3), mm, n >= 3
  VecX atom_radius;        // (#n) local lumen radius, mm; empty = largest spoke of each atom
  SurfaceBinding binding;  // how every surface node rides on the atoms (structured or generic)
  MatX3 rest_surface;      // (#S x 3) mm; empty = reconstructed from the binding at rest
  MatX3i faces;            // (#F x 3) triangles over the surface nodes
  GridLayout grid;         // rings x spokes of a structured tube (node i M + j), else invalid
  SmrmBuildReport report;  // builder findings (completed by the constructor)
};

class SmrmVessel final : public Body {
 public:
  /// Validates the parts and builds the chain model, rest frames, normal plan. Throws InvalidInput
  /// naming the vessel and the atom / node at fault.
  SmrmVessel(SmrmParts parts, const SmrmSettings& settings);

  // Body
  std::string kind() const override { return "smrm"; }
  const Model& model() const override { return model_; }
  const MatX3i& faces() const override { return faces_; }
  const MatX3& rest_surface() const override { return rest_surface_; }
  /// Frames + reconstruction (§5.5, §5.7) of state.x; normals are a separate call. Uses a per-thread
  /// workspace (allocated on the first call of a thread); map_to_surface(atoms, ws, S) is the explicit,
  /// allocation-free form.
  void map_to_surface(const State& state, MatX3& surface) const override;
  /// D-14: structured node -> all of F to its atom; generic node (i, lambda) -> (1 - lambda) F to atom i,
  /// lambda F to atom i + 1. Shares for fixed atoms are dropped (no global response). Moment discarded.
  void transfer_force(Index node, const Vec3& F, MatX3& f_dof) const override;
  GridLayout grid() const override { return grid_; }
  double local_stiffness() const override { return settings_.k_loc; }
  /// Rest distance from the node to its (interpolated) atom, mm.
  double spoke_length(Index node) const override;

  // SMRM specifics
  const std::string& name() const { return name_; }
  const SmrmSettings& settings() const { return settings_; }
  const SmrmBuildReport& report() const { return report_; }
  const FrameReference& frame_reference() const { return ref_; }
  const SurfaceBinding& binding() const { return binding_; }
  const NormalPlan& normal_plan() const { return normals_; }
  Index num_atoms() const { return ref_.size(); }
  const MatX3& rest_atoms() const { return ref_.C0; }
  const VecX& atom_radius() const { return atom_radius_; }
  /// Bending stiffness k_b,i of every atom (N/mm, §5.2 option; 0 at the ends and with k_b = 0).
  const VecX& bending_stiffness() const { return bending_k_; }
  /// Largest in-plane spoke of every atom (mm), the rho of the validity check.
  const VecX& max_spoke() const { return rho_max_; }
  /// §5.6 validity rho_i kappa_i < 1 of the atoms (#n x 3); no allocation.
  CurvatureCheck validity(const MatX3& atoms) const;
  /// Largest |alpha_i - alpha_i^0| over the interior atoms, degrees: alpha_i = the turning angle
  /// between segments (i-1, i) and (i, i+1); the atom where it is largest in *atom. No allocation.
  double max_turning_change_deg(const MatX3& atoms, Index* atom = nullptr) const;
  /// Turning angle alpha_i of every atom (degrees, 0 at the ends).
  static VecX turning_angles_deg(const MatX3& atoms);

  /// Per-update buffers (one per thread or per state).
  struct Workspace {
    FrameField frames;
    ReconstructionScratch scratch;
  };
  Workspace make_workspace() const;
  /// Frames of `atoms` (#n x 3) and the reconstructed surface (#S x 3). No heap allocation once
  /// `surface` has its size. Returns what the frame computation met (PaperXOY degeneracy, gamma, ...).
  FrameReport map_to_surface(const MatX3& atoms, Workspace& ws, MatX3& surface) const;
  /// Area-weighted unit vertex normals of a reconstructed surface (precomputed incidence, no allocation).
  void surface_normals(const MatX3& surface, Workspace& ws, MatX3& normals) const;

  /// The chain model of this vessel with the Duffing springs switched on or off (linear vs nonlinear).
  Model make_chain(bool nonlinear) const;
  /// The elastic force of the chain (springs + return springs + bending, no damping, no load) at the
  /// free atom(s) receiving a force on `node`, weighted as in transfer_force: the force the vessel exerts
  /// back on a tool at that node; -F at static equilibrium under a force F on the node (N).
  Vec3 reaction_force(const State& state, Index node) const;
  /// The atom a surface node belongs to (structured: its atom; generic: the nearer bracket atom).
  Index node_atom(Index node) const;
  /// The node of ring `atom` whose rest outward normal is most opposed to F (§7.2 contact node).
  /// Throws InvalidInput if no node belongs to that atom or F is zero.
  Index contact_node(Index atom, const Vec3& F) const;

 private:
  WorkspacePool<Workspace> workspaces_;  // of map_to_surface(State, ...), one per concurrent caller
  std::string name_;
  SmrmSettings settings_;
  FrameReference ref_;
  SurfaceBinding binding_;
  Model model_;
  MatX3 rest_surface_;
  MatX3i faces_;
  GridLayout grid_;
  NormalPlan normals_;
  MatX3 rest_normals_;
  VecX spoke_length_;
  VecX atom_radius_;
  VecX bending_k_;
  VecX rho_max_;
  VecX rest_turning_;  // radians
  SmrmBuildReport report_;
};

// ---- Builders (all throw InvalidInput naming the polyline, atom or node at fault) ----

/// Structured vessel from rest atoms (#n x 3, mm) and cross-section offsets (o_u, o_v, o_t) in the
/// rest frames: #n*M x 3 (one per node, M = settings.spokes) or #M x 3 (shared by every atom). Node
/// (i, j) = i M + j; tube-grid triangles (§1.1). Rejects < 3 atoms, repeated atoms and zero-length
/// spokes.
SmrmVessel smrm_from_offsets(const MatX3& atoms, const MatX3& offsets, const SmrmSettings& settings = {},
                             const std::string& name = "vessel");

/// Structured circular vessel from a centerline in mm (eq. (4), D-11): deduplicate, resample to
/// settings.atoms atoms, spoke j of atom i = C_i + r_i (cos th_j u_i + sin th_j v_i). Rejects fewer than
/// 3 distinct points and radii <= 0 (naming the polyline and point).
SmrmVessel smrm_from_centerline(const Centerline& line, const SmrmSettings& settings = {});

/// The longest of several centerlines (by arc length; ties: the first), e.g. the main branch of a VMTK
/// file whose polylines share a trunk. Throws InvalidInput for an empty list.
const Centerline& longest_centerline(const std::vector<Centerline>& lines);

/// Generic vessel (§5.9) from a closed, valid surface mesh and its centerline (mm): every surface node
/// is bound to the closest point of the resampled centerline. A node farther than
/// settings.max_radius_factor x the local radius is rejected, naming the node; the local radius is the
/// largest radius of the two bracket atoms and their neighbours (a closed tip tapers towards zero).
SmrmVessel smrm_from_surface(const SurfaceMesh& surface, const Centerline& line,
                             const SmrmSettings& settings = {});

/// Structured vessel whose spoke lengths are marched to a boundary mesh (§5.6, mesh input): first
/// ray-triangle hit along w_ij = cos th_j u_i^0 + sin th_j v_i^0; no hit within
/// settings.max_radius_factor r_i gives rho_ij = r_i (reported in report().spokes_without_hit).
SmrmVessel smrm_from_marched_spokes(const Centerline& line, const SurfaceMesh& boundary,
                                    const SmrmSettings& settings = {});

/// The procedural phantoms of §8.0 (settings.atoms atoms at 2.5 mm, settings.spokes spokes).
SmrmVessel smrm_phantom(VesselPath path, CrossSectionShape shape, const SmrmSettings& settings = {});

/// The closest point of a ray (origin o, unit direction w) hitting the mesh at distance in (0, t_max],
/// or +inf (Moeller-Trumbore, both triangle sides).
double first_ray_hit(const SurfaceMesh& mesh, const Vec3& o, const Vec3& w,
                     double t_max = std::numeric_limits<double>::infinity());

// ---- The paper's vessel experiment (§7.2, Fig. 10) ----

struct VesselExperimentSettings {
  Index atom = 20;                // loaded atom
  Vec3 direction = Vec3::Zero();  // force direction (its tangential part is removed); zero = u_atom^0
  double light = 0.05;            // N
  double strong = 0.5;            // N
  double t_ramp = 20.0;           // ms, linear ramp (§1.6)
  double t_release = 500.0;       // ms, instant release
  double t_end = 1000.0;          // ms
  double dt = 0.5;                // ms per frame (symplectic Euler, §2)
  double rest_tolerance = 1e-3;   // mm, "back at rest"
};

/// One force level with the linear or the nonlinear chain (global deformation only). return_time is the
/// time after release (ms) from which every surface node stays within rest_tolerance (inf: never).
struct VesselRun {
  double force = 0.0;             // N
  bool nonlinear = false;         // Duffing chain springs
  VecX time;                      // (#T) ms, end of every frame
  VecX atom_displacement;         // (#T) |C_a - C_a^0|, mm
  VecX contact_displacement;      // (#T) |S_c - S_c^0| of the contact node, mm
  VecX max_surface_displacement;  // (#T) max over surface nodes, mm
  MatX3 profile;                  // (#n x 3) atom displacements at release, mm
  MatX3 surface;                  // (#S x 3) reconstructed surface at release, mm
  double atom_hold = 0.0;         // |u| of the loaded atom at release, mm
  double contact_hold = 0.0;      // |u| of the contact node at release, mm
  double return_time = std::numeric_limits<double>::infinity();  // ms
  std::uint64_t warnings = 0;         // integrator warnings (State::warnings.total())
  double max_rho_kappa = 0.0;         // §5.6 validity, max over every update and atom
  Index rho_kappa_violations = 0;     // (update, atom) pairs with rho kappa >= 1
  double max_turning_change_deg = 0;  // max over updates and atoms of |alpha_i - alpha_i^0|
  Index max_turning_atom = -1;        // where it was largest
};

struct VesselExperimentResult {
  Index atom = 0;
  Index contact_node = -1;        // node of ring `atom` most opposed to F: the hook for local deformation
  Vec3 direction = Vec3::Zero();  // unit force direction
  VesselRun light_linear, light_nonlinear, strong_linear, strong_nonlinear;
};

/// Runs the four cases: force on `atom` ramped over t_ramp, held until t_release, released, run to
/// t_end; light and strong, linear and nonlinear chain. Throws InvalidInput for a bad atom or settings.
VesselExperimentResult run_vessel_experiment(const SmrmVessel& vessel,
                                             const VesselExperimentSettings& settings = {});

}  // namespace medspring
