// The Engine of the JavaScript API (web/src/engine.hpp, docs/web.md): the haptic virtual coupling of a
// grabbed node, the rigid tools (docs/tools.md), and the trajectory replays of the wasm = native tests
// and the bench.
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "engine.hpp"
#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/tools/tool.hpp"

namespace medspring::web {

// ---- the tool (virtual coupling, docs/haptics.md)
void Engine::grab(int i, double k_vc, double b_vc, double f_max) {
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

void Engine::moveTool(double x, double y, double z) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) throw_js("moveTool: non-finite position");
  tool_ = Vec3(x, y, z);
}

void Engine::release() {
  if (loop_) loop_->release();
  loop_.reset();
  drop_tool();
  reaction_.setZero();
}

// ---- a rigid tool (docs/tools.md)
void Engine::placeTool(const std::string& spec, double x, double y, double z, double dx, double dy, double dz,
                       double friction, double f_max, double max_step) {
  guarded([&] {
    const Tool t = parse_tool(spec);
    const Vec3 p(x, y, z), d(dx, dy, dz);
    require(p.allFinite() && d.allFinite() && d.norm() > 0,
            "placeTool: the position and a non-zero direction must be finite");
    require(std::isfinite(max_step) && max_step >= 0, "placeTool: maxStep must be >= 0 (got ", max_step, ")");
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

void Engine::setOpening(double degrees) {
  guarded([&] {
    require(tools_ != nullptr, "setOpening: no tool placed");
    tools_->set_opening(0, degrees * 3.14159265358979323846 / 180.0);
    return 0;
  });
}

val Engine::toolState() const {
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

// ---- trajectory replays
val Engine::runTrajectory(const std::string& csv, int contact) {
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

val Engine::benchTrajectory(const std::string& csv, int contact) {
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

val Engine::runToolTrajectory(const std::string& csv, const std::string& spec, double friction) {
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

}  // namespace medspring::web
