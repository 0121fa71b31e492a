// The spring term of the force pass (eqs. 1 and 5, §1.3), shared by the serial pass (forces.cpp) and the
// threaded step (integrators.cpp) so that both evaluate every spring with the same arithmetic.
#pragma once

#include <cmath>

#include "medspring/physics/kernels.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/physics/state.hpp"

namespace medspring {
struct ParallelRecords;  // volume_f32.hpp
}

namespace medspring::detail {

inline constexpr double kMinSpringLength =
    hd::kMinSpringLength;  // §1.3: springs shorter than this are skipped

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

/// Force on node i of spring s (minus that on node j) into (fx, fy, fz); false for a spring shorter than
/// kMinSpringLength (no force). With Stiff, stiff = max(stiff, kappa_s / k_s). The arithmetic is
/// hd::spring_force (kernels.hpp), which the CUDA kernels use too.
template <bool Soft, bool Stiff>
inline bool spring_force(const SpringArrays& S, Index s, const double* x, double& stiff, double& fx,
                         double& fy, double& fz) {
  const Index a = 3 * S.I[s], b = 3 * S.J[s];
  return hd::spring_force<Soft, Stiff>(x[b] - x[a], x[b + 1] - x[a + 1], x[b + 2] - x[a + 2], S.L0[s], S.K[s],
                                       S.KP[s], S.IK[s], stiff, fx, fy, fz);
}

/// Adds spring s's force to both of its nodes in f (+ on I[s], - on J[s]); the serial scatter of every
/// spring pass (forces.cpp, the threaded step's inner springs).
template <bool Soft, bool Stiff>
inline void add_spring_force(const SpringArrays& S, Index s, const double* x, double& stiff, double* f) {
  double fx, fy, fz;
  if (!spring_force<Soft, Stiff>(S, s, x, stiff, fx, fy, fz)) return;
  const Index a = 3 * S.I[s], b = 3 * S.J[s];
  f[a] += fx;
  f[a + 1] += fy;
  f[a + 2] += fz;
  f[b] -= fx;
  f[b + 1] -= fy;
  f[b + 2] -= fz;
}

/// f = f_ext - k_r (x - x0) on nodes [a0, a1).
inline void return_forces(const Model& m, const double* X, const double* FE, double* Fo, Index a0, Index a1) {
  const double* X0 = m.x0.data();
  const double* KR = m.kr.data();
  for (Index a = a0; a < a1; ++a) {
    const Index q = 3 * a;
    hd::return_force(FE + q, X + q, X0 + q, KR[a], Fo + q);
  }
}

/// Undoes the symplectic update of the free nodes fr[0 .. count) (the guard, §2.5), from the forces in
/// st.f and the coefficients st.step_coef: x_old = x - h v, v_old = (v / c - h g) / m.
inline void undo_symplectic(const Model& m, State& st, double h, const Index* fr, Index count) {
  const double* G = st.f.data();
  const double* Mv = m.mass.data();
  const double* C = st.step_coef.data();
  double* X = st.x.data();
  double* V = st.v.data();
  for (Index r = 0; r < count; ++r) {
    const Index b = fr[r], p = 3 * b;
    for (int d = 0; d < 3; ++d) {
      X[p + d] -= h * V[p + d];
      V[p + d] = (V[p + d] / C[b] - h * G[p + d]) / Mv[b];
    }
  }
}

/// One symplectic Euler substep with implicit diagonal damping (§2.1) of the free nodes fr[0 .. nf), forces
/// in st.f, coefficients st.step_coef refreshed for h. Returns 0 (ok), or 1 (a velocity over v_max) / 2
/// (non-finite) with Guard, after restoring the nodes already advanced (undo_symplectic).
template <bool Guard>
int advance_nodes(const Model& m, State& st, double h, double vmax2, const Index* fr, Index nf) {
  const double* G = st.f.data();
  const double* Mv = m.mass.data();
  const double* C = st.step_coef.data();
  double* X = st.x.data();
  double* V = st.v.data();
  for (Index k = 0; k < nf; ++k) {
    const Index a = fr[k], q = 3 * a;
    double vn[3];
    const double v2 = hd::symplectic_velocity(Mv[a], C[a], h, V + q, G + q, vn);
    if constexpr (Guard) {
      if (!hd::velocity_ok(v2, vmax2)) {  // also catches NaN
        undo_symplectic(m, st, h, fr, k);
        return std::isfinite(v2) ? 1 : 2;
      }
    }
    V[q] = vn[0];
    V[q + 1] = vn[1];
    V[q + 2] = vn[2];
    hd::symplectic_position(h, X + q, vn, X + q);
  }
  return 0;
}

/// internal_forces (forces.hpp) with the stiffening max computed only when `stiffening` (else 1 is
/// returned): the step needs it from the last force evaluation of a frame only.
double internal_forces(const Model& m, const MatX3& x, const MatX3& f_ext, MatX3& f, bool stiffening);
/// The local stiffening of a model with volume terms (issue 23, docs/volumetric-speed.md "Stable step"):
/// scratch of stiff_rows_size(#N, #T, #C) doubles (State::stiff_rows: #N + #T for the volume terms' rule, 6
/// #N for the compression terms' bound after it), and the frame step and safety of the step that will use the
/// stiffening.
struct LocalStiffening {
  double* scratch;
  double frame_dt;
  double safety;
  float* f32 = nullptr;  // State::volume_f32 (the single-precision volume pass, Model::volume_f32), or null
  const ParallelRecords* par =
      nullptr;  // the threaded step's (threaded_volume.hpp): the float pass's threads
};
/// The same, and with `local` (and stiffening) the local stiffening of the volume terms: the returned
/// stiffening is min(max(s_springs, s_terms), s_springs + row_max / omega_rest^2) (add_volume_forces_local)
/// where that asks for fewer sub-steps of local->frame_dt than the global rule max(s_springs, s_terms);
/// else (the local value, never below s_springs, could not save a sub-step: the global rule asks for no
/// more than s_springs does) the global rule, without the scatter of the local rows.
double internal_forces(const Model& m, const MatX3& x, const MatX3& f_ext, MatX3& f, bool stiffening,
                       const LocalStiffening* local);
/// The volume terms' part of internal_forces: adds their forces to Fo (flat 3N) and returns the stiffening
/// of springs (s_springs = `stiff`) and terms together by the rule above (s_springs without `stiffening`).
double volume_forces(const Model& m, const double* X, double* Fo, bool stiffening, double stiff,
                     const LocalStiffening* local);
/// Whether the volume pass of a sub-step without the stable step's bound takes the float pass
/// (Model::volume_f32, volume_f32.hpp): it then leaves the displacement mirror in local->f32.
bool volume_f32_substep(const Model& m, const LocalStiffening* local);

}  // namespace medspring::detail
