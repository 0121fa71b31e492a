// Extreme inputs (issue 9): the engine stays finite through its guard (sub-steps, rollback with a
// halved step, dropped frames) or refuses the input with a clear error. Never NaN, a crash or a hang.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::shared_ptr<HybridKidney> kidney(const HybridSettings& s = {}) {
  return std::make_shared<HybridKidney>(hybrid_kidney_phantom(s));
}
std::shared_ptr<SurfaceBody> tube_body() {
  return std::make_shared<SurfaceBody>(tube(40, 30, 2.5, 3.0), SurfaceBodyParams{}, "tube",
                                       GridLayout{40, 30});
}
double max_displacement(const Simulation& sim) {
  return (sim.state().x - sim.model().x0).rowwise().norm().maxCoeff();
}
bool finite(const Simulation& sim) {
  return sim.state().x.allFinite() && sim.state().v.allFinite() && sim.surface().allFinite();
}
// The message of the InvalidInput thrown by f (empty if none).
template <class F>
std::string invalid_input_message(F&& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return {};
}

// ---- forces 1000 x the defaults (kidney 1 N, tube 0.5 N: the demo's forces) ----

struct ForceCase {
  const char* name;
  bool kidney;
  Integrator integrator;
};
void PrintTo(const ForceCase& c, std::ostream* os) {
  *os << c.name;
}

class ThousandfoldForce : public ::testing::TestWithParam<ForceCase> {};

TEST_P(ThousandfoldForce, StaysFiniteKeepsTimeAndRecoversAfterRelease) {
  const ForceCase& fc = GetParam();
  SimulationSettings st;
  st.step.integrator = fc.integrator;
  Simulation sim(fc.kidney ? BodyPtr(kidney()) : BodyPtr(tube_body()), st);
  const Index node = fc.kidney ? 223 : 20 * 30 + 7;
  const Vec3 F = fc.kidney ? Vec3(0, 0, -1000.0) : Vec3(0, -500.0, 0);
  sim.set_loads({{.node = node, .force = F, .t_ramp = 20, .t_release = 100}});
  double peak = 0;
  for (int k = 1; k <= 4000; ++k) {  // 2 s: press 100 ms, then 1.9 s of recovery
    sim.update();
    ASSERT_TRUE(finite(sim)) << "frame " << k;
    ASSERT_EQ(sim.time(), 0.5 * k) << "the clock must advance every frame (dropped frames included)";
    peak = std::max(peak, max_displacement(sim));
  }
  EXPECT_GT(peak, 10.0);  // the force did act
  EXPECT_LT(max_displacement(sim), 1e-6) << sim.state().warnings.failed << " dropped frames";
}

INSTANTIATE_TEST_SUITE_P(Models, ThousandfoldForce,
                         ::testing::Values(ForceCase{"KidneySymplectic", true, Integrator::SymplecticEuler},
                                           ForceCase{"KidneyImplicit", true, Integrator::ImplicitEuler},
                                           ForceCase{"TubeSymplectic", false, Integrator::SymplecticEuler},
                                           ForceCase{"TubeImplicit", false, Integrator::ImplicitEuler}),
                         [](const auto& i) { return std::string(i.param.name); });

TEST(ExtremeForces, OverSpeedFramesAreDroppedAndCounted) {
  // 1000 N on a 0.3 g node exceeds v_max = 100 mm/ms within 0.03 ms: the guard halves the step
  // 6 times, then drops the frame with the state restored; the run goes on.
  Simulation sim(kidney());
  sim.set_loads({{.node = 223, .force = Vec3(0, 0, -1000.0), .t_ramp = 0, .t_release = 50}});
  const StepStatus worst = sim.advance(100);
  EXPECT_EQ(worst.code, StepCode::Failed);
  const Warnings& w = sim.state().warnings;
  EXPECT_GT(w.failed, 0u);
  EXPECT_GE(w.rollbacks, 7 * w.failed);
  EXPECT_GT(w.velocity_limit, 0u);
  EXPECT_EQ(w.nonfinite, 0u);
  EXPECT_EQ(sim.state().frames, 100u);
  EXPECT_EQ(sim.time(), 50.0);
  EXPECT_LE(sim.state().v.rowwise().norm().maxCoeff(), 100.0);
  EXPECT_TRUE(finite(sim));
}

