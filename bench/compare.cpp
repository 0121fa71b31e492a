#include "compare.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <numeric>
#include <random>

#include "medspring/core/check.hpp"
#include "medspring/geometry/locality.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/physics/state.hpp"

namespace medspring::bench {

#ifdef MEDSPRING_HAVE_BULLET
// bullet_tube.cpp: btSoftBody built from the tube; fills its settings and payload bytes per node.
std::function<void()> make_bullet_update(const TubeData& tube, std::string& settings, double& bytes_per_node);
bool bullet_available() {
  return true;
}
#else
bool bullet_available() {
  return false;
}
#endif

namespace {

using clock_type = std::chrono::steady_clock;

double seconds_since(clock_type::time_point t0) {
  return std::chrono::duration<double>(clock_type::now() - t0).count();
}

}  // namespace

std::string size_name(long nodes) {
  if (nodes >= 1000000 && nodes % 1000000 == 0) return cat("tube_", nodes / 1000000, "M");
  if (nodes >= 1000) return cat("tube_", std::round(static_cast<double>(nodes) / 100.0) / 10.0, "k");
  return cat("tube_", nodes);
}

namespace {

struct Tube {
  Model model;
  std::vector<Index> new_of_old;  // tube node (ring-by-ring numbering) -> model node
};

// The tube in the node order asked for: "built" (ring by ring, as tube() numbers it), "shuffled" (a
// fixed random permutation: what an unordered mesh looks like) or "rcm" (the shuffled tube put back
// into reverse Cuthill-McKee order by locality_order, as the builders do for their meshes).
Tube tube_model(const TubeSize& size, const std::string& order) {
  const double radius = std::max(3.0, 2.5 * static_cast<double>(size.spokes) / (2.0 * std::numbers::pi));
  SurfaceMesh mesh = tube(size.rings, size.spokes, 2.5, radius);
  const auto n = static_cast<std::size_t>(mesh.num_vertices());
  std::vector<Index> old_of_new(n);
  std::iota(old_of_new.begin(), old_of_new.end(), 0);
  if (order != "built") {
    std::mt19937_64 rng(15);
    std::shuffle(old_of_new.begin(), old_of_new.end(), rng);
    mesh = permute_vertices(mesh, old_of_new);
    if (order == "rcm") {
      const std::vector<Index> rcm = locality_order(mesh);
      mesh = permute_vertices(mesh, rcm);
      std::vector<Index> composed(n);
      for (std::size_t k = 0; k < n; ++k) composed[k] = old_of_new[static_cast<std::size_t>(rcm[k])];
      old_of_new = std::move(composed);
    }
  }
  Tube t;
  t.new_of_old = inverse_permutation(old_of_new);
  SurfaceBodyParams p;  // Strain Duffing law, k 0.05 N/mm, kidney node parameters
  for (Index j = 0; j < size.spokes; ++j) {
    p.fixed.push_back(t.new_of_old[static_cast<std::size_t>(j)]);
    p.fixed.push_back(t.new_of_old[static_cast<std::size_t>((size.rings - 1) * size.spokes + j)]);
  }
  t.model = make_surface_model(mesh, p, size_name(size.nodes()));
  return t;
}

}  // namespace

Model tube_model(const TubeSize& size) {
  return tube_model(size, "built").model;
}

namespace {

TubeData tube_data(const Model& m, const TubeSize& size, const std::vector<Index>& new_of_old) {
  TubeData d;
  const auto n = static_cast<std::size_t>(m.num_nodes());
  d.x0.assign(m.x0.data(), m.x0.data() + 3 * n);
  d.mass.assign(m.mass.data(), m.mass.data() + n);
  d.damping.assign(m.damping.data(), m.damping.data() + n);
  d.kr.assign(m.kr.data(), m.kr.data() + n);
  d.fixed = m.fixed;
  d.si = m.springs.i;
  d.sj = m.springs.j;
  d.L0 = m.springs.L0;
  d.k = m.springs.k;
  d.kp = m.springs.kp;
  d.load_node = new_of_old[static_cast<std::size_t>((size.rings / 2) * size.spokes + size.spokes / 4)];
  return d;
}

// The floor: the straightforward single-threaded scalar loop of a mass-spring step. Return springs, the
// same spring law (eq. 5), damping along the spring, symplectic Euler; interleaved xyz; nothing else.
struct PlainLoop {
  std::vector<double> x, v, f, x0, fe, kr, im;  // im: 1/m (0 for anchored nodes)
  std::vector<Index> si, sj;
  std::vector<double> L0, k, kp;
  double c = 0.15;  // damping along the spring (g/ms), ~ the node damping beta m of the tube
  int substeps = 1;
  double h = 0.5;

