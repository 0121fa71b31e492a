// How tight is the explicit step's stable-step rule on the volumetric kidney? (issue 23, item 5;
// docs/volumetric-stable-step.md). For the kidney of the benchmark (the phantom's
// 458-node surface meshed inside by TetGen, 10 kPa, nu = 0.45, supports on the bottom 20 %, a point load on
// the top node), at rest and at the equilibria of the given loads, it prints:
//   - the rule's omega (omega_rest sqrt(stiffening): the Lanczos estimate x 1.05 at rest, times the growth
//     bound of the last force pass: spring kappa/k, the volume terms' local rows, the compression blocks),
//   - the true omega_max of M^-1/2 K_t(x) M^-1/2 (Lanczos to convergence on the exact Hessian, no safety),
//   - the Gershgorin row bound at x (gershgorin_omega),
//   - the sub-steps per 0.5 ms frame the rule takes and those an exact omega would need (same safety 0.8),
//   - the largest fixed step that stays stable in practice: one symplectic step per frame, no guard, the
//     load applied at t = 0 from rest, bisected on h; a run is unstable when a position becomes
//     non-finite or moves more than 20 mm (5-10x the peak displacement), stable when it lasts `steps` steps.
//
//   medspring_stable_step_probe [--nodes 2000] [--loads 0.5,1,2] [--mass-scaling 0,0.25] [--steps 10000]
//                               [--lanczos 300] [--bisect 7]
//   --frame-times N [--precision double|float|both]: instead, N frames at the first load from rest, the
//     rules bound and refresh (and with both, each also with the single-precision volume pass,
//     VolumetricSettings::volume_precision, the default since h23b) alternated frame by frame; wall and CPU
//     time per frame. Without --frame-times the model has the default settings (float since h23b).
//     --springs both: each float simulation also with the gather pass's springs in double (the float
//     springs' A/B, spring_f32.hpp; the float springs are the default since the session of 2026-11-27 night).
//     --threads N: each float simulation also with StepSettings::threads = N (the threaded float sub-step,
//     threaded_volume.hpp; "tN" in its name); compare wall times (the CPU time is the calling thread's).
//     --block K: K consecutive frames of each simulation before the next (default 1: frame by frame).
//     --blocks both: each float simulation also with the float records' rows transposed (the layout before
//     VolumeTermsF32::blk; "rows" in its name).
//     --gather both: the float body also built with the double slots' gather limit (kSpringGatherMaxSprings:
//     "nogather" where its springs are more, the scatter pass then; spring_gather.hpp).
#include <time.h>  // clock_gettime(CLOCK_THREAD_CPUTIME_ID): the frame's CPU time, robust to a loaded machine

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/stability.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring::detail {  // the float springs of the gather pass on or off
                               // (src/physics/spring_gather.hpp), the float records' blocks (volume_f32.hpp)
bool set_gather_springs_f32(bool on);
bool set_volume_f32_blocks(bool on);
Index set_spring_gather_max_f32(Index springs);
}  // namespace medspring::detail

namespace {

using namespace medspring;

std::vector<double> parse_list(const char* text) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(std::stod(item));
  return v;
}

