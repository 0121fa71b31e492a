#include "cases.hpp"

#include <algorithm>
#include <chrono>
#include <limits>
#include <memory>
#include <numbers>
#include <numeric>
#include <random>

#include "medspring/geometry/locality.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
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

// Locality (issue 15): a hybrid model (tube surface + atoms on its axis and their spokes, kidney
// parameters) built from a mesh whose numbering is shuffled, simulated as numbered (`shuffled`) or
// renumbered for locality by HybridKidney (`rcm`, its default for this size). Same nodes, springs, load.
BenchCase hybrid_locality_case(const std::string& name, Index rings, Index spokes, bool renumber) {
  BenchCase b;
  b.name = name;
  b.group = "locality";
  const Index atoms = 100;
  b.nodes = static_cast<long>(rings) * spokes + atoms;
  b.springs = 0;  // surface edges + centerline + spokes (counted at build)
  b.setup = [=] {
    const double radius = 2.5 * static_cast<double>(spokes) / (2.0 * std::numbers::pi);
    const SurfaceMesh t = tube(rings, spokes, 2.5, radius);
    std::vector<Index> order(static_cast<std::size_t>(t.num_vertices()));
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), std::mt19937_64(15));
    const SurfaceMesh m = permute_vertices(t, order);
    MatX3 A = MatX3::Zero(atoms, 3);
    for (Index a = 0; a < atoms; ++a)
      A(a, 0) =
          2.5 * static_cast<double>(rings - 1) * (static_cast<double>(a) + 0.5) / static_cast<double>(atoms);
    const std::vector<Index> user = inverse_permutation(order);  // tube node -> the mesh's numbering
    HybridSettings hs;                                           // one end ring pinned
    for (Index j = 0; j < spokes; ++j) hs.fixed.push_back(user[static_cast<std::size_t>(j)]);
    auto body = std::make_shared<HybridKidney>(m, A, hs, name, nullptr,
                                               renumber ? Index{0} : std::numeric_limits<Index>::max());
    auto sim = std::make_shared<Sim>();
    sim->model = body->model();
    sim->settings.dt = 0.5;
    sim->state = make_state(sim->model, sim->settings);
    const Index c = body->dof_of(user[static_cast<std::size_t>((rings / 2) * spokes)]);
    sim->state.f_ext.row(c) = Vec3(0, 0, -0.5).transpose();
    return std::function<void()>([sim] { step(sim->model, sim->state, sim->settings); });
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
  if (options.large)
    for (const bool renumber : {false, true})
      cases.push_back(hybrid_locality_case(
          renumber ? "locality_hybrid_100k_rcm" : "locality_hybrid_100k_shuffled", 400, 250, renumber));
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
