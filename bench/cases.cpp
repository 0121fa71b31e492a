#include "cases.hpp"

#include <algorithm>
#include <chrono>
#include <memory>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/physics/state.hpp"
#if MEDSPRING_BENCH_TABLES
#include "table_cases.hpp"
#endif

namespace medspring::bench {

namespace {

struct Sim {
  Model model;
  State state;
  StepSettings settings;
};

// A surface mass-spring body under a held force at node c (D-18: force constant, cubic terms active).
std::function<void()> surface_update(const SurfaceMesh& mesh, bool nonlinear, Integrator integrator, Index c,
                                     const Vec3& F) {
  SurfaceBodyParams p;
  if (!nonlinear) p.duffing.mode = DuffingMode::Linear;
  auto sim = std::make_shared<Sim>();
  sim->model = make_surface_model(mesh, p, "bench");
  sim->settings.dt = 0.5;
  sim->settings.integrator = integrator;
  sim->state = make_state(sim->model, sim->settings);  // scratch of this integrator only, as Simulation
  sim->state.f_ext.row(c) = F.transpose();
  return [sim] { step(sim->model, sim->state, sim->settings); };
}

BenchCase tube_case(const std::string& name, const std::string& group, Index rings, Index spokes,
                    bool nonlinear, Integrator integrator = Integrator::SymplecticEuler) {
  BenchCase b;
  b.name = name;
  b.group = group;
  b.nodes = static_cast<long>(rings) * spokes;
  b.springs = static_cast<long>(spokes) * rings + 2L * spokes * (rings - 1);
  b.setup = [=] {
    const SurfaceMesh m = tube(rings, spokes, 2.5, 3.0);
    const Index c = (rings / 2) * spokes + spokes / 4;
    return surface_update(m, nonlinear, integrator, c, Vec3(0, 0, -0.5));
  };
  return b;
}

}  // namespace

std::vector<BenchCase> all_cases(const CaseOptions& options) {
  std::vector<BenchCase> cases;
  cases.push_back(tube_case("tube_1200_explicit_linear", "core", 40, 30, false));
  cases.push_back(tube_case("tube_1200_explicit_nonlinear", "core", 40, 30, true));
  cases.push_back(tube_case("tube_1200_implicit_nonlinear", "core", 40, 30, true, Integrator::ImplicitEuler));
  {
    BenchCase b;
    b.name = "kidney_phantom_surface_458_explicit_nonlinear";
    b.group = "kidney";
    b.nodes = 458;
    b.springs = 1368;
    b.setup = [] {
      return surface_update(kidney_phantom(), true, Integrator::SymplecticEuler, 223, Vec3(0, 0, -1.0));
    };
    cases.push_back(b);
  }
  cases.push_back(tube_case("scaling_tube_10k_explicit_nonlinear", "scaling", 100, 100, true));
  cases.push_back(tube_case("scaling_tube_100k_explicit_nonlinear", "scaling", 400, 250, true));
  if (options.large) cases.push_back(tube_case("tube_1M_explicit_nonlinear", "scaling", 1000, 1000, true));
#if MEDSPRING_BENCH_TABLES
  for (TableCase& t : table_cases()) cases.push_back(std::move(t.bench));  // Tables I and II (D-18)
#endif
  return cases;
}

Timing time_case(const BenchCase& c, long warmup, long samples, double budget_s) {
  using clock = std::chrono::steady_clock;
  const auto update = c.setup();
  const auto t0 = clock::now();
  update();
  const double first = std::chrono::duration<double>(clock::now() - t0).count();
  const long cap = std::max(10L, static_cast<long>(budget_s / std::max(first, 1e-9)));
  warmup = std::min(warmup, std::max(1L, cap / 10));
  samples = std::min(samples, cap);
  for (long i = 0; i < warmup; ++i) update();
  std::vector<double> us(static_cast<std::size_t>(samples));
  for (auto& u : us) {
    const auto a = clock::now();
    update();
    u = std::chrono::duration<double, std::micro>(clock::now() - a).count();
  }
  Timing t;
  t.samples = samples;
  double sum = 0;
  for (double u : us) sum += u;
  t.mean_us = sum / static_cast<double>(samples);
  std::sort(us.begin(), us.end());
  t.min_us = us.front();
  t.median_us = us[us.size() / 2];
  t.p99_us = us[std::min(us.size() - 1, static_cast<std::size_t>(0.99 * static_cast<double>(us.size())))];
  return t;
}

}  // namespace medspring::bench
