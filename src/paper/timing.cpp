// The cases and the timing protocol of Tables I and II (paper/timing.hpp).
#include "medspring/paper/timing.hpp"

#include <algorithm>
#include <chrono>
#include <memory>

#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/tube_hybrid.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring::paper {

namespace {

constexpr Index kSpokes = 30;

struct Setup {
  BodyPtr body;
  Index node = 0;
  Vec3 force = Vec3::Zero();
};

// The model and held force of a case: vessel strong force 0.5 N inward at ring 20, spoke 0 (+y side,
// so along -y, transverse to the axis); kidney 1.0 N at node 223 towards atom 21 (§7.1).
Setup make_setup(const std::string& model, bool nonlinear) {
  Setup s;
  if (model == "SMRM") {
    SmrmSettings st;
    st.chain.nonlinear = nonlinear;
    s.body =
        std::make_shared<SmrmVessel>(smrm_phantom(VesselPath::StraightX, CrossSectionShape::Circular, st));
    s.node = 20 * kSpokes;
    s.force = Vec3(0, -0.5, 0);
  } else if (model == "MS") {
    s.body = std::make_shared<TubeHybridBody>(TubeHybridSettings{.nonlinear = nonlinear});
    s.node = 20 * kSpokes;
    s.force = Vec3(0, -0.5, 0);
  } else {
    HybridSettings h;
    h.nonlinear = nonlinear;
    auto k = std::make_shared<HybridKidney>(hybrid_kidney_phantom(h));
    s.node = 223;
    const Model& m = k->model();
    s.force = -(m.x0.row(223) - m.x0.row(k->atom_dof(21))).normalized().transpose();
    s.body = k;
  }
  return s;
}

std::shared_ptr<Simulation> make_simulation(const TimingCase& c) {
  const Setup s = make_setup(c.model, c.nonlinear);
  SimulationSettings settings;
  settings.step.dt = 0.5;
  settings.local.enabled = c.local != "off";
  settings.local.settings.cache_local = c.local == "cache";
  auto sim = std::make_shared<Simulation>(s.body, settings);
  PointLoad L;
  L.node = s.node;
  L.force = s.force;
  L.t_ramp = 0.0;  // held constant from the first update
  sim->set_loads({L});
  return sim;
}

TimingCase make_case(const std::string& model, bool nonlinear, const std::string& local) {
  TimingCase c;
  c.model = model;
  c.nonlinear = nonlinear;
  c.local = local;
  std::string name = "table_";
  if (model == "MS") name += "ms_tube_1200";
  if (model == "SMRM") name += "smrm_1200";
  if (model == "kidney MS") name += "kidney_hybrid_500";
  name += nonlinear ? "_nonlinear" : "_linear";
  if (local != "off") name += "_local_" + local;
  c.name = name;
  c.nodes = model == "SMRM" ? 40 + 1200 : model == "MS" ? 1240 : 500;
  c.springs = model == "SMRM" ? 39 : model == "MS" ? 3540 + 39 + 1200 : 0;
  const TimingCase copy = c;
  c.setup = [copy] {
    auto sim = make_simulation(copy);
    return std::function<void()>([sim] { sim->update(); });
  };
  return c;
}

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

std::vector<TimingCase> timing_cases() {
  std::vector<TimingCase> out;
  for (const std::string model : {"MS", "SMRM", "kidney MS"}) {
    out.push_back(make_case(model, false, "off"));
    out.push_back(make_case(model, true, "off"));
    out.push_back(make_case(model, true, "no_cache"));
    out.push_back(make_case(model, true, "cache"));
  }
  for (TimingCase& c : out)
    if (c.model == "kidney MS") c.springs = make_setup(c.model, true).body->model().num_springs();
  return out;
}

TimingCaseInfo timing_case_info(const TimingCase& c) {
  auto sim = make_simulation(c);
  for (int i = 0; i < 100; ++i) sim->update();
  const auto before = sim->state().substeps;
  for (int i = 0; i < 100; ++i) sim->update();
  TimingCaseInfo info;
  const Model& m = sim->model();
  info.masses = m.num_nodes();
  info.springs = m.num_springs();
  info.surface_nodes = sim->body().num_surface_nodes();
  info.dt_safe_rest_ms = m.dt_safe_rest();
  info.substeps_per_update = static_cast<double>(sim->state().substeps - before) / 100.0;
  return info;
}

std::vector<TimedCase> time_cases(const std::vector<TimingCase>& list, const TimingProtocol& p,
                                  const std::function<void(double)>& progress) {
  using clock_type = std::chrono::steady_clock;
  require(p.warmup >= 0 && p.rounds >= 1 && p.per_round >= 1, "timing: warmup >= 0, rounds >= 1 and ",
          "per_round >= 1 needed (got ", p.warmup, ", ", p.rounds, ", ", p.per_round, ")");
  std::vector<TimedCase> cases;
  std::vector<std::function<void()>> update;
  for (const auto& c : list) {
    TimedCase t;
    t.c = c;
    t.info = timing_case_info(c);
    cases.push_back(std::move(t));
    update.push_back(c.setup());
  }
  for (auto& u : update)
    for (long i = 0; i < p.warmup; ++i) u();
  const double total = static_cast<double>(p.rounds * static_cast<long>(cases.size()));
  for (long r = 0; r < p.rounds; ++r)
    for (std::size_t k = 0; k < cases.size(); ++k) {
      std::vector<double> round;
      round.reserve(static_cast<std::size_t>(p.per_round));
      for (long i = 0; i < p.per_round; ++i) {
        const auto a = clock_type::now();
        update[k]();
        round.push_back(std::chrono::duration<double, std::micro>(clock_type::now() - a).count());
      }
      cases[k].us.insert(cases[k].us.end(), round.begin(), round.end());
      cases[k].round_medians.push_back(median_of(round));
      if (progress)
        progress(static_cast<double>(r * static_cast<long>(cases.size()) + static_cast<long>(k) + 1) / total);
    }
  for (auto& t : cases) {
    std::vector<double> v = t.us;
    std::sort(v.begin(), v.end());
    t.median = v[v.size() / 2];
    t.p90 = v[static_cast<std::size_t>(0.9 * static_cast<double>(v.size() - 1))];
    double s = 0;
    for (double x : v) s += x;
    t.mean = s / static_cast<double>(v.size());
    const auto [lo, hi] = std::minmax_element(t.round_medians.begin(), t.round_medians.end());
    t.spread = (*hi - *lo) / t.median;
  }
  return cases;
}

const TimedCase& find_case(const std::vector<TimedCase>& cs, const std::string& model, bool nl,
                           const std::string& local) {
  for (const auto& c : cs)
    if (c.c.model == model && c.c.nonlinear == nl && c.c.local == local) return c;
  throw InvalidInput(cat("paper: no timing case ", model, nl ? " nonlinear" : " linear", " local ", local));
}

}  // namespace medspring::paper
