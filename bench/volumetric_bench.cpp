// The volumetric spring kidney (issue 23, docs/volumetric.md): one simulation update (a 0.5 ms frame with
// the sub-steps its stable step needs) and one force evaluation, at about 2,000 nodes (the kidney phantom's
// 458-node surface meshed inside by TetGen -pqY), supports on the posterior 20 % and a 0.5 N load.
// Needs the fem layer (TetGen); without it nothing is registered.
#include <benchmark/benchmark.h>

#ifdef MEDSPRING_BENCH_HAVE_FEM
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/compression_terms.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/linear_response.hpp"
#include "medspring/physics/stability.hpp"
#include "medspring/physics/volume_terms.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring::detail {  // the force pass with the stiffening optional (src/physics/spring_kernel.hpp)
double internal_forces(const Model& m, const MatX3& x, const MatX3& f_ext, MatX3& f, bool stiffening);
}  // namespace medspring::detail
namespace medspring {  // the last sub-step's volume pass (src/physics/compression_rows.hpp, internal)
double add_volume_and_compression_forces_inc(const VolumeTerms& T, const double* x, double* f, double* inc,
                                             const double* s, double* trows, Index nodes);
namespace detail {  // the volume passes' vector path on or off (src/physics/compression_rows.hpp)
bool set_volume_simd(bool on);
// the float springs of the gather pass on or off (src/physics/spring_gather.hpp)
bool set_gather_springs_f32(bool on);
}  // namespace detail
}  // namespace medspring
#include "../src/physics/spring_f32.hpp"  // the float springs (internal to the physics layer)
#include "../src/physics/volume_f32.hpp"  // the single-precision volume pass (internal to the physics layer)

