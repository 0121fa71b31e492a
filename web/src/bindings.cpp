// JavaScript API of the engine (embind), compiled by web/build.sh. One Engine = one Simulation of a
// bundled model plus a haptic virtual coupling (sim/haptics.hpp) for the mouse tool.
//
//   const ms = await createMedSpring();
//   const e = new ms.Engine("kidney_phantom", true, false);   // model, nonlinear, local deformation
//   e.grab(223); e.moveTool(x, y, z); e.tick();               // 1 ms physics tick
//   const P = e.positions();                                   // Float32Array view (#S*3), zero-copy
#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <chrono>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/sim/haptics.hpp"

namespace medspring::web {
namespace {

BodyPtr make_body(const std::string& name, bool nonlinear) {
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

class Engine {
 public:
  Engine(const std::string& model, bool nonlinear, bool local) {
    body_ = make_body(model, nonlinear);
    SimulationSettings s;
    s.local.enabled = local;
    s.normals = false;  // three.js computes normals on the GPU side
    sim_ = std::make_unique<Simulation>(body_, s);
    const MatX3i& F = body_->faces();
    faces_.resize(static_cast<std::size_t>(F.size()));
    for (Index f = 0; f < F.rows(); ++f)
      for (int c = 0; c < 3; ++c)
        faces_[static_cast<std::size_t>(3 * f + c)] = static_cast<std::uint32_t>(F(f, c));
    mirror();
  }

  int numSurfaceNodes() const { return static_cast<int>(body_->num_surface_nodes()); }
  std::string kind() const { return body_->kind(); }
  double time() const { return sim_->time(); }
  /// Float32Array views into wasm memory (valid until the next allocation: re-take them every frame).
  emscripten::val positions() const {
    return emscripten::val(emscripten::typed_memory_view(pos_.size(), pos_.data()));
  }
  emscripten::val restPositions() const {
    return emscripten::val(emscripten::typed_memory_view(rest_.size(), rest_.data()));
  }
  emscripten::val faces() const {
    return emscripten::val(emscripten::typed_memory_view(faces_.size(), faces_.data()));
  }
  /// Exact (double) position of one surface node, for tests.
  emscripten::val node(int i) const {
    emscripten::val a = emscripten::val::array();
    for (int c = 0; c < 3; ++c) a.call<void>("push", sim_->surface()(i, c));
    return a;
  }

  /// Couples the tool to surface node i at its current position (no force until the tool moves).
  void grab(int i, double k_vc, double b_vc, double f_max) {
    HapticSettings hs;
    hs.k_vc = k_vc;
    hs.b_vc = b_vc;
    hs.f_max = f_max;
    hs.record = false;
    loop_ = std::make_unique<HapticLoop>(*sim_, static_cast<Index>(i), hs);
    tool_ = sim_->global_surface().row(i).transpose();
  }
  void moveTool(double x, double y, double z) { tool_ = Vec3(x, y, z); }
  void release() {
    if (loop_) loop_->release();
    loop_.reset();
  }
  bool grabbed() const { return loop_ != nullptr; }
  /// One 1 ms tick (two 0.5 ms updates); returns its compute time (µs).
  double tick() {
    const auto a = std::chrono::steady_clock::now();
    if (loop_) {
      reaction_ = loop_->tick(tool_);
    } else {
      reaction_.setZero();
      sim_->update();
      sim_->update();
    }
    mirror();
    return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count();
  }
  emscripten::val reaction() const {
    emscripten::val a = emscripten::val::array();
    for (int c = 0; c < 3; ++c) a.call<void>("push", reaction_(c));
    return a;
  }
  bool finite() const { return sim_->state().x.allFinite(); }
  void reset() {
    release();
    sim_->reset();
    mirror();
  }
  void setLocal(bool on) {
    SimulationSettings s = sim_->settings();
    s.local.enabled = on;
    sim_->set_settings(s);
  }

  /// Replays a trajectory CSV through the haptic loop exactly as `medspring haptics` does; returns
  /// per tick [t, contact xyz, reaction xyz] as one Float64Array-compatible JS array.
  emscripten::val runTrajectory(const std::string& csv, int contact) {
    std::istringstream in(csv);
    const Trajectory path = read_trajectory(in, "trajectory");
    HapticLoop loop(*sim_, static_cast<Index>(contact));
    run_trajectory(loop, path);
    std::vector<double> out;
    for (const HapticSample& s : loop.samples()) {
      out.push_back(s.t);
      for (int c = 0; c < 3; ++c) out.push_back(s.contact(c));
      for (int c = 0; c < 3; ++c) out.push_back(-s.force(c));
    }
    emscripten::val a = emscripten::val::array();
    for (double v : out) a.call<void>("push", v);
    mirror();
    return a;
  }

 private:
  void mirror() {
    const MatX3& S = sim_->surface();
    pos_.resize(static_cast<std::size_t>(S.size()));
    if (rest_.empty()) {
      const MatX3& R = body_->rest_surface();
      rest_.resize(pos_.size());
      for (Index i = 0; i < R.size(); ++i)
        rest_[static_cast<std::size_t>(i)] = static_cast<float>(R.data()[i]);
    }
    for (Index i = 0; i < S.size(); ++i) pos_[static_cast<std::size_t>(i)] = static_cast<float>(S.data()[i]);
  }

  BodyPtr body_;
  std::unique_ptr<Simulation> sim_;
  std::unique_ptr<HapticLoop> loop_;
  Vec3 tool_ = Vec3::Zero(), reaction_ = Vec3::Zero();
  std::vector<float> pos_, rest_;
  std::vector<std::uint32_t> faces_;
};

std::string error_message(std::intptr_t ptr) {
  return reinterpret_cast<std::exception*>(ptr)->what();
}

EMSCRIPTEN_BINDINGS(medspring) {
  emscripten::class_<Engine>("Engine")
      .constructor<std::string, bool, bool>()
      .function("numSurfaceNodes", &Engine::numSurfaceNodes)
      .function("kind", &Engine::kind)
      .function("time", &Engine::time)
      .function("positions", &Engine::positions)
      .function("restPositions", &Engine::restPositions)
      .function("faces", &Engine::faces)
      .function("node", &Engine::node)
      .function("grab", &Engine::grab)
      .function("moveTool", &Engine::moveTool)
      .function("release", &Engine::release)
      .function("grabbed", &Engine::grabbed)
      .function("tick", &Engine::tick)
      .function("reaction", &Engine::reaction)
      .function("finite", &Engine::finite)
      .function("reset", &Engine::reset)
      .function("setLocal", &Engine::setLocal)
      .function("runTrajectory", &Engine::runTrajectory);
  emscripten::function("errorMessage", &error_message);
}

}  // namespace medspring::web
