// The spring term of the force pass (eqs. 1 and 5, §1.3), shared by the serial pass (forces.cpp) and the
// threaded step (integrators.cpp) so that both evaluate every spring with the same arithmetic.
#pragma once

#include <algorithm>
#include <cmath>

#include "medspring/physics/model.hpp"

namespace medspring::detail {

inline constexpr double kMinSpringLength = 1e-9;  // §1.3: springs shorter than this are skipped

/// Raw pointers to the spring arrays of a model.
struct SpringArrays {
  const Index* I;
  const Index* J;
  const double* L0;
  const double* K;
  const double* KP;
  const double* IK;  // 1/k (0 for k = 0)
  explicit SpringArrays(const Model& m)
      : I(m.springs.i.data()),
        J(m.springs.j.data()),
        L0(m.springs.L0.data()),
        K(m.springs.k.data()),
        KP(m.springs.kp.data()),
        IK(m.inv_k.data()) {}
};

/// Force on node j of spring s (minus that on node i) into (fx, fy, fz); false for a spring shorter than
/// kMinSpringLength (no force). With Stiff, stiff = max(stiff, kappa_s / k_s).
template <bool Soft, bool Stiff>
inline bool spring_force(const SpringArrays& S, Index s, const double* x, double& stiff, double& fx,
                         double& fy, double& fz) {
  const Index a = 3 * S.I[s], b = 3 * S.J[s];
  const double ex = x[b] - x[a], ey = x[b + 1] - x[a + 1], ez = x[b + 2] - x[a + 2];
  const double L2 = ex * ex + ey * ey + ez * ez;
  if (L2 < kMinSpringLength * kMinSpringLength) return false;
  const double L = std::sqrt(L2);
  const double inv = 1.0 / L;
  const double d = L - S.L0[s];
  const double k = S.K[s], kp = S.KP[s];
  double phi, dphi;
  if constexpr (Soft) {
    phi = spring_tension(k, kp, d);
    dphi = spring_tension_derivative(k, kp, d);
  } else {
    const double kp_d2 = kp * d * d;
    phi = d * (k + kp_d2);  // eq. (5)
    dphi = k + 3.0 * kp_d2;
  }
  const double t = phi * inv;  // phi / L
  if constexpr (Stiff) stiff = std::max(stiff, std::max(dphi, std::abs(t)) * S.IK[s]);
  fx = t * ex;
  fy = t * ey;
  fz = t * ez;
  return true;
}

/// f = f_ext - k_r (x - x0) on nodes [a0, a1).
inline void return_forces(const Model& m, const double* X, const double* FE, double* Fo, Index a0, Index a1) {
  const double* X0 = m.x0.data();
  const double* KR = m.kr.data();
  for (Index a = a0; a < a1; ++a) {
    const double kr = KR[a];
    const Index q = 3 * a;
    Fo[q] = FE[q] - kr * (X[q] - X0[q]);
    Fo[q + 1] = FE[q + 1] - kr * (X[q + 1] - X0[q + 1]);
    Fo[q + 2] = FE[q + 2] - kr * (X[q + 2] - X0[q + 2]);
  }
}

/// internal_forces (forces.hpp) with the stiffening max computed only when `stiffening` (else 1 is
/// returned): the step needs it from the last force evaluation of a frame only.
double internal_forces(const Model& m, const MatX3& x, const MatX3& f_ext, MatX3& f, bool stiffening);

}  // namespace medspring::detail