// ---- time steps at and above the stable bound ----

TEST(ExtremeSteps, AtTheStableBoundWithoutSubsteppingRunsUntilTheSpringsStiffen) {
  auto body = kidney();
  SimulationSettings st;
  st.step.substep = false;
  st.step.dt = body->model().dt_safe_rest(st.step.safety);  // exactly the rest bound: accepted
  Simulation sim(body, st);
  EXPECT_EQ(sim.advance(100).code, StepCode::Ok);  // at rest
  // a load stretches the Duffing springs: the run-time bound drops below dt and frames are refused,
  // counted, and leave the state (finite) and the clock where they were
  sim.set_loads({{.node = 223, .force = Vec3(0, 0, -1.0), .t_on = 50, .t_ramp = 20}});
  const StepStatus worst = sim.advance(200);
  EXPECT_EQ(worst.code, StepCode::Refused);
  EXPECT_GT(sim.state().warnings.unstable_refused, 0u);
  EXPECT_TRUE(finite(sim));
  const double t = sim.time();
  const MatX3 x = sim.state().x;
  EXPECT_EQ(sim.update().code, StepCode::Refused);
  EXPECT_EQ(sim.time(), t);
  EXPECT_EQ(sim.state().x, x);
  // with sub-stepping on, the same dt runs through the press
  st.step.substep = true;
  sim.set_settings(st);
  EXPECT_TRUE(sim.advance(400).ok());
  EXPECT_GT(max_displacement(sim), 4.0);
}

TEST(ExtremeSteps, AboveTheBoundWithoutSubsteppingIsRefusedAndReported) {
  auto body = kidney();
  SimulationSettings st;
  st.step.substep = false;
  st.step.dt = 1.5 * body->model().dt_safe_rest(st.step.safety);
  const std::string msg = invalid_input_message([&] { Simulation sim(body, st); });
  EXPECT_NE(msg.find("step.dt"), std::string::npos) << msg;
  EXPECT_NE(msg.find("above the stable step"), std::string::npos) << msg;
  // at run time (stiffened springs lower the bound): the frame is refused, counted, state untouched
  State s = make_state(body->model());
  s.stiffening = 4.0;  // the bound halves
  const StepStatus r = step(body->model(), s, {.dt = body->model().dt_safe_rest(), .substep = false});
  EXPECT_EQ(r.code, StepCode::Refused);
  EXPECT_EQ(s.warnings.unstable_refused, 1u);
  EXPECT_EQ(s.x, body->model().x0);
}

TEST(ExtremeSteps, FarAboveTheBoundWithSubsteppingStaysFinite) {
  for (double factor : {1.0, 10.0, 100.0}) {
    auto body = kidney();
    SimulationSettings st;
    st.step.dt = factor * body->model().dt_safe_rest();
    Simulation sim(body, st);
    sim.set_loads({{.node = 223, .force = Vec3(0, 0, -1.0), .t_ramp = 20}});
    const long frames = static_cast<long>(std::ceil(300.0 / st.step.dt));  // 300 ms
    EXPECT_TRUE(sim.advance(frames).ok()) << "dt x " << factor;
    EXPECT_TRUE(finite(sim));
    EXPECT_GE(sim.state().substeps, static_cast<std::uint64_t>(static_cast<double>(frames) * factor));
    // the held displacement is the static one (4.7 mm at 1 N, docs/physics.md) whatever dt
    EXPECT_NEAR(max_displacement(sim), 4.705, 0.01) << "dt x " << factor;
  }
}