// One symplectic step of h per frame from rest, the load switched on at t = 0: true when `steps` steps stay
// finite and within 20 mm of the rest shape.
bool stable_at(const Model& m, Index top, double load, double h, long steps) {
  StepSettings s;
  s.dt = h;
  s.max_substeps = 1;  // one step of h per frame whatever the rule says (counted as capped)
  s.guard = false;
  State st = make_state(m, s);
  st.threaded.p = nullptr;  // no tangent refresh: it would only change State::stiffening, unused here
  const std::vector<PointLoad> loads{{.node = top, .force = Vec3(0, 0, -load), .t_ramp = 0}};
  for (long k = 0; k < steps; ++k) {
    step(m, st, s, &loads);
    if (k % 50 == 49 || k + 1 == steps) {
      const double d = (st.x - m.x0).rowwise().norm().maxCoeff();
      if (!std::isfinite(d) || d > 20.0) return false;
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Index nodes = 2000;
  std::vector<double> loads{0.5, 1.0, 2.0}, scalings{0.0, 0.25};
  long steps = 10000, frame_times = 0;
  int lanczos = 300, bisect = 7;
  std::string precision = "double";
  bool springs_both = false, blocks_both = false, gather_both = false;
  int threads = 1;
  long block = 1;
  for (int a = 1; a + 1 < argc; a += 2) {
    if (!std::strcmp(argv[a], "--nodes"))
      nodes = static_cast<Index>(std::atol(argv[a + 1]));
    else if (!std::strcmp(argv[a], "--loads"))
      loads = parse_list(argv[a + 1]);
    else if (!std::strcmp(argv[a], "--mass-scaling"))
      scalings = parse_list(argv[a + 1]);
    else if (!std::strcmp(argv[a], "--steps"))
      steps = std::atol(argv[a + 1]);
    else if (!std::strcmp(argv[a], "--lanczos"))
      lanczos = std::atoi(argv[a + 1]);
    else if (!std::strcmp(argv[a], "--frame-times"))
      frame_times = std::atol(argv[a + 1]);
    else if (!std::strcmp(argv[a], "--bisect"))
      bisect = std::atoi(argv[a + 1]);
    else if (!std::strcmp(argv[a], "--precision") &&
             (!std::strcmp(argv[a + 1], "double") || !std::strcmp(argv[a + 1], "float") ||
              !std::strcmp(argv[a + 1], "both")))
      precision = argv[a + 1];
    else if (!std::strcmp(argv[a], "--springs") && !std::strcmp(argv[a + 1], "both"))
      springs_both = true;
    else if (!std::strcmp(argv[a], "--blocks") && !std::strcmp(argv[a + 1], "both"))
      blocks_both = true;
    else if (!std::strcmp(argv[a], "--gather") && !std::strcmp(argv[a + 1], "both"))
      gather_both = true;
    else if (!std::strcmp(argv[a], "--threads"))
      threads = std::atoi(argv[a + 1]);
    else if (!std::strcmp(argv[a], "--block"))
      block = std::max(1L, std::atol(argv[a + 1]));
    else {
      std::fprintf(stderr, "stable_step_probe: unknown option %s\n", argv[a]);
      return 2;
    }
  }
  const SurfaceMesh surf = kidney_phantom();
  const VolumetricMesh vm = fem::volumetric_mesh(surf, {.target_nodes = nodes});
  const double zmin = surf.V.col(2).minCoeff(), zmax = surf.V.col(2).maxCoeff();
  if (frame_times > 0) {  // wall time of each frame, stable_step bound and refresh alternated frame by frame
    VolumetricSettings vs;  // 10 kPa, nu = 0.45, the bench's kidney (apps/cmd_bench_volumetric.cpp)
    vs.fixed = fem::support_nodes(surf.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
    std::vector<std::shared_ptr<const VolumetricBody>> bodies;  // the precisions asked for
    std::vector<std::string> names, labels;                     // labels: per body
    for (const VolumePrecision p : {VolumePrecision::Double, VolumePrecision::Float}) {
      if (precision != "both" && precision != to_string(p)) continue;
      vs.volume_precision = p;
      bodies.push_back(std::make_shared<const VolumetricBody>(vm, vs, "volumetric kidney"));
      labels.emplace_back(precision == "both" && p == VolumePrecision::Float ? " f32" : "");
      if (gather_both && p == VolumePrecision::Float) {  // the float body with the double slots' gather limit
        const Index was = medspring::detail::set_spring_gather_max_f32(kSpringGatherMaxSprings);
        bodies.push_back(std::make_shared<const VolumetricBody>(vm, vs, "volumetric kidney"));
        medspring::detail::set_spring_gather_max_f32(was);
        labels.push_back(labels.back() + (bodies.back()->model().gather.empty() ? " nogather" : " gather"));
      }
    }
    const auto& body = bodies.front();
    Index top = 0;
    for (Index i = 0; i < body->num_surface_nodes(); ++i)
      if (body->rest_surface()(i, 2) > body->rest_surface()(top, 2)) top = i;
    const double load = loads.empty() ? 0.5 : loads.front();
    std::vector<std::unique_ptr<Simulation>> sims;
    // per simulation: the gather pass's springs in float, the float records' blocks (the defaults)
    std::vector<bool> fsprings, fblocks;
    std::vector<int> thread_counts{1};
    if (threads > 1) thread_counts.push_back(threads);
    for (std::size_t bi = 0; bi < bodies.size(); ++bi)
      for (const int th : thread_counts)
        for (const int variant : {0, 1, 2}) {  // the default; double springs; the records' rows
          const auto& b = bodies[bi];
          const bool f32 = b->model().volume_f32 != nullptr, fs = variant != 1, blk = variant != 2;
          if ((variant > 0 && (!f32 || th > 1)) || (variant == 1 && !springs_both) ||
              (variant == 2 && !blocks_both))
            continue;
          if (th > 1 && !f32) continue;
          for (const StableStep rule : {StableStep::Bound, StableStep::Refresh}) {
            SimulationSettings ss;
            ss.normals = false;
            ss.local.enabled = false;
            ss.step.stable_step = rule;
            ss.step.threads = th;
            sims.push_back(std::make_unique<Simulation>(b, ss));
            sims.back()->set_loads({{.node = top, .force = Vec3(0, 0, -load), .t_ramp = 0}});
            fsprings.push_back(fs);
            fblocks.push_back(blk);
            names.push_back(std::string(rule == StableStep::Bound ? "bound" : "refresh") + labels[bi] +
                            (fs ? "" : " ds") + (blk ? "" : " rows") +
                            (th > 1 ? " t" + std::to_string(th) : ""));
          }
        }
    const int ns = static_cast<int>(sims.size());
    std::vector<std::vector<double>> us(static_cast<std::size_t>(2 * ns));  // wall, then CPU time, of each
    const auto cpu_us = [] {
      timespec t{};
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
      return 1e6 * static_cast<double>(t.tv_sec) + 1e-3 * static_cast<double>(t.tv_nsec);
    };
    for (long f = 0; f < frame_times; f += block)
      for (int k = 0; k < ns; ++k) {
        medspring::detail::set_gather_springs_f32(fsprings[static_cast<std::size_t>(k)]);
        medspring::detail::set_volume_f32_blocks(fblocks[static_cast<std::size_t>(k)]);
        for (long b = 0; b < block && f + b < frame_times; ++b) {
          const double c0 = cpu_us();
          const auto t0 = std::chrono::steady_clock::now();
          sims[static_cast<std::size_t>(k)]->update();
          us[static_cast<std::size_t>(k)].push_back(
              std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
          us[static_cast<std::size_t>(k + ns)].push_back(cpu_us() - c0);
        }
      }
    std::printf("nodes %ld, load %g N, %ld frames from rest, frame wall time (us), then CPU time (us):\n",
                static_cast<long>(body->model().num_nodes()), load, frame_times);
    for (int k = 0; k < 2 * ns; ++k) {
      std::vector<double> v = us[static_cast<std::size_t>(k)];
      std::sort(v.begin(), v.end());
      const auto at = [&](double q) {
        return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
      };
      long slow = 0;
      for (double x : v) slow += x > 5000.0 ? 1 : 0;
      const std::string name = names[static_cast<std::size_t>(k % ns)] + (k < ns ? "" : "/cpu");
      std::printf("  %-15s median %.0f  p99 %.0f  p99.9 %.0f  max %.0f  frames > 5 ms %ld  sub-steps %llu\n",
                  name.c_str(), at(0.5), at(0.99), at(0.999), v.back(), slow,
                  static_cast<unsigned long long>(sims[static_cast<std::size_t>(k % ns)]->state().substeps));
    }
    return 0;
  }
  std::printf(
      "scaling_ms load_N nodes substeps_rule stiffening omega_rule omega_true omega_L15 omega_gersh "
      "rule/true gersh/true substeps_exact(0.8) substeps_exact(1.0) h_rule_ms 2/omega_true_ms "
      "h_practical_ms h_practical*omega_true\n");
  for (double msdt : scalings) {
    VolumetricSettings vs;  // 10 kPa, nu = 0.45
    vs.mass_scaling_dt = msdt;
    vs.fixed = fem::support_nodes(surf.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
    const auto body = std::make_shared<VolumetricBody>(vm, vs, "volumetric kidney");
    const Model& m = body->model();
    Index top = 0;
    for (Index i = 0; i < body->num_surface_nodes(); ++i)
      if (body->rest_surface()(i, 2) > body->rest_surface()(top, 2)) top = i;
    const double T = 0.5, safety = 0.8;
    for (double load : loads) {
      SimulationSettings ss;
      ss.normals = false;
      ss.local.enabled = false;
      ss.step.stable_step = StableStep::Refresh;  // opt-in: "sub-steps an exact omega needs"
      Simulation sim(body, ss);
      MatX3 x = m.x0;
      double stiff = 1.0, subs = stable_substeps(m, 1.0, T, safety), refined = 1.0;
      if (load > 0) {
        const std::vector<PointLoad> pl{{.node = top, .force = Vec3(0, 0, -load), .t_ramp = 0}};
        sim.set_loads(pl);
        sim.advance(400);  // 200 ms: the transient has decayed (beta = 0.5 / ms)
        const auto s1 = sim.state().substeps;
        sim.advance(10);
        subs = static_cast<double>(sim.state().substeps - s1) / 10.0;  // with the tangent refresh
        x = sim.state().x;
        refined = sim.state().stiffening;
        // the growth bound alone: one more frame from a copy of the state with the default rule
        State st = sim.state();
        StepSettings bound = sim.settings().step;
        bound.stable_step = StableStep::Bound;
        step(m, st, bound, &pl);
        stiff = st.stiffening;
      }
      {  // the cost of one tangent refresh (15 Lanczos products, as integrators.cpp takes it)
        TangentScratch z;
        size_tangent_scratch(m, z);
        const auto t0 = std::chrono::steady_clock::now();
        double sink = 0;
        for (int r = 0; r < 5; ++r) sink += tangent_omega2(m, x, 15, z);
        const double us =
            std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / 5;
        std::printf("  one refresh (15 products): %.0f us wall (%.3g)\n", us, sink);
      }
      const double w_rule = m.omega_rest * std::sqrt(std::max(stiff, 1.0));
      const double w_ref = m.omega_rest * std::sqrt(refined);
      const double w_true = power_iteration_omega(m, x, lanczos, 1.0);
      const double w_half = power_iteration_omega(m, x, lanczos / 2, 1.0);
      const double w15 = power_iteration_omega(m, x, 15, 1.0);
      const double wg = gershgorin_omega(m, x);
      if (std::abs(w_true - w_half) > 1e-6 * w_true)
        std::fprintf(stderr, "note: Lanczos not converged at load %g: %d products %.9g, %d products %.9g\n",
                     load, lanczos / 2, w_half, lanczos, w_true);
      auto exact_subs = [&](double sf) {
        const double h = sf * 2.0 / w_true;
        return T > h * (1.0 + 1e-12) ? std::ceil(T / h) : 1.0;
      };
      // the largest stable fixed step, bisected in units of 2 / omega_true
      double lo = 0.5, hi = 1.5;
      if (!stable_at(m, top, load, lo * 2.0 / w_true, steps)) {
        lo = 0.0;
        hi = 0.5;
      } else if (stable_at(m, top, load, hi * 2.0 / w_true, steps)) {
        lo = hi;
        hi = 3.0;
      }
      for (int b = 0; b < bisect; ++b) {
        const double mid = 0.5 * (lo + hi);
        (stable_at(m, top, load, mid * 2.0 / w_true, steps) ? lo : hi) = mid;
      }
      const double hp = lo * 2.0 / w_true;
      std::printf(
          "  refresh: stiffening %.4f omega %.4f (/true %.3f), sub-steps taken %.0f (growth bound alone "
          "%.0f)\n",
          refined, w_ref, w_ref / w_true, subs, stable_substeps(m, stiff, T, safety));
      std::printf("%.3g %.3g %ld %.0f %.4f %.4f %.4f %.4f %.4f %.3f %.3f %.0f %.0f %.4f %.4f %.4f %.3f\n",
                  msdt, load, static_cast<long>(m.num_nodes()), stable_substeps(m, stiff, T, safety), stiff,
                  w_rule, w_true, w15, wg, w_rule / w_true, wg / w_true, exact_subs(safety), exact_subs(1.0),
                  dt_safe(m, stiff, safety), 2.0 / w_true, hp, hp * w_true);
      std::fflush(stdout);
    }
  }
  return 0;
}
