// The static patch solve K U = F of eq. (6): ALGORITHMS.md §6.2-§6.4 (D-16), as a precompute + solve
// pair. precompute assembles K, applies the boundary conditions and factors once; solve is cheap and
// allocation-free, so it can run every update.
//
//   LocalSolver solver;
//   solver.precompute(structured_window_patch(40, 30, GridNode{20, 7}));  // Isotropic, k_loc = 0.05
//   MatX3 U;
//   solver.solve(Vec3(0, 0, -0.05), U);  // U: #P x 3 displacement of the patch nodes, mm
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <string>
#include <string_view>
#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/local/patch.hpp"

namespace medspring {

/// How a patch spring contributes to K (§6.2, D-16).
enum class LocalStiffness {
  Isotropic,      // default (D-16): K = L (x) I3, L the k_loc-weighted graph Laplacian of the patch
  Linearized,     // exact linearised spring block k n n^T, plus k_r I per node
  AxisProjected,  // diagonal of the linearised block, diag(k n_x^2, k n_y^2, k n_z^2), plus k_r I per node
  PaperLiteral,   // the paper's 12 printed assignments verbatim (a < b by node index); comparison only
};

/// How the fixed patch nodes are imposed (§6.3). Both give the same U (§8.4-18).
enum class BoundaryMethod {
  Elimination,     // default: solve K_ff U_f = F_f
  RowReplacement,  // the paper's reading: zero each fixed row, K_ii = 1, F_i = 0; solve the full system by LU
};

const char* to_string(LocalStiffness mode);
/// The scene-file names: isotropic, linearized, axis_projected, paper_literal (core/params.hpp).
const char* param_enum_name(LocalStiffness mode);
LocalStiffness parse_enum(const std::string& text, LocalStiffness*);
const char* to_string(BoundaryMethod method);

/// Settings of the patch solve. Defaults: ALGORITHMS.md §6 and §9.
struct LocalSettings {
  LocalStiffness stiffness = LocalStiffness::Isotropic;   // D-16
  BoundaryMethod boundary = BoundaryMethod::Elimination;  // §6.3
  double return_stiffness = 0.02;  // N/mm, k_r added as k_r I per patch node in Linearized / AxisProjected
                                   // (§6.2, the return springs of §1.4); 0 = none (singular on flat patches)
  Index sparse_threshold = 64;     // Isotropic + Elimination: sparse Cholesky (SimplicialLDLT) when the patch
                                   // has more free nodes than this, dense LDLT otherwise
  double pivot_tolerance = 1e-12;  // a pivot |d| <= pivot_tolerance x max|K| means singular (§6.4)
};

/// What one solve did.
struct LocalSolveInfo {
  bool zero = false;      // U = 0 because the contact node is fixed or no patch node is free (§6.1)
  std::string_view note;  // what the stiffness mode does; non-empty only for PaperLiteral
};

/// The note carried by every PaperLiteral result.
inline constexpr std::string_view kPaperLiteralNote =
    "PaperLiteral: the paper's printed stiffness assembly taken verbatim (off-diagonal signs +k/-k "
    "depending on the axis and on which end has the lower node index), solved by LU; K is not "
    "symmetric and some nodes move against the force - a typesetting error kept for comparison only "
    "(ALGORITHMS.md §6.2), never a default";

/// The full 3P x 3P patch stiffness K before boundary conditions (§6.2), in the patch's local node order
/// (row 3a + alpha = node a, axis alpha). X: #N x 3 node positions (mm) giving the spring directions;
/// needed only for Linearized / AxisProjected (may be empty otherwise). Throws InvalidInput for an
/// inconsistent patch, missing positions, or a zero-length spring in Linearized / AxisProjected.
Eigen::MatrixXd local_stiffness_matrix(const LocalPatch& patch, const MatX3& X,
                                       const LocalSettings& settings = {});

/// Precomputed solver of K U = F for one patch (libigl-style precompute + solve).
class LocalSolver {
 public:
  /// Assembles K (§6.2), imposes the fixed nodes (§6.3) and factors (§6.4). Isotropic mode stores
  /// g = L_ff^{-1} e_c so that each solve is U_a = g_a F. X: #N x 3 positions (rest or current, mm),
  /// used only by Linearized / AxisProjected; Isotropic and PaperLiteral accept an empty X, e.g.
  /// `precompute(patch, {}, {.stiffness = LocalStiffness::PaperLiteral})`. A trivial patch (contact
  /// fixed or no free node) is not an error: every solve then returns U = 0.
  /// Throws InvalidInput for bad patches, settings or positions; SolverError naming the mode and the
  /// cause when the patch stiffness is singular.
  void precompute(const LocalPatch& patch, const MatX3& X = MatX3(), const LocalSettings& settings = {});

  /// Writes the displacement of every patch node for the force F (N) on the contact node into U
  /// (#P x 3, mm; resized if needed, so no allocation once U has #P rows). Never throws; before any
  /// precompute it writes nothing and returns zero = true.
  LocalSolveInfo solve(const Vec3& F, MatX3& U);

  bool ready() const { return ready_; }
  /// Number of patch nodes P of the last precompute.
  Index patch_size() const { return P_; }
  const LocalSettings& settings() const { return settings_; }
  /// Isotropic mode: g (#P), U_a = g_a F; empty for a trivial patch and in the other modes.
  const VecX& green() const { return g_; }
  std::string_view note() const {
    return settings_.stiffness == LocalStiffness::PaperLiteral ? kPaperLiteralNote : "";
  }

 private:
  enum class Path { None, Zero, Green, DenseLDLT, DenseLU };

  void precompute_isotropic(const LocalPatch& patch);
  void precompute_vector(const LocalPatch& patch, const MatX3& X);

  LocalSettings settings_;
  Path path_ = Path::None;
  bool ready_ = false;
  Index P_ = 0;
  Index c_dof_ = -1;               // first unknown of the contact node in the factored system
  VecX g_;                         // Isotropic: #P
  std::vector<Index> block_node_;  // vector modes: patch node of unknowns 3b..3b+2 of the factored system
  // Factored on an empty matrix: Eigen 3.4's default LDLT leaves its `info` field uninitialised, and
  // moving a LocalSolver that never took the dense path then reads it (UBSan: invalid enum load).
  Eigen::LDLT<Eigen::MatrixXd> ldlt_{Eigen::MatrixXd(0, 0)};
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
  VecX rhs_, x_;  // per-solve scratch, sized at precompute
};

}  // namespace medspring