TEST(ExtremeSteps, AbsurdStepHitsTheSubstepCapAndIsReportedNotNaN) {
  auto body = kidney();
  SimulationSettings st;
  st.step.dt = 1e6 * body->model().dt_safe_rest();  // ~6e5 ms in one frame
  Simulation sim(body, st);
  sim.set_loads({{.node = 223, .force = Vec3(0, 0, -1.0)}});
  sim.advance(5);
  EXPECT_TRUE(finite(sim));
  EXPECT_EQ(sim.state().warnings.substeps_capped, 5u);
  EXPECT_EQ(sim.state().frames, 5u);
}

// ---- degenerate geometry ----

TEST(ExtremeGeometry, DegenerateTrianglesAreRejectedNamingTheFace) {
  SurfaceMesh m = kidney_phantom();
  m.V.row(m.F(17, 2)) = 0.5 * (m.V.row(m.F(17, 0)) + m.V.row(m.F(17, 1)));  // face 17 collinear
  const std::string a = invalid_input_message([&] { SurfaceBody b(m, {}); });
  EXPECT_NE(a.find("degenerate"), std::string::npos) << a;
  const std::string b = invalid_input_message([&] { HybridKidney k(m, kidney_phantom_atoms()); });
  EXPECT_NE(b.find("degenerate"), std::string::npos) << b;
  SurfaceMesh r = kidney_phantom();
  r.F(3, 1) = r.F(3, 0);  // repeated index
  const std::string c = invalid_input_message([&] { SurfaceBody body(r, {}); });
  EXPECT_NE(c.find("face 3"), std::string::npos) << c;
}

TEST(ExtremeGeometry, ZeroLengthSpringsAreRejectedAtBuild) {
  ModelBuilder b("pair");
  b.add_node(Vec3(0, 0, 0), NodeParams{});
  b.add_node(Vec3(0, 0, 0), NodeParams{});
  b.add_spring(0, 1, 0.05, DuffingSettings{});
  const std::string msg = invalid_input_message([&] { b.build(); });
  EXPECT_NE(msg.find("springs[0].L0: zero-length spring"), std::string::npos) << msg;
  ModelBuilder e("explicit");
  e.add_node(Vec3(0, 0, 0), NodeParams{});
  e.add_node(Vec3(1, 0, 0), NodeParams{});
  e.add_spring(0, 1, 0.05, 0.0, 0.0);  // explicit rest length 0
  EXPECT_THROW(e.build(), InvalidInput);
}

TEST(ExtremeGeometry, SpringCollapsedToZeroLengthAtRunTimeStaysFinite) {
  for (Integrator integ : {Integrator::SymplecticEuler, Integrator::ImplicitEuler}) {
    auto body = kidney();
    Simulation sim(body, {.step = {.integrator = integ}});
    State s = sim.state();
    const Springs& S = body->model().springs;
    for (Index k = 0; k < 20; ++k) s.x.row(S.j[k]) = s.x.row(S.i[k]);  // 20 springs collapsed
    sim.set_state(s);
    const StepStatus st = sim.advance(2000);
    EXPECT_TRUE(st.ok()) << to_string(integ);
    EXPECT_TRUE(finite(sim));
    EXPECT_LT(max_displacement(sim), 1e-6) << to_string(integ);  // and it returns to rest
  }
}

TEST(ExtremeGeometry, CoincidentAtomsAreRejected) {
  MatX3 atoms = kidney_phantom_atoms();
  atoms.row(5) = atoms.row(4);
  const std::string a = invalid_input_message([&] { HybridKidney k(kidney_phantom(), atoms); });
  EXPECT_NE(a.find("atoms 4 and 5"), std::string::npos) << a;
  // an atom on a surface node: a zero-length spoke
  MatX3 on = kidney_phantom_atoms();
  on.row(0) = kidney_phantom().V.row(0);
  const std::string b = invalid_input_message([&] { HybridKidney k(kidney_phantom(), on); });
  EXPECT_NE(b.find("coincides with atom"), std::string::npos) << b;
  MatX3 nan_atoms = kidney_phantom_atoms();
  nan_atoms(3, 2) = kNaN;
  EXPECT_THROW(HybridKidney(kidney_phantom(), nan_atoms), InvalidInput);
}

