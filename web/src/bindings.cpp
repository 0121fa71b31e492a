// JavaScript API of the engine (embind), compiled by web/build.sh (docs/web.md). One Engine = one
// Simulation of a model (a bundled phantom or a model package, models/model_package.hpp) plus a haptic
// virtual coupling (sim/haptics.hpp) for the mouse tool, or a rigid tool (sphere probe, grasper:
// sim/tool_sim.hpp, docs/tools.md) that presses, slides and grasps through the contact model.
//
//   const ms = await createMedSpring();
//   const e = new ms.Engine('kidney_phantom', true, false);    // or new ms.Engine(uint8array, true, false)
//   e.grab(223, 0.1, 0.01, 3); e.moveTool(x, y, z); e.ticks(16);   // 16 fixed 1 ms ticks
//   const P = e.positions();                                    // Float32Array view (#S*3), zero-copy
//
// Every C++ error reaches JavaScript as an Error carrying the C++ message.
#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/smrm_tree.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/sim/haptics.hpp"
#include "medspring/sim/tool_sim.hpp"
#include "medspring/tools/tool.hpp"

namespace medspring::web {
namespace {

using emscripten::val;

/// Throws a JavaScript Error with the message (never returns).
[[noreturn]] void throw_js(const std::string& message) {
  val::global("Error").new_(message).throw_();
}

/// Runs f, turning a C++ exception into a JavaScript Error with its message.
template <class F>
auto guarded(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const std::exception& e) {
    throw_js(e.what());
  }
}

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

std::string bytes_of(const val& array) {
  const std::string type = array.typeOf().as<std::string>();
  if (type != "object" || !array["length"].isNumber())
    throw InvalidInput("model: expected a model name or the bytes of a model package (Uint8Array)");
  const auto n = array["length"].as<std::size_t>();
  std::string bytes(n, '\0');
  // Copy with one TypedArray.set into a view of the C++ buffer (no per-byte crossing).
  val view(emscripten::typed_memory_view(n, reinterpret_cast<unsigned char*>(bytes.data())));
  view.call<void>("set", val::global("Uint8Array").new_(array));
  return bytes;
}

template <class T>
val float_array(const std::vector<T>& v) {
  return val(emscripten::typed_memory_view(v.size(), v.data()));
}

}  // namespace

