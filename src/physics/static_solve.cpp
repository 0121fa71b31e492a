#include "medspring/physics/static_solve.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/physics/forces.hpp"

namespace medspring {

namespace {

// Total potential Pi(x) = V(x) - f_ext . (x - x0), whose stationary points are the equilibria.
double total_potential(const Model& m, const MatX3& x, const MatX3& f_ext) {
  return potential_energy(m, x) - (f_ext.array() * (x - m.x0).array()).sum();
}

// The compressed sparsity pattern a symbolic factorisation was computed for.
struct SparsePattern {
  std::vector<int> outer, inner;
};

bool same_pattern(const Eigen::SparseMatrix<double>& A, const SparsePattern& p) {
  return static_cast<Eigen::Index>(p.outer.size()) == A.outerSize() + 1 &&
         static_cast<Eigen::Index>(p.inner.size()) == A.nonZeros() &&
         std::equal(p.outer.begin(), p.outer.end(), A.outerIndexPtr()) &&
         std::equal(p.inner.begin(), p.inner.end(), A.innerIndexPtr());
}

}  // namespace

// Newton-Raphson on r(x) = f_ext + f_int(x) = 0 over the free DOFs (§2.4) with the full tangent
// stiffness. Where K_ff is not positive definite (e.g. zero transverse stiffness of a straight chain
// at rest) it is shifted by mu I (Levenberg-Marquardt), and steps are accepted by an Armijo
// backtracking line search on the total potential.
StaticResult static_equilibrium(const Model& m, const MatX3& f_ext, const StaticSettings& s,
                                const MatX3& x_start) {
  const Index n = m.num_nodes();
  require(f_ext.rows() == n && f_ext.cols() == 3, m.name, ": static solve: f_ext must be ", n, " x 3");
  require(f_ext.allFinite(), m.name, ": static solve: f_ext must be finite");
  StaticResult res;
  res.x = x_start.rows() == n ? x_start : m.x0;
  for (Index a = 0; a < n; ++a)
    if (m.fixed[a]) res.x.row(a) = m.x0.row(a);
  // free DOF numbering
  std::vector<Index> dof;
  for (Index a : m.free_nodes)
    for (int d = 0; d < 3; ++d) dof.push_back(3 * a + d);
  const Index nf = static_cast<Index>(dof.size());
  if (nf == 0) return res;
  std::vector<Index> map(static_cast<std::size_t>(3 * n), -1);
  for (Index q = 0; q < nf; ++q) map[dof[q]] = q;
  MatX3 f(n, 3);
  auto residual = [&](const MatX3& x, VecX& r) {
    internal_forces(m, x, f_ext, f);
    double rmax = 0;
    for (Index a : m.free_nodes) rmax = std::max(rmax, f.row(a).norm());
    for (Index q = 0; q < nf; ++q) r[q] = f.data()[dof[q]];
    return rmax;
  };
  VecX r(nf);
  res.residual = residual(res.x, r);
  double mu = 0.0;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  SparsePattern pattern;
  // modified Newton (s.reuse_tangent): the factorised tangent is kept while each step cuts the residual by
  // the factor s.reuse_rate; a step that does not, or fails the line search, refactors at the current x
  bool factored = false, stale = true;
  int last_factor_iteration = -1;
  double mu_min = 0;
  for (int it = 0; it < s.max_iterations && res.residual > s.tolerance; ++it) {
    res.iterations = it + 1;
    VecX dx;
    if (factored && !stale && s.reuse_tangent) {
      dx = ldlt.solve(r);
      if (!dx.allFinite()) {
        stale = true;
        continue;
      }
    } else {
      const Eigen::SparseMatrix<double> K =
          tangent_stiffness(m, res.x, {.clamp_transverse = false, .include_return = true});
      std::vector<Eigen::Triplet<double>> T;
      T.reserve(static_cast<std::size_t>(K.nonZeros()));
      double kmax = 0;
      for (int c = 0; c < K.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator e(K, c); e; ++e) {
          const Index rr = map[e.row()], cc = map[e.col()];
          if (rr >= 0 && cc >= 0) {
            T.emplace_back(rr, cc, e.value());
            if (rr == cc) kmax = std::max(kmax, std::abs(e.value()));
          }
        }
      Eigen::SparseMatrix<double> Kff(nf, nf);
      Kff.setFromTriplets(T.begin(), T.end());
      Eigen::SparseMatrix<double> I(nf, nf);
      I.setIdentity();
      mu_min = 1e-10 * std::max(kmax, 1e-12);
      mu = mu > 0 ? mu * 0.1 : 0.0;
      for (int tries = 0; tries < 60; ++tries) {
        // Kff + mu I always (mu = 0 keeps an explicit diagonal), so the pattern is the same on every try and
        // Newton iteration: the fill-reducing ordering and symbolic analysis are done once per solve and
        // only redone if the tangent's pattern changes (a spring graph whose pattern moves with x).
        Eigen::SparseMatrix<double> A = Kff + mu * I;
        A.makeCompressed();
        if (!same_pattern(A, pattern)) {
          ldlt.analyzePattern(A);
          pattern.outer.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1);
          pattern.inner.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
        }
        ldlt.factorize(A);
        bool pd = ldlt.info() == Eigen::Success && (ldlt.vectorD().array() > 0).all();
        if (pd) {
          dx = ldlt.solve(r);
          if (dx.allFinite()) break;
        }
        mu = std::max(mu * 10.0, mu_min);
        dx.resize(0);
      }
      if (dx.size() != nf)
        throw SolverError(cat(m.name, ": static solve: tangent stiffness could not be factored"));
      factored = true;
      stale = false;
      last_factor_iteration = it;
    }
    // Armijo backtracking on the total potential (r = -grad Pi, so dx is a descent direction).
    const double pi0 = total_potential(m, res.x, f_ext);
    const double slope = -r.dot(dx);
    double alpha = 1.0;
    MatX3 xt = res.x;
    bool accepted = false;
    for (int bt = 0; bt < s.max_backtracks; ++bt) {
      xt = res.x;
      for (Index q = 0; q < nf; ++q) xt.data()[dof[q]] += alpha * dx[q];
      const double pit = total_potential(m, xt, f_ext);
      if (std::isfinite(pit) && pit <= pi0 + 1e-4 * alpha * slope + 1e-15 * std::abs(pi0)) {
        accepted = true;
        break;
      }
      alpha *= 0.5;
    }
    if (!accepted) {
      // near the solution round-off dominates Pi: accept a full step if it reduces the residual
      xt = res.x;
      for (Index q = 0; q < nf; ++q) xt.data()[dof[q]] += dx[q];
      VecX rt(nf);
      if (residual(xt, rt) >= res.residual) {
        stale = true;  // refactor; a freshly factored tangent whose step failed is shifted as well
        if (last_factor_iteration == it) mu = std::max(mu * 10.0, mu_min);
        continue;
      }
    }
    const double previous = res.residual;
    res.x = xt;
    res.residual = residual(res.x, r);
    if (s.reuse_tangent && res.residual > s.reuse_rate * previous) stale = true;
    if (alpha == 1.0 && mu > 0) mu *= 0.1;
  }
  if (!(res.residual <= s.tolerance))
    throw SolverError(
        cat(m.name, ": static solve: no equilibrium found after ", res.iterations,
            " iterations (max residual ", res.residual,
            " N); the load may exceed what the springs can carry (e.g. a soft spring past its peak)"));
  return res;
}

}  // namespace medspring