TEST(ExtremeGeometry, EmptyAndOneNodeMeshesAreRejected) {
  const std::string e = invalid_input_message([] { SurfaceBody b(SurfaceMesh{}, {}); });
  EXPECT_FALSE(e.empty());
  SurfaceMesh one;
  one.V = MatX3::Zero(1, 3);
  const std::string o = invalid_input_message([&] { SurfaceBody b(one, {}); });
  EXPECT_FALSE(o.empty());
  EXPECT_THROW(HybridKidney(SurfaceMesh{}, kidney_phantom_atoms()), InvalidInput);
  EXPECT_THROW(HybridKidney(kidney_phantom(), MatX3::Zero(1, 3)), InvalidInput);  // one atom
  const std::string z = invalid_input_message([] { ModelBuilder("none").build(); });
  EXPECT_NE(z.find("no nodes"), std::string::npos) << z;
}

TEST(ExtremeGeometry, OneNodeModelIsAValidTrivialModel) {
  ModelBuilder b("particle");
  b.add_node(Vec3(1, 2, 3), NodeParams{});
  const Model m = b.build();
  EXPECT_GT(m.dt_safe_rest(), 0.0);
  State s = make_state(m);
  s.f_ext.row(0) = Vec3(0, 0, 0.02).transpose();  // k_r = 0.02 N/mm: static displacement 1 mm
  for (int k = 0; k < 4000; ++k) ASSERT_TRUE(step(m, s, {}).ok());
  EXPECT_NEAR(s.x(0, 2), 4.0, 1e-6);
  // a free particle (no return spring): the bound is infinite-like, still finite motion
  ModelBuilder f("free");
  f.add_node(Vec3(0, 0, 0), 1.0, 0.5, 0.0);
  const Model mf = f.build();
  State sf = make_state(mf);
  sf.f_ext(0, 0) = 1.0;
  EXPECT_TRUE(step(mf, sf, {}).ok());
  EXPECT_TRUE(sf.x.allFinite());
}

// ---- unit scales: the same phantom from 1e-6 to 1e6 ----

TEST(ExtremeScales, ScaledPhantomBuildsWithScaleInvariantStepAndResponse) {
  // Mass-spring with the same k and m and Strain Duffing (k' = k / L0^2) is scale-free: omega does
  // not depend on lengths, and a force scaled by s gives the displacement scaled by s (velocities too,
  // so the guard's absolute v_max is scaled with the model).
  double ref_dt = 0, ref_disp = 0;
  for (double s : {1.0, 1e-6, 1e-3, 1e3, 1e6}) {
    SurfaceMesh m = kidney_phantom();
    m.V *= s;
    auto body = std::make_shared<HybridKidney>(m, s * kidney_phantom_atoms(), HybridSettings{}, "scaled");
    SimulationSettings st;
    st.step.v_max = 100.0 * std::max(1.0, s);  // the guard's speed limit is absolute (mm/ms)
    Simulation sim(body, st);
    sim.set_loads({{.node = 223, .force = Vec3(0, 0, -s), .t_ramp = 20, .t_release = 100}});
    sim.advance(200);
    ASSERT_TRUE(finite(sim)) << "scale " << s;
    const double dt = body->model().dt_safe_rest(), disp = max_displacement(sim) / s;
    if (s == 1.0) {
      ref_dt = dt;
      ref_disp = disp;
    }
    EXPECT_NEAR(dt / ref_dt, 1.0, 1e-9) << "scale " << s;
    EXPECT_NEAR(disp / ref_disp, 1.0, 1e-6) << "scale " << s;
    sim.advance(2000);
    EXPECT_LT(max_displacement(sim) / s, 1e-6) << "scale " << s;
  }
}

