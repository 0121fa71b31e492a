#include "medspring/local/solver.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <vector>

#include "medspring/core/check.hpp"

namespace medspring {

const char* param_enum_name(LocalStiffness mode) {
  switch (mode) {
    case LocalStiffness::Isotropic:
      return "isotropic";
    case LocalStiffness::Linearized:
      return "linearized";
    case LocalStiffness::AxisProjected:
      return "axis_projected";
    case LocalStiffness::PaperLiteral:
      return "paper_literal";
  }
  return "unknown";
}

LocalStiffness parse_enum(const std::string& text, LocalStiffness*) {
  for (LocalStiffness m : {LocalStiffness::Isotropic, LocalStiffness::Linearized,
                           LocalStiffness::AxisProjected, LocalStiffness::PaperLiteral})
    if (text == param_enum_name(m)) return m;
  throw InvalidInput(
      cat("unknown value '", text, "' (expected isotropic, linearized, axis_projected or paper_literal)"));
}

const char* to_string(LocalStiffness mode) {
  switch (mode) {
    case LocalStiffness::Isotropic:
      return "Isotropic";
    case LocalStiffness::Linearized:
      return "Linearized";
    case LocalStiffness::AxisProjected:
      return "AxisProjected";
    case LocalStiffness::PaperLiteral:
      return "PaperLiteral";
  }
  return "unknown";
}

const char* to_string(BoundaryMethod method) {
  switch (method) {
    case BoundaryMethod::Elimination:
      return "Elimination";
    case BoundaryMethod::RowReplacement:
      return "RowReplacement";
  }
  return "unknown";
}

namespace {

bool uses_positions(LocalStiffness mode) {
  return mode == LocalStiffness::Linearized || mode == LocalStiffness::AxisProjected;
}

void validate_settings(const LocalSettings& s) {
  require_nonnegative(s.return_stiffness, "local deformation: return_stiffness");
  require_positive(s.pivot_tolerance, "local deformation: pivot_tolerance");
  require(s.sparse_threshold >= 0, "local deformation: sparse_threshold must be >= 0 (got ",
          s.sparse_threshold, ")");
}

void validate_patch(const LocalPatch& p) {
  const Index P = p.size();
  require(P > 0, "local patch: no nodes");
  require(static_cast<Index>(p.fixed.size()) == P, "local patch: fixed flags have ", p.fixed.size(),
          " entries for ", P, " nodes");
  require_index(p.contact_local, P, "local patch: contact_local");
  require(p.nodes[p.contact_local] == p.contact, "local patch: nodes[", p.contact_local,
          "] = ", p.nodes[p.contact_local], " is not the contact node ", p.contact);
  require(p.k.size() == p.springs.rows(), "local patch: ", p.k.size(), " stiffnesses for ", p.springs.rows(),
          " springs");
  for (Index s = 0; s < p.num_springs(); ++s) {
    const Index a = p.springs(s, 0), b = p.springs(s, 1);
    require(a >= 0 && a < P && b >= 0 && b < P, "local patch: springs[", s, "] = (", a, ", ", b,
            ") out of range [0, ", P, ")");
    require(a != b, "local patch: springs[", s, "] joins node ", a, " to itself");
    require(std::isfinite(p.k(s)) && p.k(s) > 0.0, "local patch: k[", s, "]: must be > 0 (got ", p.k(s), ")");
  }
  Index f = 0;
  for (Index a = 0; a < P; ++a)
    if (p.fixed[a] == 0) {
      require(f < p.num_free() && p.free_nodes[f] == a, "local patch: free_nodes does not list free node ",
              a);
      ++f;
    }
  require(f == p.num_free(), "local patch: free_nodes lists ", p.num_free(), " nodes, ", f, " are free");
}

// Unit direction of patch spring s from the positions X (global rows).
Vec3 spring_direction(const LocalPatch& p, const MatX3& X, Index s, LocalStiffness mode) {
  const Index ga = p.nodes[p.springs(s, 0)], gb = p.nodes[p.springs(s, 1)];
  const Vec3 e = X.row(gb).transpose() - X.row(ga).transpose();
  const double L = e.norm();
  require(std::isfinite(L) && L > 0.0, "local deformation (", to_string(mode), "): spring ", s, " (nodes ",
          ga, "-", gb, ") has zero length or non-finite positions; its direction is undefined");
  return e / L;
}

[[noreturn]] void throw_singular(const LocalSettings& s, double pivot, double max_abs_K) {
  const char* cause = nullptr;
  if (uses_positions(s.stiffness) && s.return_stiffness == 0.0)
    cause =
        "no return-spring term (return_stiffness = 0): a flat patch has zero stiffness normal to its plane "
        "and "
        "cannot resist an out-of-plane force; set return_stiffness > 0 or use Isotropic";
  else if (uses_positions(s.stiffness))
    cause = "the spring directions and return springs leave a displacement mode without stiffness";
  else if (s.stiffness == LocalStiffness::PaperLiteral)
    cause = "the paper-literal (non-symmetric) matrix is singular for this patch";
  else
    cause =
        "some free nodes are not connected to any fixed node (the patch covers a whole mesh component with "
        "no "
        "fixed node)";
  throw SolverError(cat("local deformation (", to_string(s.stiffness), ", ", to_string(s.boundary),
                        "): singular patch stiffness (pivot ", pivot, " <= ", s.pivot_tolerance,
                        " x max|K| = ", s.pivot_tolerance * max_abs_K, ") - ", cause));
}

// §6.4: a pivot at or below tol x max|K| means singular. signed_pivots: LDLT's D must be positive.
void check_pivots(const VecX& pivots, double max_abs_K, const LocalSettings& s, bool signed_pivots) {
  const double tol = s.pivot_tolerance * max_abs_K;
  for (Index i = 0; i < pivots.size(); ++i) {
    const double d = signed_pivots ? pivots(i) : std::abs(pivots(i));
    if (!(d > tol)) throw_singular(s, pivots(i), max_abs_K);
  }
}

}  // namespace

Eigen::MatrixXd local_stiffness_matrix(const LocalPatch& patch, const MatX3& X,
                                       const LocalSettings& settings) {
  validate_patch(patch);
  validate_settings(settings);
  const LocalStiffness mode = settings.stiffness;
  const Index P = patch.size();
  if (uses_positions(mode)) {
    const Index max_node = *std::max_element(patch.nodes.begin(), patch.nodes.end());
    require(X.rows() > max_node, "local deformation (", to_string(mode), "): positions have ", X.rows(),
            " rows, the patch uses node ", max_node);
  }
  const Eigen::Index n3 = 3 * static_cast<Eigen::Index>(P);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n3, n3);
  for (Index s = 0; s < patch.num_springs(); ++s) {
    const Index a = patch.springs(s, 0), b = patch.springs(s, 1);
    const double k = patch.k(s);
    const Index i = 3 * a, j = 3 * b;
    switch (mode) {
      case LocalStiffness::Isotropic:  // D-16: K = L (x) I3
        for (Index al = 0; al < 3; ++al) {
          K(i + al, i + al) += k;
          K(j + al, j + al) += k;
          K(i + al, j + al) -= k;
          K(j + al, i + al) -= k;
        }
        break;
      case LocalStiffness::Linearized:
      case LocalStiffness::AxisProjected: {  // §6.2 readings (c) and (b)
        const Vec3 n = spring_direction(patch, X, s, mode);
        Mat3 B = Mat3::Zero();
        for (Index r = 0; r < 3; ++r)
          for (Index q = r; q < 3; ++q)
            if (r == q || mode == LocalStiffness::Linearized)
              B(r, q) = B(q, r) = k * (n(r) * n(q));  // exactly symmetric
        K.block<3, 3>(i, i) += B;
        K.block<3, 3>(j, j) += B;
        K.block<3, 3>(i, j) -= B;
        K.block<3, 3>(j, i) -= B;
        break;
      }
      case LocalStiffness::PaperLiteral: {  // the 12 printed assignments, verbatim; kx = ky = kz = k
        // Local ends are ordered so that nodes[a] < nodes[b] ("a < b by node index").
        K(i, i) += k;
        K(i + 1, i + 1) += k;
        K(i + 2, i + 2) += k;
        K(j, j) += k;
        K(j + 1, j + 1) += k;
        K(j + 2, j + 2) += k;
        K(i, j) = -k;
        K(j + 1, i + 1) = -k;
        K(j + 2, i + 2) = -k;
        K(j, i) = +k;
        K(i + 1, j + 1) = +k;
        K(i + 2, j + 2) = +k;
        break;
      }
    }
  }
  if (uses_positions(mode))
    for (Index r = 0; r < 3 * P; ++r) K(r, r) += settings.return_stiffness;  // k_r I per node (§6.2)
  return K;
}