namespace {

using namespace medspring;

std::shared_ptr<const VolumetricBody> kidney(Index nodes, double mass_scaling_dt = 0.25,
                                             VolumePrecision precision = VolumePrecision::Double) {
  const SurfaceMesh s = kidney_phantom();
  const VolumetricMesh vm = fem::volumetric_mesh(s, {.target_nodes = nodes});
  const double zmin = s.V.col(2).minCoeff(), zmax = s.V.col(2).maxCoeff();
  VolumetricSettings st;  // 10 kPa, nu = 0.45
  st.mass_scaling_dt = mass_scaling_dt;
  st.volume_precision = precision;
  st.fixed = fem::support_nodes(s.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
  return std::make_shared<VolumetricBody>(vm, st, "volumetric kidney");
}

// The former stable-step bound of the terms (before the block bound, issue 23; as in
// tests/fem/compression_test.cpp): the scalar Gershgorin row,
// max over free nodes of sum_t sum_l (a |g_k| |g_l| + [l != k] |b| L_max / 3) s_k s_l.
double former_compression_bound(const CompressionTerms& T, const MatX3& x, const VecX& mass,
                                const std::vector<std::uint8_t>& fixed) {
  VecX rows = VecX::Zero(x.rows());
  for (Index t = 0; t < T.size(); ++t) {
    const auto u = static_cast<std::size_t>(t);
    const Index id[4] = {T.a[u], T.b[u], T.c[u], T.d[u]};
    Vec3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = x.row(id[k]).transpose();
    const Vec3 e1 = p[1] - p[0], e2 = p[2] - p[0], e3 = p[3] - p[0];
    Vec3 g[4];
    g[1] = e2.cross(e3) / 6;
    g[2] = e3.cross(e1) / 6;
    g[3] = e1.cross(e2) / 6;
    g[0] = -(g[1] + g[2] + g[3]);
    const double J = e1.dot(g[1]) / T.V0[u];
    if (J >= 1) continue;
    double L = 0;
    for (int k = 0; k < 4; ++k)
      for (int l = 0; l < k; ++l) L = std::max(L, (p[k] - p[l]).norm());
    const CompressionH hj = compression_h(J);
    const double a = T.kc[u] / T.V0[u] * hj.d2, hb = std::abs(T.kc[u] * hj.d1) * L / 3;
    for (int k = 0; k < 4; ++k)
      for (int l = 0; l < 4; ++l) {
        const double sk = fixed[static_cast<std::size_t>(id[k])] ? 0 : 1 / std::sqrt(mass[id[k]]);
        const double sl = fixed[static_cast<std::size_t>(id[l])] ? 0 : 1 / std::sqrt(mass[id[l]]);
        rows[id[k]] += (a * g[k].norm() * g[l].norm() + (l == k ? 0.0 : hb)) * sk * sl;
      }
  }
  return rows.maxCoeff();
}

// One update of the kidney of `nodes` nodes with mass scaling for `mass_scaling_dt` (ms, 0: off) under a
// point load of `load` N on its top node, with the counters of its stable step.
void kidney_update(benchmark::State& st, Index nodes, double mass_scaling_dt, double load,
                   VolumePrecision precision = VolumePrecision::Double, StableStep rule = StableStep::Bound,
                   int threads = 1) {
  const auto body = kidney(nodes, mass_scaling_dt, precision);
  SimulationSettings ss;
  ss.normals = false;
  ss.local.enabled = false;
  ss.step.stable_step = rule;
  ss.step.threads = threads;
  Simulation sim(body, ss);
  Index top = 0;
  for (Index i = 0; i < body->num_surface_nodes(); ++i)
    if (body->rest_surface()(i, 2) > body->rest_surface()(top, 2)) top = i;
  sim.set_loads({{.node = top, .force = Vec3(0, 0, -load), .t_ramp = 0}});
  sim.advance(50);
  const auto s0 = sim.state().substeps;
  const auto f0 = sim.state().frames;
  for (auto _ : st) sim.update();
  st.counters["nodes"] = static_cast<double>(body->model().num_nodes());
  st.counters["threads_used"] = effective_threads(body->model(), ss.step);
  st.counters["springs"] = static_cast<double>(body->model().num_springs());
  st.counters["tets"] = static_cast<double>(body->model().volume.size());
  st.counters["substeps_per_update"] =
      static_cast<double>(sim.state().substeps - s0) / static_cast<double>(sim.state().frames - f0);
  st.counters["dt_rest_ms"] = body->model().dt_safe_rest();
  st.counters["added_mass_pct"] = 100.0 * body->stats().added_mass_fraction;
  // the stable-step rule against the loaded state's own omega (Lanczos on the exact Hessian at x)
  const Model& m = body->model();
  st.counters["stiffening"] = sim.state().stiffening;
  st.counters["omega_bound_over_true"] =
      m.omega_rest * std::sqrt(sim.state().stiffening) / power_iteration_omega(m, sim.state().x, 40, 1.0);
  st.counters["omega_rest_over_true_rest"] = m.omega_rest / power_iteration_omega(m, m.x0, 40, 1.0);
  // how the stiffening splits (issue 23): the compression terms' bound (omega^2 / omega_rest^2 added by
  // Weyl), the rest (springs and volume terms), the compressed terms, and the sub-steps at rest
  const double w2r = m.omega_rest * m.omega_rest;
  const Index n = m.num_nodes();
  VecX fc = VecX::Zero(3 * n), rows(6 * n);  // src/physics/compression_rows.hpp
  const double bc = m.compression.size() > 0
                        ? add_compression_forces(m.compression, sim.state().x.data(), fc.data(),
                                                 m.mass.data(), m.fixed.data(), rows.data(), n)
                        : 0.0;
  Index compressed = 0;
  for (Index t = 0; t < m.compression.size(); ++t) {
    const auto& C = m.compression;
    const MatX3& x = sim.state().x;
    const auto u = static_cast<std::size_t>(t);
    compressed +=
        signed_tet_volume(x.row(C.a[u]), x.row(C.b[u]), x.row(C.c[u]), x.row(C.d[u])) < C.V0[u] ? 1 : 0;
  }
  // the parts of the rule: springs alone, the volume terms' global and local rows, their rule R
  Model springs_only = m;
  springs_only.volume = VolumeTerms{};
  springs_only.compression = CompressionTerms{};
  MatX3 fs(n, 3), fe = MatX3::Zero(n, 3);
  const double s_springs = detail::internal_forces(springs_only, sim.state().x, fe, fs, true);
  VecX inc(m.volume.size()), vrows(n);
  VecX fv = VecX::Zero(3 * n);
  const double sv = add_volume_forces_inc(m.volume, sim.state().x.data(), fv.data(), inc.data());
  const double rv = volume_row_max(m.volume, inc.data(), vrows.data(), n);
  const double R = std::min(std::max(s_springs, sv), s_springs + rv / w2r);
  st.counters["s_springs"] = s_springs;
  st.counters["s_volume_global"] = sv;
  st.counters["volume_rows_max"] = rv / w2r;
  st.counters["stiff_rest_terms"] = R;  // springs and volume terms (the local rule)
  // the compression terms' part, block bound and former bound, and the sub-steps each asks for with R
  const double former = former_compression_bound(m.compression, sim.state().x, m.mass, m.fixed) / w2r;
  const StepSettings& step_s = sim.settings().step;
  st.counters["stiff_compression"] = bc / w2r;
  st.counters["stiff_compression_former"] = former;
  st.counters["substeps_block_bound"] = stable_substeps(m, R + bc / w2r, step_s.dt, step_s.safety);
  st.counters["substeps_former_bound"] = stable_substeps(m, R + former, step_s.dt, step_s.safety);
  st.counters["compressed_tets"] = static_cast<double>(compressed);
  st.counters["substeps_at_rest"] =
      stable_substeps(m, 1.0, sim.settings().step.dt, sim.settings().step.safety);
}

// Args: nodes, mass_scaling_dt in microseconds (0 = off: the masses as lumped, with the 0.5 floor); 0.5 N.
void BM_VolumetricKidneyUpdate(benchmark::State& st) {
  kidney_update(st, static_cast<Index>(st.range(0)), 1e-3 * static_cast<double>(st.range(1)), 0.5);
}
// Args: nodes, the load in mN (mass scaling off): where the compression terms' bound sets the sub-steps.
void BM_VolumetricKidneyUpdateLoad(benchmark::State& st) {
  kidney_update(st, static_cast<Index>(st.range(0)), 0.0, 1e-3 * static_cast<double>(st.range(1)));
}
BENCHMARK(BM_VolumetricKidneyUpdateLoad)
    ->Args({2000, 1000})
    ->Args({2000, 2000})
    ->Unit(benchmark::kMicrosecond);
// BM_VolumetricKidneyUpdate with the volume passes one tetrahedron at a time (their vector path off): the
// A/B of tet_simd.hpp in one binary.
void BM_VolumetricKidneyUpdateScalar(benchmark::State& st) {
  const bool was = detail::set_volume_simd(false);
  kidney_update(st, static_cast<Index>(st.range(0)), 1e-3 * static_cast<double>(st.range(1)), 0.5);
  detail::set_volume_simd(was);
}
BENCHMARK(BM_VolumetricKidneyUpdateScalar)
    ->Args({500, 0})
    ->Args({1000, 0})
    ->Args({2000, 0})
    ->Unit(benchmark::kMicrosecond);
// BM_VolumetricKidneyUpdate with the single-precision volume pass (volume_precision float, the default since
// h23b; BM_VolumetricKidneyUpdate keeps the double pass, the former default) on the sub-steps without the
// stable step's bound.
void BM_VolumetricKidneyUpdateF32(benchmark::State& st) {
  kidney_update(st, static_cast<Index>(st.range(0)), 1e-3 * static_cast<double>(st.range(1)), 0.5,
                VolumePrecision::Float);
}
BENCHMARK(BM_VolumetricKidneyUpdateF32)
    ->Args({500, 0})
    ->Args({1000, 0})
    ->Args({2000, 0})
    ->Args({2000, 250})
    ->Unit(benchmark::kMicrosecond);
// BM_VolumetricKidneyUpdateF32 (mass scaling off) with the gather pass's springs in double (second Arg 0: the
// float volume passes alone, as before the session of 2026-11-27 night) and in float (1, the default since
// then; spring_f32.hpp): the A/B of the float springs in one process.
void BM_VolumetricKidneyUpdateF32Springs(benchmark::State& st) {
  const bool was = detail::set_gather_springs_f32(st.range(1) != 0);
  kidney_update(st, static_cast<Index>(st.range(0)), 0.0, 0.5, VolumePrecision::Float);
  detail::set_gather_springs_f32(was);
}
BENCHMARK(BM_VolumetricKidneyUpdateF32Springs)
    ->Args({500, 0})
    ->Args({500, 1})
    ->Args({2000, 0})
    ->Args({2000, 1})
    ->Unit(benchmark::kMicrosecond);
// The default update (mass scaling off) with the float passes reading the records' blocks of eight (second
// Arg 1, the default since 2026-11-28) or transposing their rows (0, as before): the A/B in one process.
void BM_VolumetricKidneyUpdateF32Blocks(benchmark::State& st) {
  const bool was = detail::set_volume_f32_blocks(st.range(1) != 0);
  kidney_update(st, static_cast<Index>(st.range(0)), 0.0, 0.5, VolumePrecision::Float);
  detail::set_volume_f32_blocks(was);
}
BENCHMARK(BM_VolumetricKidneyUpdateF32Blocks)
    ->Args({2000, 0})
    ->Args({2000, 1})
    ->Unit(benchmark::kMicrosecond);
// The default update (float passes, mass scaling off) on Arg 1 threads (StepSettings::threads; the threaded
// float passes, threaded_volume.hpp): the A/B of the second core. Wall time is the figure (UseRealTime).
void BM_VolumetricKidneyUpdateThreads(benchmark::State& st) {
  kidney_update(st, static_cast<Index>(st.range(0)), 0.0, 0.5, VolumePrecision::Float, StableStep::Bound,
                static_cast<int>(st.range(1)));
}
BENCHMARK(BM_VolumetricKidneyUpdateThreads)
    ->Args({2000, 1})
    ->Args({2000, 2})
    ->Args({4000, 1})
    ->Args({4000, 2})
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);
// The quasi-static linear response (Integrator::LinearStatic, physics/linear_response.hpp; issue 23, item 5):
// Args: nodes, disk radius in mm (0: the 0.5 N on the top node alone; r: 0.5 N spread equally over the
// surface nodes within r of it), the columns' precision (0: float, the default; 1: double). One update of the
// Simulation (the step, the surface map) with the loaded nodes' response cached by the warm-up; the default
// (dynamic) update is BM_VolumetricKidneyUpdateF32/2000/0.
void BM_VolumetricKidneyLinearStatic(benchmark::State& st) {
  const auto body = kidney(static_cast<Index>(st.range(0)), 0.0, VolumePrecision::Float);
  SimulationSettings ss;
  ss.normals = false;
  ss.local.enabled = false;
  ss.step.integrator = Integrator::LinearStatic;
  Simulation sim(body, ss);
  if (st.range(2) != 0)
    sim.state().linear = std::make_shared<LinearResponse>(body->model(), LinearResponse::kDefaultCacheBytes,
                                                          LinearResponse::Precision::Double);
  const MatX3& S = body->rest_surface();
  Index top = 0;
  for (Index i = 0; i < S.rows(); ++i)
    if (S(i, 2) > S(top, 2)) top = i;
  std::vector<Index> disk;
  for (Index i = 0; i < S.rows(); ++i)
    if ((S.row(i) - S.row(top)).norm() <= static_cast<double>(st.range(1))) disk.push_back(i);
  std::vector<PointLoad> loads;
  for (Index i : disk)
    loads.push_back({.node = i, .force = Vec3(0, 0, -0.5 / static_cast<double>(disk.size())), .t_ramp = 0});
  sim.set_loads(loads);
  sim.advance(5);  // factors K0 (first frame) and caches the loaded nodes' columns
  for (auto _ : st) sim.update();
  const LinearResponse& R = *sim.state().linear;
  st.counters["nodes"] = static_cast<double>(body->model().num_nodes());
  st.counters["loaded_nodes"] = static_cast<double>(disk.size());
  st.counters["direct_threshold"] = R.direct_threshold();
  st.counters["factor_ms"] = R.factor_ms();
  st.counters["factor_nnz"] = static_cast<double>(R.factor_nonzeros());
  st.counters["cached_MB"] = static_cast<double>(R.cached_bytes()) / (1 << 20);
  st.counters["peak_mm"] = (sim.state().x - body->model().x0).rowwise().norm().maxCoeff();
}
BENCHMARK(BM_VolumetricKidneyLinearStatic)
    ->Args({2000, 0, 0})
    ->Args({2000, 0, 1})
    ->Args({2000, 12, 0})
    ->Args({2000, 12, 1})
    ->Args({4000, 0, 0})
    ->Args({4000, 0, 1})
    ->Args({4000, 12, 0})
    ->Args({4000, 12, 1})
    ->Unit(benchmark::kMicrosecond);
// The opt-in tangent refresh (StepSettings::stable_step = refresh), with the volume pass in double and with
// the single-precision pass (the default since h23b); mass scaling off. The mean includes the frames
// that carry one product of the re-estimate.
void BM_VolumetricKidneyUpdateRefresh(benchmark::State& st) {
  kidney_update(st, static_cast<Index>(st.range(0)), 0.0, 0.5, VolumePrecision::Double, StableStep::Refresh);
}
void BM_VolumetricKidneyUpdateF32Refresh(benchmark::State& st) {
  kidney_update(st, static_cast<Index>(st.range(0)), 0.0, 0.5, VolumePrecision::Float, StableStep::Refresh);
}
BENCHMARK(BM_VolumetricKidneyUpdateRefresh)->Arg(500)->Arg(2000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_VolumetricKidneyUpdateF32Refresh)->Arg(500)->Arg(2000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_VolumetricKidneyUpdate)
    ->Args({500, 0})
    ->Args({700, 0})
    ->Args({1000, 0})
    ->Args({1000, 250})
    ->Args({2000, 250})
    ->Args({2000, 500})
    ->Args({2000, 0})
    ->Unit(benchmark::kMicrosecond);

void BM_VolumetricKidneyForces(benchmark::State& st) {
  const auto body = kidney(2000);
  const Model& m = body->model();
  MatX3 x = m.x0, f(m.num_nodes(), 3), fe = MatX3::Zero(m.num_nodes(), 3);
  x.col(2) *= 0.98;
  for (auto _ : st) {
    internal_forces(m, x, fe, f);
    benchmark::DoNotOptimize(f.data());
  }
  st.counters["nodes"] = static_cast<double>(m.num_nodes());
}
BENCHMARK(BM_VolumetricKidneyForces)->Unit(benchmark::kMicrosecond);

// The force pass as it was before the fused tetrahedron pass (commit 39af8e7), for an A/B in one run: the
// plain spring pass (internal_forces of the model without its volume terms) and the former per-term loop
// (Eigen 3-vectors, corner lookup by branch, a division and six edge lengths per term), copied here.
double former_volume_forces(const VolumeTerms& T, const double* x, double* f, bool stiffening) {
  auto row = [&](Index i) { return Vec3(x[3 * i], x[3 * i + 1], x[3 * i + 2]); };
  auto node = [&](Index t, int k) { return k == 0 ? T.a[t] : k == 1 ? T.b[t] : k == 2 ? T.c[t] : T.d[t]; };
  double stiff = 1.0;
  for (Index t = 0; t < T.size(); ++t) {
    const Vec3 xa = row(T.a[t]), e1 = row(T.b[t]) - xa, e2 = row(T.c[t]) - xa, e3 = row(T.d[t]) - xa;
    Vec3 g[4];
    g[1] = e2.cross(e3) / 6.0;
    g[2] = e3.cross(e1) / 6.0;
    g[3] = e1.cross(e2) / 6.0;
    g[0] = -(g[1] + g[2] + g[3]);
    const double V = e1.dot(e2.cross(e3)) / 6.0;
    const double V0 = T.V0[static_cast<std::size_t>(t)];
    const double s = -T.kv[static_cast<std::size_t>(t)] * (V - V0) / V0;
    for (int k = 0; k < 4; ++k) {
      const Index i = 3 * node(t, k);
      f[i] += s * g[k][0];
      f[i + 1] += s * g[k][1];
      f[i + 2] += s * g[k][2];
    }
    if (!stiffening) continue;
    const double gg = g[0].squaredNorm() + g[1].squaredNorm() + g[2].squaredNorm() + g[3].squaredNorm();
    const double L =
        std::max({e1.norm(), e2.norm(), e3.norm(), (e2 - e1).norm(), (e3 - e1).norm(), (e3 - e2).norm()});
    const double cur = gg + std::abs(V - V0) * L / 3.0 * 4.0;
    const double rest = T.G0[static_cast<std::size_t>(t)];
    if (rest > 0 && cur > rest * stiff) stiff = cur / rest;
  }
  return stiff;
}

// Arg: 1 = with the stiffening bound (the last force evaluation of a frame), 0 = without (the others).
void BM_VolumetricKidneyForcesFormer(benchmark::State& st) {
  const bool stiff = st.range(0) != 0;
  const auto body = kidney(2000);
  const Model& m = body->model();
  Model springs_only = m;
  springs_only.volume = VolumeTerms{};
  MatX3 x = m.x0, f(m.num_nodes(), 3), fe = MatX3::Zero(m.num_nodes(), 3), g = f;
  x.col(2) *= 0.98;
  for (auto _ : st) {
    detail::internal_forces(springs_only, x, fe, f, stiff);
    former_volume_forces(m.volume, x.data(), f.data(), stiff);
    benchmark::DoNotOptimize(f.data());
  }
  internal_forces(m, x, fe, g);  // the fused pass gives the same forces (to rounding)
  st.counters["max_rel_diff"] = (f - g).cwiseAbs().maxCoeff() / g.cwiseAbs().maxCoeff();
}
BENCHMARK(BM_VolumetricKidneyForcesFormer)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// Arg: 0 = the fused pass (the terms own springs), 1 = the packed volume pass then the plain spring pass (the
// default); Arg 2: the stiffening.
void BM_VolumetricKidneyForcesUnfused(benchmark::State& st) {
  const auto body = kidney(2000);
  Model m = body->model();
  if (st.range(0) == 0) plan_owned_springs(m.volume, m.springs.i, m.springs.j, m.num_nodes());
  if (st.range(0) == 2)  // trial: records sorted by their smallest corner
    std::sort(m.volume.packed.begin(), m.volume.packed.end(), [](const auto& a, const auto& b) {
      return std::min({a.n[0], a.n[1], a.n[2], a.n[3]}) < std::min({b.n[0], b.n[1], b.n[2], b.n[3]});
    });
  const bool stiff = st.range(1) != 0;
  MatX3 x = m.x0, f(m.num_nodes(), 3), fe = MatX3::Zero(m.num_nodes(), 3);
  x.col(2) *= 0.98;
  for (auto _ : st) {
    detail::internal_forces(m, x, fe, f, stiff);
    benchmark::DoNotOptimize(f.data());
  }
}
BENCHMARK(BM_VolumetricKidneyForcesUnfused)
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Args({2, 0})
    ->Unit(benchmark::kMicrosecond);

// Where a default update's time goes (docs/volumetric-speed.md "Where the time goes"), one phase per Arg, on
// the 2,000-node kidney without mass scaling at a 2 % compressed state: 0 = the spring pass (return springs
// and loads included; the model without its volume terms), 1 = the volume pass without the stiffening bound
// (the frame's first sub-steps), 2 = with the global bound, 3 = with the local stiffening (the frame's last
// sub-step: the pass with the increments, then the row scatter), 4 = the per-frame inversion count, 5 = the
// pass with the increments alone (the frame's last sub-step where the local rule cannot save a sub-step).
// The default model has compression terms (c = 32): 6 = the volume pass with them fused
// (add_volume_and_compression_forces: the frame's first sub-steps), 7 = their forces in a separate pass
// (add_compression_forces, as before the fusion: /1 + /7 is what /6 replaces), 8 = their forces and
// curvature bound (the frame's last sub-step).
void BM_VolumetricKidneyPhases(benchmark::State& st) {
  const auto body = kidney(2000, 0.0);
  const Model& m = body->model();
  Model springs_only = m;
  springs_only.volume = VolumeTerms{};
  MatX3 x = m.x0, f = MatX3::Zero(m.num_nodes(), 3), fe = MatX3::Zero(m.num_nodes(), 3);
  x.col(2) *= 0.98;
  VecX rows(m.num_nodes() + m.volume.size());
  VecX crows(8 * m.num_nodes());  // the compression bound's scratch (a few doubles per node)
  VecX msq(m.num_nodes());        // m_i^-1/2, 0 on a fixed node (phase 9)
  for (Index i = 0; i < m.num_nodes(); ++i) msq[i] = m.fixed[i] ? 0.0 : 1.0 / std::sqrt(m.mass[i]);
  // phases 10 + p: phase p with the volume passes one tetrahedron at a time (their vector path off)
  // phases 20 / 21: phase 6 in single precision (volume_f32.hpp), 6V - 6V0 from the displacement differences
  // (the default) / as a difference of the two volumes; 22: phase 20 one record at a time (4-float vectors,
  // not eight records per 256-bit vector); 23 / 24: phase 9 in single precision (the default's last sub-step
  // since 2026-11-27, add_volume_and_compression_forces_inc_f32), eight records per vector / one at a time;
  // 25 / 26: the float springs' slots (spring_slots_f32, without the stiffening: the default's sub-steps
  // since 2026-11-27 night), eight springs per vector / one at a time; 27: phase 25 with the stiffening; 28:
  // phase 4 with the float volume pass (count_inverted_f32, the step's count since 2026-11-27 night); 29, 30,
  // 31: phases 20, 28, 23 with the records' rows transposed (the layout before the blocks of 2026-11-28)
  const bool row_layout = st.range(0) >= 29;
  const int phase = row_layout          ? (st.range(0) == 29   ? 20
                                           : st.range(0) == 30 ? 28
                                                               : 23)
                    : st.range(0) >= 20 ? static_cast<int>(st.range(0))
                                        : static_cast<int>(st.range(0)) % 10;
  const bool blocks_was = detail::set_volume_f32_blocks(!row_layout);
  const bool simd_was = detail::set_volume_simd(st.range(0) < 10 || st.range(0) >= 20);
  VolumeTermsF32 vf;
  std::vector<float> fscratch;
  const bool x8_was = detail::set_volume_f32_x8(phase != 22 && phase != 24);
  if (phase >= 20) {
    build_volume_f32(m.volume, m.x0, vf);
    detail::build_springs_f32(m, vf.springs);
    fscratch.resize(static_cast<std::size_t>(kVolumeF32ScratchPerNode * m.num_nodes()));
  }
  std::vector<float> slots(phase >= 25 ? static_cast<std::size_t>(4 * (2 * m.num_springs() + 1)) : 0);
  if (phase >= 25 && phase <= 27) detail::fill_displacements_f32(vf, x.data(), fscratch.data());
  double row_max = 0;
  for (auto _ : st) {
    if (phase == 0) detail::internal_forces(springs_only, x, fe, f, false);
    if (phase == 1 || phase == 2)
      benchmark::DoNotOptimize(add_volume_forces(m.volume, x.data(), f.data(), phase == 2));
    if (phase == 3)
      benchmark::DoNotOptimize(
          add_volume_forces_local(m.volume, x.data(), f.data(), rows.data(), m.num_nodes(), row_max));
    if (phase == 4) benchmark::DoNotOptimize(count_inverted(m.volume, x));
    if (phase == 5)
      benchmark::DoNotOptimize(
          add_volume_forces_inc(m.volume, x.data(), f.data(), rows.data() + m.num_nodes()));
    if (phase == 6) add_volume_and_compression_forces(m.volume, x.data(), f.data());
    if (phase == 7 || phase == 8)
      benchmark::DoNotOptimize(add_compression_forces(
          m.compression, x.data(), f.data(), phase == 8 ? m.mass.data() : nullptr,
          phase == 8 ? m.fixed.data() : nullptr, phase == 8 ? crows.data() : nullptr, m.num_nodes()));
    if (phase == 9)  // the last sub-step's pass: volume + compression forces, increments, bound's traces
      benchmark::DoNotOptimize(add_volume_and_compression_forces_inc(m.volume, x.data(), f.data(),
                                                                     rows.data() + m.num_nodes(), msq.data(),
                                                                     crows.data(), m.num_nodes()));
    if (phase >= 20 && phase <= 22)
      add_volume_and_compression_forces_f32(vf, x.data(), f.data(), fscratch.data(), phase != 21);
    if (phase == 28) benchmark::DoNotOptimize(count_inverted_f32(vf, m.volume, x.data(), fscratch.data()));
    if (phase >= 25 && phase <= 27)
      benchmark::DoNotOptimize(
          detail::spring_slots_f32(vf.springs, fscratch.data(), slots.data(), phase == 27, phase != 26));
    if (phase == 23 || phase == 24)
      benchmark::DoNotOptimize(add_volume_and_compression_forces_inc_f32(
          vf, x.data(), f.data(), fscratch.data(), rows.data() + m.num_nodes(), msq.data(), crows.data()));
    benchmark::DoNotOptimize(f.data());
  }
  detail::set_volume_simd(simd_was);
  detail::set_volume_f32_x8(x8_was);
  detail::set_volume_f32_blocks(blocks_was);
  st.counters["tets"] = static_cast<double>(m.volume.size());
  st.counters["springs"] = static_cast<double>(m.num_springs());
}
BENCHMARK(BM_VolumetricKidneyPhases)
    ->DenseRange(0, 9)
    ->Arg(15)
    ->Arg(16)
    ->Arg(19)
    ->Arg(20)
    ->Arg(21)
    ->Arg(22)
    ->Arg(23)
    ->Arg(24)
    ->Arg(25)
    ->Arg(26)
    ->Arg(27)
    ->Arg(28)
    ->Arg(29)
    ->Arg(30)
    ->Arg(31)
    ->Unit(benchmark::kMicrosecond);

}  // namespace
#endif