// ---- NaN in forces or positions ----

TEST(ExtremeNaN, NaNForceDropsTheFrameRestoresTheStateAndIsReported) {
  for (Integrator integ : {Integrator::SymplecticEuler, Integrator::ImplicitEuler}) {
    auto body = kidney();
    const Model& m = body->model();
    State s = make_state(m);
    s.f_ext.row(223) = Vec3(0, 0, -1).transpose();
    for (int k = 0; k < 40; ++k) step(m, s, {.integrator = integ});
    const MatX3 x = s.x;
    s.f_ext(100, 1) = kNaN;
    const StepStatus st = step(m, s, {.integrator = integ});
    EXPECT_EQ(st.code, StepCode::Failed) << to_string(integ);
    EXPECT_TRUE(s.x.allFinite() && s.v.allFinite());
    EXPECT_LT((s.x - x).cwiseAbs().maxCoeff(), 1e-12);  // restored (up to the undo's rounding)
    EXPECT_GT(s.warnings.nonfinite, 0u);
    EXPECT_EQ(s.warnings.failed, 1u);
    EXPECT_EQ(s.t, 20.5);
    s.f_ext(100, 1) = 0.0;  // the next good frame proceeds
    EXPECT_EQ(step(m, s, {.integrator = integ}).code, StepCode::Ok);
  }
}

TEST(ExtremeNaN, NaNPositionsAndLoadsAreRefusedAtTheApi) {
  Simulation sim(kidney());
  State s = sim.state();
  s.x(7, 0) = kNaN;
  EXPECT_THROW(sim.set_state(s), InvalidInput);
  EXPECT_THROW(sim.set_loads({{.node = 3, .force = Vec3(kNaN, 0, 0)}}), InvalidInput);
  EXPECT_THROW(sim.set_loads({{.node = 3, .force = Vec3(0, 0, 1), .t_on = kNaN}}), InvalidInput);
  EXPECT_TRUE(finite(sim));
}

TEST(ExtremeNaN, StatesBeyondReachAreRefusedAtTheApi) {
  // finite but absurd (found by fuzz_checkpoint: 1e307 mm overflowed the SMRM surface map to NaN)
  Simulation sim(kidney());
  State s = sim.state();
  s.x(7, 1) = 1e307;
  try {
    sim.set_state(s);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("state.x: node 7 is 1e+307 mm from its rest position"), std::string::npos)
        << e.what();
  }
  s = sim.state();
  s.v(3, 0) = 1e200;
  EXPECT_THROW(sim.set_state(s), InvalidInput);
  s = sim.state();
  s.x(7, 1) += 1e3;  // far, but physical: accepted
  s.v(3, 0) = 1e3;
  EXPECT_NO_THROW(sim.set_state(s));
  EXPECT_TRUE(finite(sim));
}

TEST(ExtremeNaN, NaNWrittenIntoThePositionsIsContainedAndReportedEveryFrame) {
  // A caller writing NaN straight into state().x bypasses set_state: every frame is then dropped
  // and reported, and the NaN does not spread to any other node.
  Simulation sim(kidney());
  sim.state().x(7, 0) = kNaN;
  for (int k = 0; k < 5; ++k) EXPECT_EQ(sim.update().code, StepCode::Failed);
  EXPECT_EQ(sim.state().warnings.failed, 5u);
  MatX3 others = sim.state().x;
  others.row(7).setZero();
  EXPECT_TRUE(others.allFinite());
  EXPECT_TRUE(sim.state().v.allFinite());
  EXPECT_EQ(sim.time(), 2.5);
}

}  // namespace
}  // namespace medspring
