// The stable step's tangent refresh (issue 23, docs/volumetric-stable-step.md): the
// allocation-free Lanczos estimate equals power_iteration_omega, and on a TetGen kidney under constant,
// ramped and released loads up to large strain the refreshed step stays finite, never takes more sub-steps
// than the growth bound, and its sub-step never exceeds 2 / omega_max of the state it starts from (Lanczos to
// convergence on the exact tangent, measured independently). The refresh is opt-in (StepSettings::stable_step
// = refresh); the default takes exactly main's sub-steps (the growth bound). The estimate is amortised, one
// Lanczos product per frame on a snapshot of the state: it equals the one-shot estimate at the snapshot, and
// no frame takes more than one product.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "medspring/core/params.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/physics/stability.hpp"
#include "threaded_step.hpp"  // the refresh's reference and scratch (src/physics)

using namespace medspring;

namespace {

struct Kidney {
  std::unique_ptr<VolumetricBody> body;
  Index top = 0;
};

Kidney kidney(Index nodes) {
  const SurfaceMesh s = kidney_phantom();
  const double zmin = s.V.col(2).minCoeff(), zmax = s.V.col(2).maxCoeff();
  VolumetricSettings vs;  // 10 kPa, nu = 0.45
  vs.fixed = fem::support_nodes(s.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
  Kidney k;
  k.body = std::make_unique<VolumetricBody>(fem::volumetric_mesh(s, {.target_nodes = nodes}), vs, "kidney");
  for (Index i = 0; i < k.body->num_surface_nodes(); ++i)
    if (s.V(i, 2) > s.V(k.top, 2)) k.top = i;
  return k;
}

TEST(StableStepRefresh, TangentOmegaEqualsThePowerIterationEstimate) {
  const Kidney k = kidney(800);
  const Model& m = k.body->model();
  MatX3 x = m.x0;
  TangentScratch z;
  for (int pass = 0; pass < 2; ++pass) {
    for (const int it : {1, 5, 15, 40}) {
      const double w = power_iteration_omega(m, x, it, 1.0);
      EXPECT_NEAR(std::sqrt(tangent_omega2(m, x, it, z)), w, 1e-9 * w) << it << " products, pass " << pass;
    }
    x.col(2) *= 0.9;  // a compressed state (the compression terms' Hessian active)
  }
}

// The estimate in pieces (tangent_lanczos_start / advance / omega2) is tangent_omega2 bit for bit, however
// its products are split, and it reads only its snapshot: changing x after the start changes nothing.
TEST(StableStepRefresh, AmortisedEstimateEqualsTheOneShotEstimateBitForBit) {
  const Kidney k = kidney(800);
  const Model& m = k.body->model();
  MatX3 x = m.x0;
  x.col(2) *= 0.9;  // a compressed state (the compression terms' Hessian active)
  TangentScratch one, parts;
  const double w2 = tangent_omega2(m, x, 15, one);
  ASSERT_GT(w2, 0.0);
  for (const int per_call : {1, 2, 4, 15}) {
    MatX3 moving = x;
    tangent_lanczos_start(m, moving, 15, parts);
    const std::uint64_t p0 = parts.products;
    moving.setZero();  // the state moves on; the estimate reads its snapshot
    int calls = 0;
    while (!tangent_lanczos_advance(m, per_call, parts)) {
      ++calls;
      ASSERT_LE(parts.products - p0, static_cast<std::uint64_t>(calls * per_call));
      ASSERT_LT(calls, 20);
    }
    EXPECT_EQ(parts.products - p0, 15u) << per_call << " per call";
    EXPECT_EQ(parts.k, one.k) << per_call << " per call";
    EXPECT_EQ(tangent_lanczos_omega2(parts), w2) << per_call << " per call";  // bit for bit
  }
}

// One frame of the refreshed step at a time: the sub-step it takes (T / sub-steps) against 2 / omega_max of
// the state it starts from, at every 10th frame; positions finite and no rollback at any frame.
void check_run(const Model& m, const std::vector<PointLoad>& loads, int frames, const char* what,
               int* refreshed_below) {
  StepSettings s;                       // 0.5 ms frames, safety 0.8
  s.stable_step = StableStep::Refresh;  // opt-in
  StepSettings bound;                   // the default: the growth bound alone
  State st = make_state(m, s);
  State plain = make_state(m, bound);  // the same run with the growth bound alone
  double worst = 0, peak = 0;
  long subs_refresh = 0, subs_plain = 0;
  for (int f = 0; f < frames; ++f) {
    const bool check = f % 10 == 0 || f == frames - 1;
    const double w_true = check ? power_iteration_omega(m, st.x, 120, 1.0) : 0.0;
    const auto s0 = st.substeps;
    const StepStatus r = step(m, st, s, &loads);
    step(m, plain, bound, &loads);
    ASSERT_EQ(r.code, StepCode::Ok) << what << ", frame " << f;
    ASSERT_TRUE(st.x.allFinite()) << what << ", frame " << f;
    const double h = s.dt / static_cast<double>(st.substeps - s0);
    if (check) {
      EXPECT_LE(h * w_true, 2.0) << what << ", frame " << f << ": h " << h << " ms, omega_max " << w_true;
      worst = std::max(worst, h * w_true);
    }
    if (st.stiffening < plain.stiffening * (1 - 1e-9)) ++*refreshed_below;
    peak = std::max(peak, (st.x - m.x0).rowwise().norm().maxCoeff());
  }
  subs_refresh = static_cast<long>(st.substeps);
  subs_plain = static_cast<long>(plain.substeps);
  // never more sub-steps than the growth bound alone (the two runs part by rounding only)
  EXPECT_LE(subs_refresh, subs_plain) << what;
  EXPECT_EQ(st.warnings.rollbacks, 0u) << what;
  std::cout << what << ": sub-steps " << subs_refresh << " (growth bound alone " << subs_plain
            << "), largest h omega_max " << worst << ", peak displacement " << peak << " mm\n";
}

TEST(StableStepRefresh, RefreshedStepStaysBelowTheTrueLimitUpToLargeStrain) {
  const Kidney k = kidney(800);
  const Model& m = k.body->model();
  const Vec3 down(0, 0, -1);
  int below = 0;
  // constant loads applied at once (the benchmark's case, and large strain at 2 N)
  for (const double load : {0.5, 2.0}) {
    const std::vector<PointLoad> l{{.node = k.top, .force = load * down, .t_ramp = 0}};
    check_run(m, l, 300, load == 0.5 ? "0.5 N at once" : "2 N at once", &below);
  }
  // ramped to 3 N over 60 ms and released at once at 100 ms: the bound grows, then the organ rings
  const std::vector<PointLoad> ramp{{.node = k.top, .force = 3.0 * down, .t_ramp = 60, .t_release = 100}};
  check_run(m, ramp, 300, "3 N ramped, released", &below);
  EXPECT_GT(below, 100);  // the refresh does act: below the growth bound in many frames
}

// The refreshed step under 2 N at once (a large-strain transient, then a constant load) and 3 N ramped and
// released (400 frames each): no frame takes more than one Lanczos product; every reference it installs is
// the one-shot estimate (15 products x 1.05, squared, over omega_rest^2) at the state of the frame its
// snapshot was taken, to rounding (1e-14); a second state fed the same inputs takes the same sub-steps and
// positions bit for bit.
TEST(StableStepRefresh, AmortisedRefreshTakesOneProductPerFrameAndInstallsTheOneShotEstimate) {
  const Kidney k = kidney(800);
  const Model& m = k.body->model();
  const Vec3 down(0, 0, -1);
  StepSettings s;
  s.stable_step = StableStep::Refresh;
  const std::vector<std::vector<PointLoad>> runs{
      {{.node = k.top, .force = 2.0 * down, .t_ramp = 0}},
      {{.node = k.top, .force = 3.0 * down, .t_ramp = 60, .t_release = 100}}};
  TangentScratch z;
  for (std::size_t run = 0; run < runs.size(); ++run) {
    State st = make_state(m, s), twin = make_state(m, s);
    ASSERT_TRUE(st.threaded.p);
    const ThreadedStep::TangentRefresh& r = st.threaded.p->tangent;
    std::vector<MatX3> xs{st.x};  // xs[f]: the state at the end of frame f (State::frames)
    int installed = 0, pending_frames = 0;
    std::uint64_t last_frame = ~0ull;
    for (int f = 0; f < 400; ++f) {
      const std::uint64_t p0 = r.scratch.products;
      const auto s0 = st.substeps, t0 = twin.substeps;
      ASSERT_EQ(step(m, st, s, &runs[run]).code, StepCode::Ok) << "run " << run << ", frame " << f;
      step(m, twin, s, &runs[run]);
      xs.push_back(st.x);
      ASSERT_LE(r.scratch.products - p0, 1u) << "run " << run << ", frame " << f;
      ASSERT_EQ(st.substeps - s0, twin.substeps - t0) << "run " << run << ", frame " << f;
      ASSERT_TRUE(st.x == twin.x) << "run " << run << ", frame " << f;
      pending_frames += r.pending ? 1 : 0;
      if (r.valid && r.frame != last_frame) {  // a reference installed in this frame
        last_frame = r.frame;
        ++installed;
        ASSERT_LT(r.frame, xs.size());
        const double w2 = tangent_omega2(m, xs[r.frame], 15, z);
        const double expect = 1.05 * 1.05 * w2 / (m.omega_rest * m.omega_rest);
        EXPECT_NEAR(r.s_ref, expect, 1e-14 * expect) << "run " << run << ", frame " << f;
        EXPECT_GE(st.frames - r.frame, 15u) << "the products take 15 frames";
      }
    }
    EXPECT_EQ(st.warnings.rollbacks, 0u) << "run " << run;
    std::cout << "run " << run << ": " << installed << " references installed, an estimate under way in "
              << pending_frames << " of 400 frames, " << r.scratch.products << " products, sub-steps "
              << st.substeps << "\n";
    // 2 N: the first reference and its renewal before it ages out (the load is constant); 3 N: B moves
    // while the load ramps and the organ rings, so most estimates are discarded (measured: one installed)
    EXPECT_GE(installed, run == 0 ? 2 : 1) << "run " << run;
    EXPECT_GT(pending_frames, 15 * installed - 1) << "run " << run;
  }
}

// The default (stable_step = bound) is main's rule bit for bit: on the same kidney and loads it takes exactly
// the sub-steps main's growth bound takes (600, 899 and 877 in 300 frames: measured with main 20c360e, the
// runs of the test above without the refresh), and a state prepared for the default steps identically to one
// made without settings.
TEST(StableStepRefresh, DefaultTakesExactlyMainsSubSteps) {
  const Kidney k = kidney(800);
  const Model& m = k.body->model();
  const Vec3 down(0, 0, -1);
  const StepSettings s;
  ASSERT_EQ(s.stable_step, StableStep::Bound);
  const std::vector<std::vector<PointLoad>> runs{
      {{.node = k.top, .force = 0.5 * down, .t_ramp = 0}},
      {{.node = k.top, .force = 2.0 * down, .t_ramp = 0}},
      {{.node = k.top, .force = 3.0 * down, .t_ramp = 60, .t_release = 100}}};
  const std::uint64_t mains[] = {600, 899, 877};
  for (std::size_t r = 0; r < runs.size(); ++r) {
    State st = make_state(m, s);
    State other = make_state(m);
    for (int f = 0; f < 300; ++f) {
      step(m, st, s, &runs[r]);
      step(m, other, s, &runs[r]);
    }
    EXPECT_EQ(st.substeps, mains[r]) << "run " << r;
    EXPECT_EQ(other.substeps, st.substeps) << "run " << r;
    EXPECT_TRUE(st.x == other.x) << "run " << r;
    EXPECT_EQ(st.stiffening, other.stiffening) << "run " << r;
  }
}

TEST(StableStepRefresh, BadValueIsRefusedNamingTheParameter) {
  StepSettings s;
  set_param(s, "stable_step", "refresh");
  EXPECT_EQ(s.stable_step, StableStep::Refresh);
  try {
    set_param(s, "stable_step", "tight");
    FAIL() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("stable_step"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("tight"), std::string::npos) << e.what();
  }
}

}  // namespace
