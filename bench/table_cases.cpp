#include "table_cases.hpp"

#include <memory>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring::bench {

namespace {

constexpr Index kRings = 40, kSpokes = 30;

/// The MS column of D-18: the hybrid mass-spring applied to the vessel geometry. 1200 surface nodes
/// with tube-grid springs (k_surf) + 40 atoms on the axis (centerline springs k_cl), one spoke per
/// surface node to its ring's atom (k_spoke), return springs on every node, end rings and end atoms
/// fixed, kidney per-node parameters (0.3 g, beta 0.5/ms, k_r 0.02 N/mm; §9).
class TubeHybridBody final : public Body {
 public:
  explicit TubeHybridBody(bool nonlinear) {
    const SurfaceMesh t = tube(kRings, kSpokes, 2.5, 3.0);
    const Index S = t.num_vertices();
    const HybridSettings h;  // kidney parameters
    DuffingSettings d = h.duffing;
    if (!nonlinear) d.mode = DuffingMode::Linear;
    ModelBuilder b("vessel hybrid MS (D-18)");
    for (Index r = 0; r < S; ++r) b.add_node(t.V.row(r).transpose(), h.surface_node);
    for (Index i = 0; i < kRings; ++i) b.add_node(Vec3(2.5 * static_cast<double>(i), 0, 0), h.atom_node);
    const MatX2i edges = unique_edges(t.F);
    for (Index e = 0; e < edges.rows(); ++e) b.add_spring(edges(e, 0), edges(e, 1), h.k_surf, d);
    for (Index i = 0; i + 1 < kRings; ++i) b.add_spring(S + i, S + i + 1, h.k_cl, d);
    for (Index i = 0; i < kRings; ++i)
      for (Index j = 0; j < kSpokes; ++j) b.add_spring(i * kSpokes + j, S + i, h.k_spoke, d);
    fixed_surface_.assign(static_cast<std::size_t>(S), 0);
    for (Index j = 0; j < kSpokes; ++j) {
      for (const Index r : {j, (kRings - 1) * kSpokes + j}) {
        b.set_fixed(r);
        fixed_surface_[static_cast<std::size_t>(r)] = 1;
      }
    }
    b.set_fixed(S);
    b.set_fixed(S + kRings - 1);
    model_ = b.build();
    F_ = t.F;
    rest_ = t.V;
    k_ = h.k_surf;
  }
  std::string kind() const override { return "hybrid"; }
  const Model& model() const override { return model_; }
  const MatX3i& faces() const override { return F_; }
  const MatX3& rest_surface() const override { return rest_; }
  void map_to_surface(const State& state, MatX3& surface) const override {
    surface = state.x.topRows(rest_.rows());
  }
  void transfer_force(Index node, const Vec3& F, MatX3& f_dof) const override {
    f_dof.row(node) += F.transpose();
  }
  GridLayout grid() const override { return {kRings, kSpokes}; }
  double local_stiffness() const override { return k_; }
  std::vector<std::uint8_t> fixed_surface_nodes() const override { return fixed_surface_; }

 private:
  Model model_;
  MatX3i F_;
  MatX3 rest_;
  std::vector<std::uint8_t> fixed_surface_;
  double k_ = 0.05;
};

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
    s.body = std::make_shared<TubeHybridBody>(nonlinear);
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

std::shared_ptr<Simulation> make_simulation(const TableCase& c) {
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

TableCase make_case(const std::string& model, bool nonlinear, const std::string& local) {
  TableCase c;
  c.model = model;
  c.nonlinear = nonlinear;
  c.local = local;
  std::string name = "table_";
  if (model == "MS") name += "ms_tube_1200";
  if (model == "SMRM") name += "smrm_1200";
  if (model == "kidney MS") name += "kidney_hybrid_500";
  name += nonlinear ? "_nonlinear" : "_linear";
  if (local != "off") name += "_local_" + local;
  c.bench.name = name;
  c.bench.group = "table";
  c.bench.nodes = model == "SMRM" ? 40 + 1200 : model == "MS" ? 1240 : 500;
  c.bench.springs = model == "SMRM" ? 39 : model == "MS" ? 3540 + 39 + 1200 : 0;
  const TableCase copy = c;
  c.bench.setup = [copy] {
    auto sim = make_simulation(copy);
    return std::function<void()>([sim] { sim->update(); });
  };
  return c;
}

}  // namespace

std::vector<TableCase> table_cases() {
  std::vector<TableCase> out;
  for (const std::string model : {"MS", "SMRM", "kidney MS"}) {
    out.push_back(make_case(model, false, "off"));
    out.push_back(make_case(model, true, "off"));
    out.push_back(make_case(model, true, "no_cache"));
    out.push_back(make_case(model, true, "cache"));
  }
  for (TableCase& c : out)
    if (c.model == "kidney MS") c.bench.springs = make_setup(c.model, true).body->model().num_springs();
  return out;
}

TableCaseInfo table_case_info(const TableCase& c) {
  auto sim = make_simulation(c);
  for (int i = 0; i < 100; ++i) sim->update();
  const auto before = sim->state().substeps;
  for (int i = 0; i < 100; ++i) sim->update();
  TableCaseInfo info;
  const Model& m = sim->model();
  info.masses = m.num_nodes();
  info.springs = m.num_springs();
  info.surface_nodes = sim->body().num_surface_nodes();
  info.dt_safe_rest_ms = m.dt_safe_rest();
  info.substeps_per_update = static_cast<double>(sim->state().substeps - before) / 100.0;
  return info;
}

}  // namespace medspring::bench
