// The Engine of the JavaScript API (web/src/engine.hpp, docs/web.md): the model (a built-in phantom or a
// model package) and its display buffers, time and automatic resets, and the tissue settings.
#include "engine.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_tree.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"

namespace medspring::web {
namespace {

BodyPtr builtin_body(const std::string& name, bool nonlinear) {
  if (name == "kidney_phantom") {
    HybridSettings hs;
    hs.nonlinear = nonlinear;
    return std::make_shared<HybridKidney>(hybrid_kidney_phantom(hs));
  }
  if (name == "tube") {
    SurfaceBodyParams p;
    if (!nonlinear) p.duffing.mode = DuffingMode::Linear;
    return std::make_shared<SurfaceBody>(tube(40, 30, 2.5, 3.0), p, "tube", GridLayout{40, 30});
  }
  if (name == "vessel_phantom") {
    SmrmSettings s;
    s.chain.nonlinear = nonlinear;
    return std::make_shared<SmrmVessel>(smrm_phantom(VesselPath::StraightX, CrossSectionShape::Circular, s));
  }
  throw InvalidInput("unknown model '" + name + "' (expected kidney_phantom, tube or vessel_phantom)");
}

}  // namespace

Engine::Engine(const val& model, bool nonlinear, bool local) {
  if (model.isString()) {
    const std::string name = model.as<std::string>();
    body_ = builtin_body(name, nonlinear);
    package_ = package_of(*body_, name, "bundled procedural model");
  } else {
    package_ = decode_model_package(bytes_of(model), "model package");
    if (tissue_params(package_).nonlinear != nonlinear) {
      TissueParams t = tissue_params(package_);
      t.nonlinear = nonlinear;
      set_tissue_params(package_, t);
    }
    body_ = make_body(package_);
  }
  SimulationSettings s;
  s.local.enabled = local;
  s.normals = false;  // three.js computes normals on the GPU side
  sim_ = std::make_unique<Simulation>(body_, s);
  const MatX3i& F = body_->faces();
  faces_.resize(static_cast<std::size_t>(F.size()));
  for (Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      faces_[static_cast<std::size_t>(3 * f + c)] = static_cast<std::uint32_t>(F(f, c));
  const MatX3& R = body_->rest_surface();
  rest_.resize(static_cast<std::size_t>(R.size()));
  for (Index i = 0; i < R.size(); ++i) rest_[static_cast<std::size_t>(i)] = static_cast<float>(R.data()[i]);
  const Vec3 lo = R.colwise().minCoeff(), hi = R.colwise().maxCoeff();
  size_ = (hi - lo).norm();
  build_spokes();
  mirror();
}

// ---- what the model is
val Engine::node(int i) const {
  return guarded([&] {
    check_node(i);
    val a = val::array();
    for (int c = 0; c < 3; ++c) a.call<void>("push", sim_->surface()(i, c));
    return a;
  });
}

// ---- time
double Engine::tick() {
  const double us = advance();
  mirror();
  return us;
}

double Engine::ticks(int n) {
  double us = 0;
  for (int k = 0; k < n; ++k) us += advance();
  mirror();
  return us;
}

val Engine::tickStats() const {
  std::vector<double> t(times_.begin(), times_.begin() + static_cast<std::ptrdiff_t>(times_used_));
  val o = val::object();
  o.set("count", static_cast<double>(tick_count_));
  if (t.empty()) return o;
  std::sort(t.begin(), t.end());
  double sum = 0;
  for (double v : t) sum += v;
  o.set("median", t[t.size() / 2]);
  o.set("p99", t[std::min(t.size() - 1, static_cast<std::size_t>(0.99 * static_cast<double>(t.size())))]);
  o.set("mean", sum / static_cast<double>(t.size()));
  return o;
}

// ---- health
void Engine::injectNaN() {
  sim_->state().x(0, 0) = std::nan("");
}

// ---- settings
void Engine::reset() {
  release();
  sim_->reset();
  failed_seen_ = sim_->state().warnings.failed;
  mirror();
}

void Engine::setLocal(bool on) {
  guarded([&] {
    SimulationSettings s = sim_->settings();
    s.local.enabled = on;
    sim_->set_settings(s);
    return 0;
  });
}

val Engine::params() const {
  const TissueParams t = tissue_params(package_);
  val o = val::object();
  o.set("k", t.k);
  o.set("eta", t.eta);
  o.set("kr", t.kr);
  o.set("beta", t.beta);
  o.set("nonlinear", t.nonlinear);
  return o;
}

void Engine::setParams(const val& p) {
  guarded([&] {
    TissueParams t = tissue_params(package_);
    auto number = [&](const char* key, double& out) {
      if (p[key].isUndefined()) return;
      if (!p[key].isNumber()) throw InvalidInput(cat("setParams: ", key, " must be a number"));
      out = p[key].as<double>();
    };
    number("k", t.k);
    number("eta", t.eta);
    number("kr", t.kr);
    number("beta", t.beta);
    if (!p["nonlinear"].isUndefined()) t.nonlinear = p["nonlinear"].as<bool>();
    ModelPackage next = package_;
    set_tissue_params(next, t);
    BodyPtr body = make_body(next);
    auto sim = std::make_unique<Simulation>(body, sim_->settings());
    const State& old = sim_->state();
    if (body->model().num_nodes() == old.x.rows()) {
      State s = make_state(body->model());
      s.x = old.x;
      s.v = old.v;
      s.t = old.t;
      s.frames = old.frames;
      sim->set_state(s);
    }
    const Index contact = loop_ ? loop_->contact() : -1;
    loop_.reset();
    drop_tool();  // a rigid tool belongs to the old simulation: it is removed
    package_ = std::move(next);
    body_ = std::move(body);
    sim_ = std::move(sim);
    failed_seen_ = sim_->state().warnings.failed;
    if (contact >= 0) loop_ = std::make_unique<HapticLoop>(*sim_, contact, haptic_);
    mirror();
    return 0;
  });
}

// ---- private
void Engine::check_node(int i) const {
  if (i < 0 || i >= body_->num_surface_nodes())
    throw InvalidInput(cat("surface node ", i, " out of range [0, ", body_->num_surface_nodes(), ")"));
}

double Engine::advance() {
  const auto a = std::chrono::steady_clock::now();
  if (loop_) {
    reaction_ = loop_->tick(tool_);
  } else if (tool_loop_) {
    const Vec3 at = tools_->contact().state(0).pose.position;
    Vec3 step = tool_ - at;
    if (max_step_ > 0 && step.norm() > max_step_) step *= max_step_ / step.norm();
    reaction_ = tool_loop_->tick(at + step);
  } else {
    reaction_.setZero();
    sim_->update();
    sim_->update();
  }
  const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count();
  times_[static_cast<std::size_t>(tick_count_ % static_cast<long>(times_.size()))] = us;
  if (tick_count_ < static_cast<long>(times_.size())) times_used_ = static_cast<std::size_t>(tick_count_ + 1);
  ++tick_count_;
  const State& s = sim_->state();
  if (!finite())
    auto_reset("the simulation diverged (non-finite state)");
  else if (s.warnings.failed > failed_seen_)
    auto_reset("the simulation could not advance (step failed)");
  else if (!reaction_.allFinite())
    auto_reset("the tool force diverged");
  return us;
}

void Engine::auto_reset(const std::string& why) {
  message_ = why + ": reset to rest";
  ++auto_resets_;
  reset();
}

void Engine::build_spokes() {
  spokes_.clear();
  atom_offset_ = -1;
  if (const auto* h = dynamic_cast<const HybridKidney*>(body_.get())) {
    atom_offset_ = h->num_surface_nodes();
    const MatX2i& S = h->spokes();
    for (Index r = 0; r < S.rows(); ++r) {
      spokes_.push_back(static_cast<std::uint32_t>(S(r, 0)));
      spokes_.push_back(static_cast<std::uint32_t>(S(r, 1)));
    }
  } else if (const auto* v = dynamic_cast<const SmrmVessel*>(body_.get())) {
    atom_offset_ = 0;
    for (Index i = 0; i < v->num_surface_nodes(); ++i) {
      spokes_.push_back(static_cast<std::uint32_t>(i));
      spokes_.push_back(static_cast<std::uint32_t>(v->node_atom(i)));
    }
  } else if (const auto* t = dynamic_cast<const SmrmTree*>(body_.get())) {
    atom_offset_ = 0;
    for (Index i = 0; i < t->num_surface_nodes(); ++i) {
      spokes_.push_back(static_cast<std::uint32_t>(i));
      spokes_.push_back(static_cast<std::uint32_t>(t->node_atom(i)));
    }
  }
  // Centerline segments as atom pairs: the springs between atoms (a tree's branches meet at shared atoms).
  edges_.clear();
  if (atom_offset_ >= 0) {
    const Springs& sp = body_->model().springs;
    for (std::size_t k = 0; k < sp.i.size(); ++k) {
      const Index a = sp.i[k] - atom_offset_, b = sp.j[k] - atom_offset_;
      if (a < 0 || b < 0) continue;  // hybrid: surface springs and spokes
      edges_.push_back(static_cast<std::uint32_t>(a));
      edges_.push_back(static_cast<std::uint32_t>(b));
    }
  }
}

void Engine::mirror() {
  if (!finite()) auto_reset("the simulation diverged (non-finite state)");
  const MatX3& S = sim_->surface();
  if (size_ > 0 && maxDisplacement() > 10 * size_) {
    auto_reset("the simulation diverged (displacement beyond 10x the model size)");
  }
  pos_.resize(static_cast<std::size_t>(S.size()));
  for (Index i = 0; i < S.size(); ++i) pos_[static_cast<std::size_t>(i)] = static_cast<float>(S.data()[i]);
  const MatX3& X = sim_->state().x;
  atoms_.clear();
  if (atom_offset_ >= 0)
    for (Index r = atom_offset_; r < X.rows(); ++r)
      for (int c = 0; c < 3; ++c) atoms_.push_back(static_cast<float>(X(r, c)));
}

}  // namespace medspring::web