class Engine {
 public:
  /// model: "kidney_phantom" | "tube" | "vessel_phantom", or a Uint8Array holding a model package.
  /// nonlinear: Duffing springs (a package keeps its own setting unless this differs from it).
  Engine(const val& model, bool nonlinear, bool local) {
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
  int numSurfaceNodes() const { return static_cast<int>(body_->num_surface_nodes()); }
  int numAtoms() const {
    return static_cast<int>(atom_offset_ < 0 ? 0 : sim_->state().x.rows() - atom_offset_);
  }
  std::string kind() const { return body_->kind(); }
  std::string name() const { return package_.name; }
  std::string description() const { return package_.description; }
  int numMasses() const { return static_cast<int>(body_->model().num_nodes()); }
  int numSprings() const { return static_cast<int>(body_->model().num_springs()); }
  /// Rest bounding-box diagonal of the surface, mm.
  double size() const { return size_; }
  double time() const { return sim_->time(); }

  // ---- zero-copy views into wasm memory (valid until the next allocation: re-take them every frame)
  val positions() const { return float_array(pos_); }
  val restPositions() const { return float_array(rest_); }
  val faces() const { return float_array(faces_); }
  /// Current atom positions (#A*3): hybrid skeleton atoms, SMRM centerline atoms; empty for a surface body.
  /// The centerline is the polyline through them in order.
  val atoms() const { return float_array(atoms_); }
  /// The centerline: the polyline through atoms() in order (the same view; for readability).
  val centerline() const { return float_array(atoms_); }
  /// Centerline segments as pairs of atom indices (#segments*2): the springs between atoms (an SMRM
  /// chain: i, i+1; a vessel tree: its branches, meeting at shared junction atoms).
  val centerlineEdges() const { return float_array(edges_); }
  /// Spokes as pairs (surface node, atom), #spokes*2: hybrid spokes (D-9), SMRM node -> its atom.
  val spokes() const { return float_array(spokes_); }
  /// Exact (double) position of one surface node, for tests.
  val node(int i) const {
    return guarded([&] {
      check_node(i);
      val a = val::array();
      for (int c = 0; c < 3; ++c) a.call<void>("push", sim_->surface()(i, c));
      return a;
    });
  }
  /// max_i |x_i - x0_i| over the displayed surface, mm.
  double maxDisplacement() const {
    return (sim_->surface() - body_->rest_surface()).rowwise().norm().maxCoeff();
  }

  // ---- the tool (virtual coupling, docs/haptics.md)
  /// Couples the tool to surface node i at its current position (no force until the tool moves).
  void grab(int i, double k_vc, double b_vc, double f_max) {
    guarded([&] {
      check_node(i);
      drop_tool();
      haptic_.k_vc = k_vc;
      haptic_.b_vc = b_vc;
      haptic_.f_max = f_max;
      haptic_.record = false;
      loop_ = std::make_unique<HapticLoop>(*sim_, static_cast<Index>(i), haptic_);
      tool_ = sim_->global_surface().row(i).transpose();
      return 0;
    });
  }
  void moveTool(double x, double y, double z) {
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
      throw_js("moveTool: non-finite position");
    tool_ = Vec3(x, y, z);
  }
  void release() {
    if (loop_) loop_->release();
    loop_.reset();
    drop_tool();
    reaction_.setZero();
  }
  bool grabbed() const { return loop_ != nullptr; }

  // ---- a rigid tool (docs/tools.md): "sphere:R" | "capsule:R:L" | "grasper:R:L:DEG"
  /// Places a rigid tool with its centre (sphere) / tip / hinge at (x, y, z), its local -z along
  /// (dx, dy, dz) (the direction it presses in), replacing a held node or another tool. Throws an Error
  /// for a bad tool, pose or friction, or a tool that starts inside the organ. Each tick the tool moves
  /// towards moveTool()'s target by at most maxStep (mm; 0 = no limit) and the contact reaction is
  /// reaction() (saturated to f_max N).
  void placeTool(const std::string& spec, double x, double y, double z, double dx, double dy, double dz,
                 double friction, double f_max, double max_step) {
    guarded([&] {
      const Tool t = parse_tool(spec);
      const Vec3 p(x, y, z), d(dx, dy, dz);
      require(p.allFinite() && d.allFinite() && d.norm() > 0,
              "placeTool: the position and a non-zero direction must be finite");
      require(std::isfinite(max_step) && max_step >= 0, "placeTool: maxStep must be >= 0 (got ", max_step,
              ")");
      release();
      Pose pose;
      pose.position = p;
      pose.rotation = Quat::FromTwoVectors(Vec3(0, 0, -1), d.normalized());
      ContactSettings cs;
      cs.friction = friction;
      HapticSettings hs;
      hs.f_max = f_max;
      hs.record = false;
      auto tools = std::make_unique<ToolSimulation>(*sim_, cs);
      tools->add_tool(t, pose);
      tool_loop_ = std::make_unique<ToolHapticLoop>(*tools, 0, hs);
      tools_ = std::move(tools);
      tool_ = p;
      max_step_ = max_step;
      return 0;
    });
  }
  /// Opening of the grasper (degrees): closing to <= the grasp angle holds what the jaws touch.
  void setOpening(double degrees) {
    guarded([&] {
      require(tools_ != nullptr, "setOpening: no tool placed");
      tools_->set_opening(0, degrees * 3.14159265358979323846 / 180.0);
      return 0;
    });
  }
  bool hasTool() const { return tools_ != nullptr; }
  /// The placed tool: {kind, radius, length, opening (deg), position [xyz], axis [xyz] (local -z),
  /// force [xyz] (N, on the tool), torque, area (mm^2), penetration (mm), contacts, grasping,
  /// attached, graspForce (N)}; null without a tool.
  val toolState() const {
    if (!tools_) return val::null();
    const ToolState& s = tools_->contact().state(0);
    val o = val::object();
    o.set("kind", to_string(s.tool.kind));
    o.set("radius", s.tool.radius);
    o.set("length", s.tool.length);
    o.set("opening", s.tool.opening * 180.0 / 3.14159265358979323846);
    o.set("position", vec(s.pose.position));
    o.set("axis", vec(s.pose.rotation * Vec3(0, 0, -1)));
    o.set("force", vec(s.force));
    o.set("torque", vec(s.torque));
    o.set("area", s.area);
    o.set("penetration", s.penetration);
    o.set("contacts", static_cast<double>(s.contacts));
    o.set("grasping", s.grasping);
    o.set("attached", static_cast<double>(s.attached));
    o.set("graspForce", s.grasp_force.norm());
    return o;
  }
  int contact() const { return loop_ ? static_cast<int>(loop_->contact()) : -1; }
  val tool() const { return vec(tool_); }
  /// Reaction for the device (-F, N) of the last tick; zero when nothing is grabbed.
  val reaction() const { return vec(reaction_); }

  // ---- time
  /// One 1 ms tick (two 0.5 ms updates); returns its compute time (µs).
  double tick() {
    const double us = advance();
    mirror();
    return us;
  }
  /// n ticks, the surface mirrored once at the end; returns their total compute time (µs). A state
  /// that diverges is reset to rest (message()).
  double ticks(int n) {
    double us = 0;
    for (int k = 0; k < n; ++k) us += advance();
    mirror();
    return us;
  }
  /// Median, p99 and mean compute time (µs) of the last (up to) 1000 ticks, and the tick count.
  val tickStats() const {
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
  bool finite() const { return sim_->state().x.allFinite() && sim_->state().v.allFinite(); }
  /// The last automatic-reset message ("" when none) and the number of automatic resets.
  std::string message() const { return message_; }
  void clearMessage() { message_.clear(); }
  int autoResets() const { return auto_resets_; }
  /// Test hook: puts a NaN into the state, as a diverging integration would.
  void injectNaN() { sim_->state().x(0, 0) = std::nan(""); }

  // ---- settings
  void reset() {
    release();
    sim_->reset();
    failed_seen_ = sim_->state().warnings.failed;
    mirror();
  }
  void setLocal(bool on) {
    guarded([&] {
      SimulationSettings s = sim_->settings();
      s.local.enabled = on;
      sim_->set_settings(s);
      return 0;
    });
  }
  bool local() const { return sim_->settings().local.enabled; }
  /// {k, eta, kr, beta, nonlinear} (models/model_package.hpp TissueParams).
  val params() const {
    const TissueParams t = tissue_params(package_);
    val o = val::object();
    o.set("k", t.k);
    o.set("eta", t.eta);
    o.set("kr", t.kr);
    o.set("beta", t.beta);
    o.set("nonlinear", t.nonlinear);
    return o;
  }
  /// Sets any of {k, eta, kr, beta, nonlinear} and rebuilds the body; the state (positions,
  /// velocities, time) and a grabbed node are kept when the DOF count is unchanged (a rigid tool is
  /// removed). Invalid values
  /// throw an Error naming the parameter, and nothing changes.
  void setParams(const val& p) {
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

  /// Replays a trajectory CSV through the haptic loop exactly as `medspring haptics` does; returns
  /// per tick [t, contact xyz, reaction xyz] as one flat JS array.
  val runTrajectory(const std::string& csv, int contact) {
    return guarded([&] {
      check_node(contact);
      std::istringstream in(csv);
      const Trajectory path = read_trajectory(in, "trajectory");
      HapticLoop loop(*sim_, static_cast<Index>(contact));
      run_trajectory(loop, path);
      val a = val::array();
      for (const HapticSample& s : loop.samples()) {
        a.call<void>("push", s.t);
        for (int c = 0; c < 3; ++c) a.call<void>("push", s.contact(c));
        for (int c = 0; c < 3; ++c) a.call<void>("push", -s.force(c));
      }
      mirror();
      return a;
    });
  }
  /// The same replay, timed: {median, p99, max, mean, ticks} of the per-tick compute time (µs) and
  /// times, a Float64Array of every tick's.
  val benchTrajectory(const std::string& csv, int contact) {
    return guarded([&] {
      check_node(contact);
      std::istringstream in(csv);
      const Trajectory path = read_trajectory(in, "trajectory");
      HapticLoop loop(*sim_, static_cast<Index>(contact));
      const TickStats st = run_trajectory(loop, path);
      mirror();
      std::vector<double> times;
      for (const HapticSample& s : loop.samples()) times.push_back(s.compute_us);
      val o = val::object();
      o.set("times",
            val::global("Float64Array").new_(val(emscripten::typed_memory_view(times.size(), times.data()))));
      o.set("median", st.median_us);
      o.set("p99", st.p99_us);
      o.set("max", st.max_us);
      o.set("mean", st.mean_us);
      o.set("ticks", static_cast<double>(st.ticks));
      return o;
    });
  }
  /// Replays a tool path CSV (time_ms, x, y, z) with a rigid tool exactly as `medspring haptics
  /// --tool SPEC --friction MU` does; returns per tick [t, tool xyz, reaction on the tool xyz] flat.
  val runToolTrajectory(const std::string& csv, const std::string& spec, double friction) {
    return guarded([&] {
      release();
      std::istringstream in(csv);
      const ToolPath path = read_tool_path(in, "tool path");
      require(!path.empty(), "tool path: no rows");
      ContactSettings cs;
      cs.friction = friction;
      HapticSettings hs;
      ToolSimulation tools(*sim_, cs);
      const Tool t = parse_tool(spec);
      tools.add_tool(t, path.front().pose);
      ToolHapticLoop loop(tools, 0, hs);
      const long n = static_cast<long>(std::floor(path.back().t / hs.tick + 1e-9));
      for (long i = 0; i < n; ++i) {
        const ToolKeyframe f = tool_path_at(path, static_cast<double>(i) * hs.tick);
        Pose p = tools.contact().state(0).pose;
        p.rotation = f.pose.rotation;
        tools.set_pose(0, p);
        if (f.opening >= 0 && t.kind == ToolKind::Grasper) tools.set_opening(0, f.opening);
        loop.tick(f.pose.position);
      }
      val a = val::array();
      for (const HapticSample& s : loop.samples()) {
        a.call<void>("push", s.t);
        for (int c = 0; c < 3; ++c) a.call<void>("push", s.tool(c));
        for (int c = 0; c < 3; ++c) a.call<void>("push", -s.force(c));
      }
      mirror();
      return a;
    });
  }

 private:
  static val vec(const Vec3& v) {
    val a = val::array();
    for (int c = 0; c < 3; ++c) a.call<void>("push", v(c));
    return a;
  }
  void drop_tool() {
    tool_loop_.reset();
    tools_.reset();  // detaches its surface forces from the simulation
  }
  void check_node(int i) const {
    if (i < 0 || i >= body_->num_surface_nodes())
      throw InvalidInput(cat("surface node ", i, " out of range [0, ", body_->num_surface_nodes(), ")"));
  }

  /// One tick; a state that is no longer finite, could not be advanced, or flew apart is reset.
  double advance() {
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
    if (tick_count_ < static_cast<long>(times_.size()))
      times_used_ = static_cast<std::size_t>(tick_count_ + 1);
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
  void auto_reset(const std::string& why) {
    message_ = why + ": reset to rest";
    ++auto_resets_;
    reset();
  }

  void build_spokes() {
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

  void mirror() {
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

  ModelPackage package_;
  BodyPtr body_;
  std::unique_ptr<Simulation> sim_;
  std::unique_ptr<HapticLoop> loop_;
  std::unique_ptr<ToolSimulation> tools_;  // a rigid tool (placeTool), or none
  std::unique_ptr<ToolHapticLoop> tool_loop_;
  double max_step_ = 0;
  HapticSettings haptic_;
  Vec3 tool_ = Vec3::Zero(), reaction_ = Vec3::Zero();
  std::vector<float> pos_, rest_, atoms_;
  std::vector<std::uint32_t> faces_, spokes_, edges_;
  Index atom_offset_ = -1;  // first atom DOF (hybrid: #S, smrm: 0), -1 without atoms
  double size_ = 0;
  std::vector<double> times_ = std::vector<double>(1000, 0.0);
  std::size_t times_used_ = 0;
  long tick_count_ = 0;
  std::uint64_t failed_seen_ = 0;
  std::string message_;
  int auto_resets_ = 0;
};

Engine* make_engine(val model, bool nonlinear, bool local) {
  return guarded([&] { return new Engine(model, nonlinear, local); });
}
Engine* make_engine_default(val model) {
  return make_engine(std::move(model), true, false);
}

/// Checks a model package without building an engine: {name, kind, description, params} or an Error.
val inspect_package(const val& bytes) {
  return guarded([&] {
    const ModelPackage p = decode_model_package(bytes_of(bytes), "model package");
    val o = val::object();
    o.set("name", p.name);
    o.set("kind", p.kind);
    o.set("description", p.description);
    o.set("surfaceNodes", static_cast<double>(p.surface.V.rows()));
    return o;
  });
}

std::string error_message(std::intptr_t ptr) {
  return reinterpret_cast<std::exception*>(ptr)->what();
}

EMSCRIPTEN_BINDINGS(medspring) {
  emscripten::class_<Engine>("Engine")
      .constructor(&make_engine)
      .constructor(&make_engine_default)
      .function("numSurfaceNodes", &Engine::numSurfaceNodes)
      .function("numAtoms", &Engine::numAtoms)
      .function("numMasses", &Engine::numMasses)
      .function("numSprings", &Engine::numSprings)
      .function("kind", &Engine::kind)
      .function("name", &Engine::name)
      .function("description", &Engine::description)
      .function("size", &Engine::size)
      .function("time", &Engine::time)
      .function("positions", &Engine::positions)
      .function("restPositions", &Engine::restPositions)
      .function("faces", &Engine::faces)
      .function("atoms", &Engine::atoms)
      .function("centerline", &Engine::centerline)
      .function("spokes", &Engine::spokes)
      .function("centerlineEdges", &Engine::centerlineEdges)
      .function("node", &Engine::node)
      .function("maxDisplacement", &Engine::maxDisplacement)
      .function("grab", &Engine::grab)
      .function("moveTool", &Engine::moveTool)
      .function("release", &Engine::release)
      .function("grabbed", &Engine::grabbed)
      .function("placeTool", &Engine::placeTool)
      .function("setOpening", &Engine::setOpening)
      .function("hasTool", &Engine::hasTool)
      .function("toolState", &Engine::toolState)
      .function("runToolTrajectory", &Engine::runToolTrajectory)
      .function("contact", &Engine::contact)
      .function("tool", &Engine::tool)
      .function("reaction", &Engine::reaction)
      .function("tick", &Engine::tick)
      .function("ticks", &Engine::ticks)
      .function("tickStats", &Engine::tickStats)
      .function("finite", &Engine::finite)
      .function("message", &Engine::message)
      .function("clearMessage", &Engine::clearMessage)
      .function("autoResets", &Engine::autoResets)
      .function("injectNaN", &Engine::injectNaN)
      .function("reset", &Engine::reset)
      .function("setLocal", &Engine::setLocal)
      .function("local", &Engine::local)
      .function("params", &Engine::params)
      .function("setParams", &Engine::setParams)
      .function("runTrajectory", &Engine::runTrajectory)
      .function("benchTrajectory", &Engine::benchTrajectory);
  emscripten::function("inspectPackage", &inspect_package);
  emscripten::function("errorMessage", &error_message);
}

}  // namespace medspring::web
