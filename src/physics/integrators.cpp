#include "medspring/physics/integrators.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "compression_rows.hpp"
#include "linear_static_step.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/parallel.hpp"
#include "medspring/physics/stability.hpp"
#include "spring_gather.hpp"
#include "spring_kernel.hpp"
#include "stiffness_product.hpp"
#include "threaded_step.hpp"
#include "volume_f32.hpp"

namespace medspring {

Integrator parse_integrator(const std::string& text) {
  if (text == "symplectic_euler" || text == "symplectic" || text == "SymplecticEuler")
    return Integrator::SymplecticEuler;
  if (text == "implicit_euler" || text == "implicit" || text == "ImplicitEuler")
    return Integrator::ImplicitEuler;
  if (text == "linear_static" || text == "LinearStatic") return Integrator::LinearStatic;
  throw InvalidInput(cat("integrator: unknown value '", text,
                         "' (expected symplectic_euler, implicit_euler or linear_static)"));
}

std::string to_string(Integrator integrator) {
  switch (integrator) {
    case Integrator::ImplicitEuler:
      return "implicit_euler";
    case Integrator::LinearStatic:
      return "linear_static";
    default:
      return "symplectic_euler";
  }
}

StableStep parse_stable_step(const std::string& text) {
  if (text == "bound" || text == "Bound") return StableStep::Bound;
  if (text == "refresh" || text == "Refresh") return StableStep::Refresh;
  throw InvalidInput(cat("stable_step: unknown value '", text, "' (expected bound or refresh)"));
}

std::string to_string(StableStep rule) {
  return rule == StableStep::Refresh ? "refresh" : "bound";
}

void validate_step_settings(const Model& model, const StepSettings& s) {
  static_assert(kMaxThreads == 256, "StepSettings::threads is declared 1..256 in integrators.hpp");
  validate_params(s, "step");  // the ranges declared in integrators.hpp
  if (!s.substep && s.integrator == Integrator::SymplecticEuler) {
    const double bound = model.dt_safe_rest(s.safety);
    require(s.dt <= bound, "step.dt: ", s.dt, " ms is above the stable step ", bound, " ms of model '",
            model.name, "' (sub-stepping is off; enable it or use a smaller dt)");
  }
}

namespace {

// Outcome of one guarded substep (§2.5).
enum class Substep { Ok, TooFast, NonFinite };
static_assert(static_cast<int>(Substep::TooFast) == 1 &&
              static_cast<int>(Substep::NonFinite) == 2);  // advance_nodes

// 1 / (m + h d) per node for the substep h (cached while h stays the same).
void refresh_step_coefficients(const Model& m, State& st, double h) {
  if (st.step_coef_h != h) {
    for (Index a = 0; a < m.num_nodes(); ++a)
      st.step_coef[a] = hd::step_coefficient(m.mass[a], m.damping[a], h);
    st.step_coef_h = h;
  }
}

using detail::undo_symplectic;

// One symplectic Euler substep of the free nodes fr[0 .. nf) (detail::advance_nodes, spring_kernel.hpp).
template <bool Guard>
Substep symplectic_range(const Model& m, State& st, double h, double vmax2, const Index* fr, Index nf) {
  return static_cast<Substep>(detail::advance_nodes<Guard>(m, st, h, vmax2, fr, nf));
}

template <bool Guard>
Substep symplectic_substep(const Model& m, State& st, double h, double vmax2) {
  refresh_step_coefficients(m, st, h);
  return symplectic_range<Guard>(m, st, h, vmax2, m.free_nodes.data(),
                                 static_cast<Index>(m.free_nodes.size()));
}

// Per-spring coefficients of K_s = a n n^T + b I at x with the transverse clamp (§2.3).
void spring_coefficients(const Model& m, const MatX3& x, State& st) {
  const Springs& S = m.springs;
  for (Index s = 0; s < S.size(); ++s) {
    const Vec3 e = (x.row(S.j[s]) - x.row(S.i[s])).transpose();
    const double L = e.norm();
    if (L < 1e-9) {
      st.spring_a[s] = st.spring_b[s] = 0.0;
      st.spring_n.row(s).setZero();
      continue;
    }
    const double d = L - S.L0[s];
    const double b = std::max(spring_tension(S.k[s], S.kp[s], d) / L, 0.0);
    st.spring_a[s] = spring_tension_derivative(S.k[s], S.kp[s], d) - b;
    st.spring_b[s] = b;
    st.spring_n.row(s) = (e / L).transpose();
  }
}

// y = K p (springs + bending + return springs + volume terms), matrix-free (stiffness_product.hpp), with
// the springs' coefficients of spring_coefficients.
void apply_stiffness(const Model& m, const State& st, const VecX& p, VecX& y) {
  // volume terms (issue 23): Gauss-Newton part only, so the CG system stays positive definite
  detail::stiffness_product<false>(m, st.x, nullptr, p, y, nullptr, true, [&](Index s, const Vec3& dp) {
    const Vec3 nh = st.spring_n.row(s).transpose();
    return Vec3(st.spring_a[s] * nh * nh.dot(dp) + st.spring_b[s] * dp);
  });
}

// y = (M + h D + h^2 K) p on free DOFs, 0 on fixed DOFs.
void apply_system(const Model& m, const State& st, double h, const VecX& p, VecX& y) {
  apply_stiffness(m, st, p, y);
  for (Index a = 0; a < m.num_nodes(); ++a) {
    if (m.fixed[a]) {
      y.segment<3>(3 * a).setZero();
      continue;
    }
    y.segment<3>(3 * a) = (m.mass[a] + h * m.damping[a]) * p.segment<3>(3 * a) + h * h * y.segment<3>(3 * a);
  }
}

void jacobi_diagonal(const Model& m, State& st, double h) {
  VecX& dg = st.jacobi;
  for (Index a = 0; a < m.num_nodes(); ++a) dg.segment<3>(3 * a).setConstant(m.kr[a]);
  const Springs& S = m.springs;
  for (Index s = 0; s < S.size(); ++s) {
    const Vec3 nh = st.spring_n.row(s).transpose();
    const Vec3 d = st.spring_a[s] * nh.cwiseProduct(nh) + Vec3::Constant(st.spring_b[s]);
    dg.segment<3>(3 * S.i[s]) += d;
    dg.segment<3>(3 * S.j[s]) += d;
  }
  const BendingTerms& B = m.bending;
  for (Index t = 0; t < B.size(); ++t) {
    dg.segment<3>(3 * B.a[t]).array() += B.kb[t];
    dg.segment<3>(3 * B.b[t]).array() += 4 * B.kb[t];
    dg.segment<3>(3 * B.c[t]).array() += B.kb[t];
  }
  for (Index a = 0; a < m.num_nodes(); ++a)
    dg.segment<3>(3 * a) = ((m.mass[a] + h * m.damping[a]) + h * h * dg.segment<3>(3 * a).array()).matrix();
}

// Preconditioned CG on the free DOFs; x holds the warm start on entry. Returns iterations.
int conjugate_gradient(const Model& m, State& st, double h, const VecX& b, VecX& x, double tol, int max_it,
                       bool& converged) {
  VecX& r = st.cg_r;
  VecX& z = st.cg_z;
  VecX& p = st.cg_p;
  VecX& q = st.cg_q;
  for (Index a = 0; a < m.num_nodes(); ++a)
    if (m.fixed[a]) x.segment<3>(3 * a).setZero();
  apply_system(m, st, h, x, q);
  r = b - q;
  const double bn = b.norm();
  converged = true;
  if (!std::isfinite(bn)) {  // NaN/Inf in the system: report it as a non-finite result (guard, §2.5)
    converged = false;
    x.setConstant(std::numeric_limits<double>::quiet_NaN());
    return 0;
  }
  if (bn == 0) {
    x.setZero();
    return 0;
  }
  z = r.cwiseQuotient(st.jacobi);
  p = z;
  double rz = r.dot(z);
  for (int it = 0; it < max_it; ++it) {
    if (r.norm() <= tol * bn) return it;
    apply_system(m, st, h, p, q);
    const double pq = p.dot(q);
    if (!std::isfinite(pq)) {
      converged = false;
      x.setConstant(std::numeric_limits<double>::quiet_NaN());
      return it;
    }
    if (!(pq > 0)) break;
    const double alpha = rz / pq;
    x += alpha * p;
    r -= alpha * q;
    z = r.cwiseQuotient(st.jacobi);
    const double rz_new = r.dot(z);
    p = z + (rz_new / rz) * p;
    rz = rz_new;
  }
  converged = r.norm() <= tol * bn;
  return max_it;
}

Substep state_check(const Model& m, const State& st, double vmax2) {
  Substep r = Substep::Ok;
  for (Index a : m.free_nodes) {
    const double v2 = st.v.row(a).squaredNorm();
    if (!std::isfinite(v2) || !st.x.row(a).allFinite()) return Substep::NonFinite;
    if (!(v2 <= vmax2)) r = Substep::TooFast;
  }
  return r;
}

// One linearly implicit Euler substep (§2.3), optionally followed by Newton iterations on
// R(v) = M (v - v^n) - h f(x^n + h v, v). Returns TooFast / NonFinite (state restored) if the result is
// too fast / not finite.
Substep implicit_substep(const Model& m, State& st, const StepSettings& s, double h, double vmax2,
                         int& cg_its) {
  st.x_save = st.x;
  st.v_save = st.v;
  st.stiffening = internal_forces(m, st.x, st.f_ext, st.f);
  spring_coefficients(m, st.x, st);
  jacobi_diagonal(m, st, h);
  // rhs = h (g - D v - h K v)
  apply_stiffness(m, st, flat(st.v), st.cg_q);
  for (Index a = 0; a < m.num_nodes(); ++a) {
    if (m.fixed[a]) {
      st.rhs.segment<3>(3 * a).setZero();
      continue;
    }
    st.rhs.segment<3>(3 * a) = h * (st.f.row(a).transpose() - m.damping[a] * st.v.row(a).transpose() -
                                    h * st.cg_q.segment<3>(3 * a));
  }
  bool conv = true;
  cg_its += conjugate_gradient(m, st, h, st.rhs, st.dv, s.cg_tolerance, s.cg_max_iterations, conv);
  if (!conv) ++st.warnings.cg_not_converged;
  for (Index a : m.free_nodes) st.v.row(a) += st.dv.segment<3>(3 * a).transpose();
  // Full Newton (option): iterate on R(v) with backtracking on |R|.
  auto residual =
      [&](VecX& R) {  // R = M (v - v^n) - h (g(x^n + h v) - D v), free DOFs; leaves forces in st.f
        for (Index a = 0; a < m.num_nodes(); ++a)
          st.x_trial.row(a) = st.x_save.row(a) + (m.fixed[a] ? 0.0 : h) * st.v.row(a);
        st.stiffening = internal_forces(m, st.x_trial, st.f_ext, st.f);
        double rmax = 0;
        for (Index a = 0; a < m.num_nodes(); ++a) {
          if (m.fixed[a]) {
            R.segment<3>(3 * a).setZero();
            continue;
          }
          R.segment<3>(3 * a) = m.mass[a] * (st.v.row(a) - st.v_save.row(a)).transpose() -
                                h * (st.f.row(a).transpose() - m.damping[a] * st.v.row(a).transpose());
          rmax = std::max(rmax, R.segment<3>(3 * a).norm());
        }
        return rmax;
      };
  if (s.newton_iterations > 1) {
    double rn = residual(st.rhs);
    for (int it = 1; it < s.newton_iterations && rn > 1e-10; ++it) {
      spring_coefficients(m, st.x_trial, st);
      jacobi_diagonal(m, st, h);
      st.rhs = -st.rhs;
      st.dv.setZero();
      cg_its += conjugate_gradient(m, st, h, st.rhs, st.dv, s.cg_tolerance, s.cg_max_iterations, conv);
      if (!conv) ++st.warnings.cg_not_converged;
      double alpha = 1.0;
      st.cg_p = flat(st.v);  // v_k
      for (int bt = 0; bt < 30; ++bt) {
        for (Index a : m.free_nodes)
          st.v.row(a) = st.cg_p.segment<3>(3 * a).transpose() + alpha * st.dv.segment<3>(3 * a).transpose();
        const double rt = residual(st.rhs);
        if (rt < rn || bt == 29) {
          rn = rt;
          break;
        }
        alpha *= 0.5;
      }
    }
  }
  for (Index a : m.free_nodes) st.x.row(a) = st.x_save.row(a) + h * st.v.row(a);
  const Substep r = state_check(m, st, vmax2);
  if (r != Substep::Ok) {
    st.x = st.x_save;
    st.v = st.v_save;
    st.dv.setZero();
  }
  return r;
}

}  // namespace

namespace {

// Threads of the fused node-range step (threaded_step.hpp): models without bending, volume, compression or
// thin-tetrahedron terms.
int fused_threads(const Model& m, const StepSettings& s) {
  if (!threads_supported() || s.threads <= 1 || s.integrator != Integrator::SymplecticEuler ||
      m.bending.size() > 0 || m.volume.size() > 0 || m.compression.size() > 0 || m.thin.size() > 0)
    return 1;
  const Index by_size = m.num_springs() / kMinSpringsPerThread;
  return static_cast<int>(std::max<Index>(1, std::min<Index>(std::min(s.threads, kMaxThreads), by_size)));
}

}  // namespace

int effective_threads(const Model& m, const StepSettings& s) {
  const int fused = fused_threads(m, s);
  return fused > 1 ? fused : volume_threads(m, s);  // the threaded float sub-step (threaded_volume.hpp)
}

namespace {

// The serial symplectic step of m goes through the fused node-range step: no gather pass (too many
// springs, or soft springs), no bending or volume terms.
bool fused_serial(const Model& m, const StepSettings& s) {
  return s.integrator == Integrator::SymplecticEuler && detail::fused_step_applies(m) && m.gather.empty() &&
         m.num_springs() > 0;
}

bool implicit_scratch_ready(const Model& m, const State& st) {
  return st.x_save.rows() == m.num_nodes() && st.spring_a.size() == m.num_springs() &&
         st.jacobi.size() == 3 * m.num_nodes();
}

}  // namespace

namespace {

// Lanczos products of the tangent refresh (those of omega_rest), its safety on omega (as omega_rest's), the
// band of the growth bound within which a reference stays in use, and its age limits in frames; the products
// taken per frame (the estimate is spread over kRefreshProducts frames), and how many frames before the age
// limit the next estimate starts (so that under a steady load a new reference is ready before the old one
// ages out: the products take kRefreshProducts frames).
constexpr int kRefreshProducts = 15;
constexpr double kRefreshSafety = 1.05;
constexpr double kRefreshBand = 0.02;
constexpr std::uint64_t kRefreshMaxAge = 200, kRefreshMinGap = 20;
constexpr int kRefreshProductsPerFrame = 1;
constexpr std::uint64_t kRefreshLead = 20;
static_assert(kRefreshLead * kRefreshProductsPerFrame > kRefreshProducts && kRefreshLead < kRefreshMaxAge);

// The stable step's tangent refresh (docs/volumetric-stable-step.md). B =
// st.stiffening is the growth bound of the frame's last force pass (omega^2 <= B omega_rest^2: springs' kappa
// / k, the volume terms' rows, the compression blocks, added by Weyl to the rest value). Where B asks for
// more sub-steps than the rest value does, it is replaced by the same estimate as omega_rest (15 Lanczos
// products of the exact tangent x 1.05) taken at a recent state x_r of this run, grown by B / B_r: s = s_r
// max(1, B / B_r), when smaller. The reference holds while B stays in [B_r (1 - band), B_r (1 + band)] and
// for kRefreshMaxAge frames; a frame with a rollback drops it. The estimate is amortised: it is started on a
// snapshot of the frame's end state x_r (and its B_r), one product is taken per later frame, and when its
// last product is in, it replaces the reference at once if B is still within the band of B_r (else it is
// discarded). Meanwhile the step keeps its valid rule: the old reference while it holds, else B. An estimate
// starts when the reference does not hold, or kRefreshLead frames before it ages out, at most every
// kRefreshMinGap frames. So a loaded organ under a constant load (the benchmark) keeps the sub-steps of its
// true omega without a frame that takes all the products; a moving load mostly takes B.
void refine_stiffening(const Model& m, State& st, double T, double safety, bool rolled_back) {
  ThreadedStep::TangentRefresh& r = st.threaded.p->tangent;
  if (rolled_back) {
    r.drop();
    return;
  }
  const double B = st.stiffening;
  // nothing to gain where B asks for no more sub-steps than the rest value (omega_max hardly falls below
  // its rest value under load: docs/volumetric-speed.md)
  if (stable_substeps(m, B, T, safety) <= stable_substeps(m, 1.0, T, safety) || !(m.omega_rest > 0)) return;
  const auto within = [B](double b) { return B <= b * (1 + kRefreshBand) && B >= b * (1 - kRefreshBand); };
  if (r.pending && tangent_lanczos_advance(m, kRefreshProductsPerFrame, r.scratch)) {
    r.pending = false;  // complete: the new reference, if the state is still near its snapshot
    const double w2 = tangent_lanczos_omega2(r.scratch);
    if (w2 > 0 && std::isfinite(w2) && within(r.b_snap) && st.frames - r.frame_snap < kRefreshMaxAge) {
      r.s_ref = kRefreshSafety * kRefreshSafety * w2 / (m.omega_rest * m.omega_rest);
      r.b_ref = r.b_snap;
      r.frame = r.frame_snap;
      r.valid = true;
    }
  }
  const bool fresh = r.valid && st.frames - r.frame < kRefreshMaxAge && within(r.b_ref);
  if (!r.pending && (!fresh || st.frames - r.frame + kRefreshLead >= kRefreshMaxAge) &&
      !(r.tried > 0 && st.frames + 1 - r.tried < kRefreshMinGap)) {
    tangent_lanczos_start(m, st.x, kRefreshProducts, r.scratch);  // its products: the next frames
    r.pending = true;
    r.b_snap = B;
    r.frame_snap = st.frames;
    r.tried = st.frames + 1;
  }
  if (!fresh) return;  // B as it is
  const double s = r.s_ref * std::max(1.0, B / r.b_ref);
  if (s < B) st.stiffening = s;
}

// The opt-in tangent refresh applies to a symplectic step of a model with volume or compression terms.
bool tangent_refresh_on(const Model& m, const StepSettings& s) {
  return s.integrator == Integrator::SymplecticEuler && s.stable_step == StableStep::Refresh &&
         (m.volume.size() > 0 || m.compression.size() > 0);
}

}  // namespace

void prepare_step(const Model& m, State& st, const StepSettings& s) {
  // the quasi-static linear response's factor (the rest below sizes what the other integrators' steps use
  // too, so that a state can switch integrators)
  if (s.integrator == Integrator::LinearStatic) detail::prepare_linear_static(m, st);
  if (s.integrator == Integrator::ImplicitEuler && !implicit_scratch_ready(m, st)) {
    const Index n = m.num_nodes(), ns = m.num_springs();
    st.x_save.setZero(n, 3);
    st.v_save.setZero(n, 3);
    st.x_trial.setZero(n, 3);
    for (VecX* b : {&st.cg_r, &st.cg_z, &st.cg_p, &st.cg_q, &st.dv, &st.rhs, &st.jacobi}) b->setZero(3 * n);
    st.spring_a.setZero(ns);
    st.spring_b.setZero(ns);
    st.spring_n.setZero(ns, 3);
  }
  if (s.integrator == Integrator::SymplecticEuler) detail::gather_ready(m, st);  // sizes its buffer now
  if ((m.volume.size() > 0 || m.compression.size() > 0) &&
      st.stiff_rows.size() != stiff_rows_size(m.num_nodes(), m.volume.size(), m.compression.size()))
    st.stiff_rows.setZero(stiff_rows_size(m.num_nodes(), m.volume.size(), m.compression.size()));
  if (m.volume_f32 &&
      st.volume_f32.size() != static_cast<std::size_t>(kVolumeF32ScratchPerNode * m.num_nodes()))
    st.volume_f32.assign(static_cast<std::size_t>(kVolumeF32ScratchPerNode * m.num_nodes()), 0.0f);
  const int T = fused_threads(m, s);
  // the threaded float sub-step of volumetric models (threaded_volume.hpp): its pool and partition
  if (const int TV = volume_threads(m, s); TV > 1) {
    if (!st.threaded.p || st.threaded.p->pool.size() != TV)
      st.threaded.p = std::make_shared<ThreadedStep>(TV);
    if (!st.threaded.p->volume.matches(m, TV)) st.threaded.p->volume.partition(m, st.threaded.p->pool);
  }
  if (tangent_refresh_on(m, s) &&
      T <= 1) {  // the stable step's tangent refresh (refine_stiffening): its scratch, sized now
    if (!st.threaded.p) st.threaded.p = std::make_shared<ThreadedStep>(1);
    size_tangent_scratch(m, st.threaded.p->tangent.scratch);
  }
  // one thread: the fused node-range step (threaded_step.hpp) for models beyond the gather pass
  if (T <= 1 && !fused_serial(m, s)) return;
  if (!st.threaded.p || st.threaded.p->pool.size() != T) st.threaded.p = std::make_shared<ThreadedStep>(T);
  if (!st.threaded.p->matches(m)) st.threaded.p->partition(m);
}

State make_state(const Model& m, const StepSettings& s) {
  require(m.finalized, m.name, ": model is not finalized (call finalize or ModelBuilder::build)");
  const Index n = m.num_nodes();
  State st;
  st.x = m.x0;
  st.v.setZero(n, 3);
  st.f_ext.setZero(n, 3);
  st.f.setZero(n, 3);
  st.step_coef.setZero(n);
  prepare_step(m, st, s);
  return st;
}

StepStatus step(const Model& m, State& st, const StepSettings& s, const std::vector<PointLoad>* loads,
                const SubstepForce* per_substep) {
  if (s.integrator == Integrator::LinearStatic)
    return detail::linear_static_step(m, st, s, loads, per_substep);
  StepStatus status;
  if (s.integrator == Integrator::ImplicitEuler && !implicit_scratch_ready(m, st))
    prepare_step(m, st, s);  // a state from make_state(model, symplectic settings): allocates once
  ThreadedStep* par = nullptr;
  if (s.integrator == Integrator::SymplecticEuler && (fused_threads(m, s) > 1 || fused_serial(m, s))) {
    prepare_step(m, st, s);  // allocates only on the first fused step of this state
    par = st.threaded.p.get();
  }
  // the opt-in tangent refresh (StepSettings::stable_step): a state not prepared for it is, once
  if (!par && tangent_refresh_on(m, s) && (!st.threaded.p || st.threaded.p->tangent.scratch.q.size() == 0))
    prepare_step(m, st, s);
  // the gather pass (spring_gather.hpp) for the serial symplectic step of a model that has one
  const bool gather = !par && s.integrator == Integrator::SymplecticEuler && detail::gather_ready(m, st);
  // the float volume passes on threads (threaded_volume.hpp): a state not prepared for them is, once
  const int TV = !par && s.integrator == Integrator::SymplecticEuler ? volume_threads(m, s) : 1;
  if (TV > 1 && (!st.threaded.p || st.threaded.p->pool.size() != TV || !st.threaded.p->volume.matches(m, TV)))
    prepare_step(m, st, s);
  const double T = s.dt;
  const double vmax2 = s.v_max * s.v_max;
  long subs = 1;
  if (s.integrator == Integrator::SymplecticEuler) {
    const double hs = dt_safe(m, st.stiffening, s.safety);
    if (T > hs * (1.0 + 1e-12)) {
      if (!s.substep) {
        ++st.warnings.unstable_refused;
        status.code = StepCode::Refused;
        return status;
      }
      const double need = std::ceil(T / hs);
      if (need > s.max_substeps) ++st.warnings.substeps_capped;
      subs = static_cast<long>(std::min<double>(need, s.max_substeps));
    }
  }
  // volume terms: the local stiffening (scratch sized by prepare_step; a state without it gets the global
  // rule)
  const bool f32_scratch =
      m.volume_f32 &&
      st.volume_f32.size() == static_cast<std::size_t>(kVolumeF32ScratchPerNode * m.num_nodes());
  // the threaded step's shares of the float passes (threaded_volume.hpp)
  const ParallelRecords* par_records =
      TV > 1 && f32_scratch ? st.threaded.p->volume.records_for(st) : nullptr;
  const detail::LocalStiffening local{st.stiff_rows.data(), T, s.safety,
                                      f32_scratch ? st.volume_f32.data() : nullptr, par_records};
  const detail::LocalStiffening* local_rule =
      (m.volume.size() > 0 || m.compression.size() > 0) &&
              st.stiff_rows.size() == stiff_rows_size(m.num_nodes(), m.volume.size(), m.compression.size())
          ? &local
          : nullptr;
  const double t0 = st.t;
  double h = T / static_cast<double>(subs);
  double t = t0;
  long left = subs;
  int rollbacks = 0;
  while (left > 0) {
    if (loads) accumulate_loads(*loads, t, st.f_ext);
    if (per_substep) per_substep->fn(per_substep->ctx, st, t);
    Substep r;
    if (s.integrator == Integrator::SymplecticEuler) {
      // The stiffening (max kappa/k over the springs) sets the substeps of the next frame, so only the
      // frame's last force evaluation needs it: the substep that ends the frame (left == 1) or the one
      // whose failure would end it (rollbacks == max_rollbacks). Skipping it elsewhere changes no result.
      const bool stiffening = left == 1 || rollbacks == s.max_rollbacks;
      if (par) {
        refresh_step_coefficients(m, st, h);
        r = static_cast<Substep>(detail::threaded_substep(m, st, *par, h, vmax2, s.guard, stiffening));
      } else if (gather) {
        refresh_step_coefficients(m, st, h);
        if (par_records && !stiffening && detail::float_substep_applies(m, local_rule))
          r = static_cast<Substep>(detail::threaded_volume_substep(m, st, *st.threaded.p, h, vmax2, s.guard));
        else
          r = static_cast<Substep>(detail::gather_substep(m, st, h, vmax2, s.guard, stiffening, local_rule));
      } else {
        const double stiff = detail::internal_forces(m, st.x, st.f_ext, st.f, stiffening, local_rule);
        if (stiffening) st.stiffening = stiff;
        r = s.guard ? symplectic_substep<true>(m, st, h, vmax2) : symplectic_substep<false>(m, st, h, vmax2);
      }
    } else {
      r = implicit_substep(m, st, s, h, s.guard ? vmax2 : std::numeric_limits<double>::infinity(),
                           status.cg_iterations);
    }
    if (r != Substep::Ok) {
      ++(r == Substep::NonFinite ? st.warnings.nonfinite : st.warnings.velocity_limit);
      ++st.warnings.rollbacks;
      if (++rollbacks > s.max_rollbacks) {
        // The frame is dropped: positions stay at the last valid substep, velocities are zeroed (a
        // state moving at v_max under large spring forces would otherwise fail every later frame), and
        // the clock moves to the frame end so that time-driven loops and load schedules keep going.
        ++st.warnings.failed;
        status.code = StepCode::Failed;
        if (st.threaded.p) st.threaded.p->tangent.drop();  // the tangent refresh starts again
        st.v.setZero();
        st.t = t0 + T;
        ++st.frames;
        return status;
      }
      status.code = StepCode::RolledBack;
      left *= 2;  // halve the step for the rest of the frame (§2.5 failure guard)
      h *= 0.5;
      continue;
    }
    --left;
    ++status.substeps;
    ++st.substeps;
    t += h;
  }
  st.t = t0 + T;
  ++st.frames;
  if (s.integrator == Integrator::SymplecticEuler && s.stable_step == StableStep::Refresh && local_rule &&
      !par && st.threaded.p && s.substep)
    refine_stiffening(m, st, T, s.safety, rollbacks > 0);  // the stable step's tangent refresh (opt-in)
  if (m.volume.size() > 0 && f32_scratch)
    st.warnings.inverted_elements +=
        count_inverted_f32(*m.volume_f32, m.volume, st.x.data(), st.volume_f32.data(), par_records);
  else if (m.volume.size() > 0)
    st.warnings.inverted_elements += count_inverted(m.volume, st.x);
  else if (m.compression.size() > 0)  // the same tetrahedra: counted once
    st.warnings.inverted_elements += count_inverted(m.compression, st.x);
  return status;
}

}  // namespace medspring