  explicit PlainLoop(const TubeData& d, int subs)
      : x(d.x0),
        v(d.x0.size(), 0.0),
        f(d.x0.size(), 0.0),
        x0(d.x0),
        fe(d.x0.size(), 0.0),
        kr(d.kr),
        im(d.mass.size()),
        si(d.si),
        sj(d.sj),
        L0(d.L0),
        k(d.k),
        kp(d.kp),
        substeps(subs),
        h(d.dt / subs) {
    for (std::size_t a = 0; a < im.size(); ++a) im[a] = d.fixed[a] ? 0.0 : 1.0 / d.mass[a];
    for (int q = 0; q < 3; ++q)
      fe[3 * static_cast<std::size_t>(d.load_node) + static_cast<std::size_t>(q)] = d.load[q];
  }

  void update() {
    const std::size_t n = im.size(), ns = si.size();
    double* X = x.data();
    double* V = v.data();
    double* F = f.data();
    for (int sub = 0; sub < substeps; ++sub) {
      for (std::size_t a = 0; a < n; ++a)
        for (std::size_t q = 3 * a; q < 3 * a + 3; ++q) F[q] = fe[q] - kr[a] * (X[q] - x0[q]);
      for (std::size_t s = 0; s < ns; ++s) {
        const std::size_t a = 3 * static_cast<std::size_t>(si[s]), b = 3 * static_cast<std::size_t>(sj[s]);
        const double ex = X[b] - X[a], ey = X[b + 1] - X[a + 1], ez = X[b + 2] - X[a + 2];
        const double L = std::sqrt(ex * ex + ey * ey + ez * ez);
        const double inv = 1.0 / L;
        const double d = L - L0[s];
        const double rv = (V[b] - V[a]) * ex + (V[b + 1] - V[a + 1]) * ey + (V[b + 2] - V[a + 2]) * ez;
        const double t = (d * (k[s] + kp[s] * d * d) + c * rv * inv) * inv;
        const double fx = t * ex, fy = t * ey, fz = t * ez;
        F[a] += fx;
        F[a + 1] += fy;
        F[a + 2] += fz;
        F[b] -= fx;
        F[b + 1] -= fy;
        F[b + 2] -= fz;
      }
      for (std::size_t a = 0; a < n; ++a) {
        const double w = h * im[a];
        for (std::size_t q = 3 * a; q < 3 * a + 3; ++q) {
          V[q] += w * F[q];
          X[q] += h * V[q];
        }
      }
    }
  }
  double bytes_per_node() const {
    const double n = static_cast<double>(im.size()), ns = static_cast<double>(si.size());
    return (n * 8.0 * (3 * 5 + 2) + ns * (2 * sizeof(Index) + 3 * 8.0)) / n;
  }
};

double medspring_bytes_per_node(const Model& m, const State& s) {
  const double n = static_cast<double>(m.num_nodes()), ns = static_cast<double>(m.num_springs());
  auto mat = [](const MatX3& a) { return 8.0 * static_cast<double>(a.size()); };
  auto vec = [](const VecX& a) { return 8.0 * static_cast<double>(a.size()); };
  double b = mat(m.x0) + vec(m.mass) + vec(m.damping) + vec(m.kr) + n + vec(m.inv_k) +
             4.0 * static_cast<double>(m.free_nodes.size()) + ns * (2 * sizeof(Index) + 3 * 8.0);
  b += mat(s.x) + mat(s.v) + mat(s.f_ext) + mat(s.f) + mat(s.x_save) + mat(s.v_save) + mat(s.x_trial) +
       vec(s.step_coef);
  for (const VecX* v : {&s.cg_r, &s.cg_z, &s.cg_p, &s.cg_q, &s.dv, &s.rhs, &s.jacobi}) b += vec(*v);
  b += vec(s.spring_a) + vec(s.spring_b) + mat(s.spring_n);
  b += vec(s.spring_force) +
       static_cast<double>(sizeof(Index)) *
           static_cast<double>(m.gather.row.size() + m.gather.extra_begin.size() + m.gather.extra.size());
  return b / n;
}

CompareResult finish(CompareResult r) {
  r.ns_per_spring = 1000.0 * r.timing.median_us / (static_cast<double>(r.springs) * r.substeps);
  return r;
}

}  // namespace

std::vector<CompareResult> run_compare(const CompareOptions& o,
                                       const std::function<void(const CompareResult&)>& on_result) {
  std::vector<CompareResult> out;
  auto emit = [&](CompareResult r) {
    r = finish(std::move(r));
    if (on_result) on_result(r);
    out.push_back(std::move(r));
  };
  std::vector<TubeSize> sizes = o.sizes;
  if (sizes.empty()) sizes = {{40, 30}, {100, 100}, {400, 250}, {1000, 1000}};
  for (const TubeSize& size : sizes) {
    auto t0 = clock_type::now();
    Tube built = tube_model(size, o.order);
    const auto model = std::make_shared<const Model>(std::move(built.model));
    const double build_s = seconds_since(t0);
    const TubeData data = tube_data(*model, size, built.new_of_old);
    built.new_of_old = {};
    CompareResult base;
    base.name = size_name(size.nodes());
    base.nodes = model->num_nodes();
    base.springs = model->num_springs();
    // MedSpring's substeps per update on this tube (the stiffening under the load sets them): the plain
    // loop does as many, so that the two do the same work. Measured on a short untimed run first.
    double medspring_substeps = 1;
    {
      StepSettings st;
      st.dt = data.dt;
      State state = make_state(*model, st);
      for (int q = 0; q < 3; ++q) state.f_ext(data.load_node, q) = data.load[q];
      const int frames = model->num_nodes() > 200000 ? 4 : 40;
      for (int f = 0; f < frames; ++f) step(*model, state, st);
      const std::uint64_t before = state.substeps;
      for (int f = 0; f < frames; ++f) step(*model, state, st);
      medspring_substeps = static_cast<double>(state.substeps - before) / frames;
    }
    {
      const int subs = std::max(1, static_cast<int>(std::lround(medspring_substeps)));
      auto plain = std::make_shared<PlainLoop>(data, subs);
      CompareResult r = base;
      r.engine = "plain";
      r.substeps = subs;
      r.bytes_per_node = plain->bytes_per_node();
      r.settings = cat("reference scalar loop, ", subs, " substeps of ", plain->h, " ms (as MedSpring)");
      BenchCase c;
      c.setup = [plain] { return std::function<void()>([plain] { plain->update(); }); };
      r.timing = time_case(c, 200, o.samples, o.budget_s);
      emit(r);
    }
    for (const int threads : o.threads) {
      StepSettings st;
      st.dt = data.dt;
      st.threads = threads;
      auto state = std::make_shared<State>(make_state(*model, st));  // symplectic scratch only
      for (int q = 0; q < 3; ++q) state->f_ext(data.load_node, q) = data.load[q];
      CompareResult r = base;
      r.engine = "medspring";
      r.threads = threads;
      r.threads_used = effective_threads(*model, st);
      r.build_s = build_s;
      r.bytes_per_node = medspring_bytes_per_node(*model, *state);
      r.settings = cat("symplectic Euler + implicit node damping, guard on, dt ", st.dt, " ms");
      BenchCase c;
      const std::uint64_t before = state->substeps;
      std::uint64_t frames = 0;
      c.setup = [&] {
        return std::function<void()>([&, model, state] {
          step(*model, *state, st);
          ++frames;
        });
      };
      r.timing = time_case(c, 200, o.samples, o.budget_s);
      r.substeps = static_cast<double>(state->substeps - before) /
                   static_cast<double>(std::max<std::uint64_t>(frames, 1));
      emit(r);
    }
#ifdef MEDSPRING_HAVE_BULLET
    if (o.bullet) {
      CompareResult r = base;
      r.engine = "bullet";
      t0 = clock_type::now();
      std::function<void()> update = make_bullet_update(data, r.settings, r.bytes_per_node);
      r.build_s = seconds_since(t0);
      BenchCase c;
      c.setup = [&update] { return update; };
      r.timing = time_case(c, 20, o.samples, o.budget_s);
      emit(r);
    }
#endif
  }
  return out;
}

double fitted_exponent(const std::vector<CompareResult>& results, const std::string& engine, int threads) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (const CompareResult& r : results) {
    if (r.engine != engine || r.threads != threads || r.timing.median_us <= 0) continue;
    const double x = std::log(static_cast<double>(r.nodes)), y = std::log(r.timing.median_us);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
  }
  if (n < 2) return 0.0;
  const double den = n * sxx - sx * sx;
  return den > 0 ? (n * sxy - sx * sy) / den : 0.0;
}

}  // namespace medspring::bench