void LocalSolver::precompute(const LocalPatch& patch, const MatX3& X, const LocalSettings& settings) {
  ready_ = false;
  path_ = Path::None;
  validate_settings(settings);
  validate_patch(patch);
  settings_ = settings;
  P_ = patch.size();
  g_.resize(0);
  block_node_.clear();
  if (patch.trivial()) {  // §6.1: contact fixed or no free node => U = 0
    path_ = Path::Zero;
  } else if (settings.stiffness == LocalStiffness::Isotropic) {
    precompute_isotropic(patch);
  } else {
    precompute_vector(patch, X);
  }
  ready_ = true;
}

// §6.4 isotropic: K = L (x) I3 decouples; solve the scalar system L_ff g = e_c once.
void LocalSolver::precompute_isotropic(const LocalPatch& patch) {
  const Index P = patch.size(), c = patch.contact_local;
  VecX degree = VecX::Zero(P);
  for (Index s = 0; s < patch.num_springs(); ++s) {
    degree(patch.springs(s, 0)) += patch.k(s);
    degree(patch.springs(s, 1)) += patch.k(s);
  }
  const double max_abs_K = degree.maxCoeff();  // the diagonal dominates every row of L
  g_ = VecX::Zero(P);

  if (settings_.boundary == BoundaryMethod::RowReplacement) {
    Eigen::MatrixXd L = Eigen::MatrixXd::Zero(P, P);
    for (Index s = 0; s < patch.num_springs(); ++s) {
      const Index a = patch.springs(s, 0), b = patch.springs(s, 1);
      const double k = patch.k(s);
      L(a, a) += k;
      L(b, b) += k;
      L(a, b) -= k;
      L(b, a) -= k;
    }
    VecX e = VecX::Zero(P);
    e(c) = 1.0;
    for (Index a = 0; a < P; ++a)
      if (patch.fixed[a] != 0) {  // §6.3: zero the row, K_ii = 1, F_i = 0
        L.row(a).setZero();
        L(a, a) = 1.0;
        e(a) = 0.0;
      }
    Eigen::PartialPivLU<Eigen::MatrixXd> lu(L);
    check_pivots(lu.matrixLU().diagonal(), max_abs_K, settings_, false);
    g_ = lu.solve(e);
    path_ = Path::Green;
    return;
  }

  std::vector<Index> fidx(static_cast<std::size_t>(P), -1);
  const Index nf = patch.num_free();
  for (Index f = 0; f < nf; ++f) fidx[patch.free_nodes[f]] = f;
  VecX e = VecX::Zero(nf), gf;
  e(fidx[c]) = 1.0;
  if (nf <= settings_.sparse_threshold) {
    Eigen::MatrixXd Lff = Eigen::MatrixXd::Zero(nf, nf);
    for (Index s = 0; s < patch.num_springs(); ++s) {
      const Index fa = fidx[patch.springs(s, 0)], fb = fidx[patch.springs(s, 1)];
      const double k = patch.k(s);
      if (fa >= 0) Lff(fa, fa) += k;
      if (fb >= 0) Lff(fb, fb) += k;
      if (fa >= 0 && fb >= 0) {
        Lff(fa, fb) -= k;
        Lff(fb, fa) -= k;
      }
    }
    Eigen::LDLT<Eigen::MatrixXd> ldlt(Lff);
    if (ldlt.info() != Eigen::Success) throw_singular(settings_, 0.0, max_abs_K);
    check_pivots(ldlt.vectorD(), max_abs_K, settings_, true);
    gf = ldlt.solve(e);
  } else {
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(4 * static_cast<std::size_t>(patch.num_springs()));
    for (Index s = 0; s < patch.num_springs(); ++s) {
      const Index fa = fidx[patch.springs(s, 0)], fb = fidx[patch.springs(s, 1)];
      const double k = patch.k(s);
      if (fa >= 0) t.emplace_back(fa, fa, k);
      if (fb >= 0) t.emplace_back(fb, fb, k);
      if (fa >= 0 && fb >= 0) {
        t.emplace_back(fa, fb, -k);
        t.emplace_back(fb, fa, -k);
      }
    }
    Eigen::SparseMatrix<double> Lff(nf, nf);
    Lff.setFromTriplets(t.begin(), t.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(Lff);
    if (ldlt.info() != Eigen::Success) throw_singular(settings_, 0.0, max_abs_K);
    check_pivots(ldlt.vectorD(), max_abs_K, settings_, true);
    gf = ldlt.solve(e);
  }
  for (Index f = 0; f < nf; ++f) g_(patch.free_nodes[f]) = gf(f);
  path_ = Path::Green;
}

// §6.4 other modes: dense 3n_f (or 3P with row replacement) system, factored once.
void LocalSolver::precompute_vector(const LocalPatch& patch, const MatX3& X) {
  const Index P = patch.size(), c = patch.contact_local;
  const Eigen::MatrixXd K = local_stiffness_matrix(patch, X, settings_);
  const double max_abs_K = K.cwiseAbs().maxCoeff();
  const bool spd = settings_.stiffness != LocalStiffness::PaperLiteral;

  if (settings_.boundary == BoundaryMethod::RowReplacement) {
    Eigen::MatrixXd Kr = K;
    for (Index a = 0; a < P; ++a)
      if (patch.fixed[a] != 0)
        for (Index al = 0; al < 3; ++al) {  // §6.3: zero the row, K_ii = 1 (F_i = 0 in solve)
          Kr.row(3 * a + al).setZero();
          Kr(3 * a + al, 3 * a + al) = 1.0;
        }
    lu_.compute(Kr);
    check_pivots(lu_.matrixLU().diagonal(), max_abs_K, settings_, false);
    block_node_.resize(static_cast<std::size_t>(P));
    for (Index a = 0; a < P; ++a) block_node_[a] = a;
    c_dof_ = 3 * c;
    path_ = Path::DenseLU;
  } else {
    const Index nf = patch.num_free();
    block_node_.assign(patch.free_nodes.begin(), patch.free_nodes.end());
    Eigen::MatrixXd Kff(3 * nf, 3 * nf);
    for (Index f = 0; f < nf; ++f)
      for (Index h = 0; h < nf; ++h)
        Kff.block<3, 3>(3 * Eigen::Index{f}, 3 * Eigen::Index{h}) =
            K.block<3, 3>(3 * Eigen::Index{block_node_[f]}, 3 * Eigen::Index{block_node_[h]});
    c_dof_ =
        3 * static_cast<Index>(std::find(block_node_.begin(), block_node_.end(), c) - block_node_.begin());
    if (spd) {
      ldlt_.compute(Kff);
      if (ldlt_.info() != Eigen::Success) throw_singular(settings_, 0.0, max_abs_K);
      check_pivots(ldlt_.vectorD(), max_abs_K, settings_, true);
      path_ = Path::DenseLDLT;
    } else {
      lu_.compute(Kff);
      check_pivots(lu_.matrixLU().diagonal(), max_abs_K, settings_, false);
      path_ = Path::DenseLU;
    }
  }
  const Index m = 3 * static_cast<Index>(block_node_.size());
  rhs_ = VecX::Zero(m);
  x_ = VecX::Zero(m);
}

LocalSolveInfo LocalSolver::solve(const Vec3& F, MatX3& U) {
  LocalSolveInfo info;
  info.note = note();
  if (!ready_) {
    info.zero = true;
    return info;
  }
  if (U.rows() != P_) U.resize(P_, 3);
  switch (path_) {
    case Path::None:
    case Path::Zero:
      U.setZero();
      info.zero = true;
      break;
    case Path::Green:  // U_a = g_a F
      for (Index a = 0; a < P_; ++a) U.row(a) = g_(a) * F.transpose();
      break;
    case Path::DenseLDLT:
    case Path::DenseLU: {
      rhs_.setZero();
      rhs_.segment<3>(c_dof_) = F;  // §6.3: F[3c + alpha] = F_alpha, F_i = 0 on fixed rows
      if (path_ == Path::DenseLDLT)
        x_ = ldlt_.solve(rhs_);
      else
        x_ = lu_.solve(rhs_);
      U.setZero();
      for (std::size_t b = 0; b < block_node_.size(); ++b)
        U.row(block_node_[b]) = x_.segment<3>(3 * static_cast<Eigen::Index>(b)).transpose();
      break;
    }
  }
  return info;
}

}  // namespace medspring
