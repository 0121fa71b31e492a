#include "medspring/sim/tool_sim.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"

namespace medspring {

namespace {

bool parse_field(const std::string& field, double& value) {
  const char* begin = field.c_str();
  while (*begin == ' ' || *begin == '\t') ++begin;
  if (*begin == '\0') return false;
  char* end = nullptr;
  value = std::strtod(begin, &end);
  while (*end == ' ' || *end == '\t' || *end == '\r') ++end;
  return *end == '\0' && std::isfinite(value);
}

}  // namespace

ToolPath read_tool_path(std::istream& in, const std::string& name) {
  ToolPath path;
  std::string line;
  long number = 0;
  bool header_allowed = true;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) fields.push_back(field);
    if (line.back() == ',') fields.emplace_back();
    double v0 = 0;
    if (header_allowed && !fields.empty() && !parse_field(fields[0], v0)) {
      header_allowed = false;
      continue;
    }
    header_allowed = false;
    const std::size_t n = fields.size();
    require(n == 4 || n == 8 || n == 9, name, ":", number,
            ": expected 4, 8 or 9 fields (time_ms, x, y, z[, qw, qx, qy, qz[, opening_deg]]), found ", n);
    double v[9];
    for (std::size_t k = 0; k < n; ++k)
      require(parse_field(fields[k], v[k]), name, ":", number, ": field ", k + 1, " '", fields[k],
              "' is not a finite number");
    ToolKeyframe f;
    f.t = v[0];
    f.pose.position = Vec3(v[1], v[2], v[3]);
    if (n >= 8) {
      f.pose.rotation = Quat(v[4], v[5], v[6], v[7]);
      require(f.pose.rotation.coeffs().norm() > 1e-12, name, ":", number, ": the quaternion is zero");
      f.pose.rotation.normalize();
    }
    if (n == 9) {
      require(v[8] >= 0 && v[8] <= 180, name, ":", number, ": opening ", v[8],
              " degrees is outside [0, 180]");
      f.opening = v[8] * std::numbers::pi / 180;
    }
    require(path.empty() || f.t > path.back().t, name, ":", number, ": time ", f.t,
            " ms is not after the previous row's ", path.empty() ? 0.0 : path.back().t, " ms");
    path.push_back(f);
  }
  require(!path.empty(), name, ": no rows (expected CSV: time_ms, x, y, z[, qw, qx, qy, qz[, opening_deg]])");
  return path;
}

ToolPath read_tool_path_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw IoError(cat(file.string(), ": cannot open the tool path"));
  return read_tool_path(in, file.string());
}

void validate_tool_path(const ToolPath& path, const std::string& what) {
  for (std::size_t k = 0; k < path.size(); ++k) {
    require_finite(path[k].t, what, "[", k, "].t");
    checked_pose(path[k].pose, cat(what, "[", k, "].pose"));
    require(std::isfinite(path[k].opening) && path[k].opening <= std::numbers::pi, what, "[", k,
            "].opening: must be finite and <= pi (got ", path[k].opening, ")");
    require(k == 0 || path[k].t > path[k - 1].t, what, "[", k, "].t: ", path[k].t,
            " ms is not after the previous keyframe's ", k ? path[k - 1].t : 0.0, " ms");
  }
}

ToolKeyframe tool_path_at(const ToolPath& path, double t) {
  require(!path.empty(), "tool path: empty");
  if (t <= path.front().t) return path.front();
  if (t >= path.back().t) return path.back();
  const auto it = std::upper_bound(path.begin(), path.end(), t,
                                   [](double value, const ToolKeyframe& p) { return value < p.t; });
  const ToolKeyframe& b = *it;
  const ToolKeyframe& a = *(it - 1);
  const double s = (t - a.t) / (b.t - a.t);
  ToolKeyframe f;
  f.t = t;
  f.pose.position = (1 - s) * a.pose.position + s * b.pose.position;
  f.pose.rotation = a.pose.rotation.slerp(s, b.pose.rotation);
  f.opening = a.opening >= 0 && b.opening >= 0 ? (1 - s) * a.opening + s * b.opening : a.opening;
  return f;
}

ContactSettings contact_settings_for(const Simulation& sim, ContactSettings base) {
  require(sim.settings().step.integrator != Integrator::LinearStatic, sim.model().name,
          ": tools: the linear_static integrator has no inertia for the penalty contact to act on (it would "
          "oscillate from update to update); use symplectic_euler or implicit_euler with tools");
  base.dt = sim.settings().step.dt;
  base.min_mass = sim.model().mass.minCoeff();
  return base;
}

ToolSimulation::ToolSimulation(Simulation& sim, const ContactSettings& base)
    : sim_(sim), contact_(sim.body().faces(), sim.body().rest_surface(), contact_settings_for(sim, base)) {
  substep_surface_ = sim.global_surface();
  substep_delta_ = MatX3::Zero(substep_surface_.rows(), 3);
  substep_ = {&ToolSimulation::substep_contact, this};
}

ToolSimulation::~ToolSimulation() {
  sim_.set_surface_forces(nullptr);
  sim_.set_substep_force(nullptr);
}

// The contact at the substep rate: the body's surface at this substep, the change of the contact's
// normal forces, transferred to the DOFs like the update's forces.
void ToolSimulation::substep_contact(void* self, State& state, double t) {
  auto& me = *static_cast<ToolSimulation*>(self);
  const Body& body = me.sim_.body();
  body.map_to_surface(state, me.substep_surface_);
  if (!me.contact_.substep(me.substep_surface_, t, me.substep_delta_)) return;
  for (const Index n : me.contact_.forces().nodes)
    body.transfer_force(n, me.substep_delta_.row(n).transpose(), state.f_ext);
}

Index ToolSimulation::add_tool(const Tool& tool, const Pose& pose) {
  const std::string what = cat("tools[", contact_.num_tools(), "]");
  validate_tool(tool, what);
  contact_.check_outside(sim_.global_surface(), tool, pose, what);
  const Index k = contact_.add_tool(tool, pose);
  paths_.resize(static_cast<std::size_t>(contact_.num_tools()));
  return k;
}

void ToolSimulation::set_path(Index k, ToolPath path) {
  require_index(k, contact_.num_tools(), "tool path: tool");
  validate_tool_path(path, cat("tools[", k, "].path"));
  if (!path.empty() && path.front().opening >= 0) contact_.set_opening(k, path.front().opening);
  paths_[static_cast<std::size_t>(k)] = std::move(path);
}

StepStatus ToolSimulation::update() {
  const double t = sim_.time();
  for (Index k = 0; k < contact_.num_tools(); ++k) {
    const ToolPath& p = paths_[static_cast<std::size_t>(k)];
    if (p.empty()) continue;
    const ToolKeyframe f = tool_path_at(p, t);
    contact_.set_pose(k, f.pose);
    if (f.opening >= 0 && contact_.state(k).tool.kind == ToolKind::Grasper)
      contact_.set_opening(k, f.opening);
  }
  contact_.update(sim_.global_surface());
  sim_.set_surface_forces(&contact_.forces());
  sim_.set_substep_force(contact_.settings().substep && !contact_.contacts().empty() ? &substep_ : nullptr);
  const StepStatus s = sim_.update();
  contact_.end_frame(sim_.time());
  return s;
}

StepStatus ToolSimulation::advance(long frames) {
  StepStatus worst;
  for (long i = 0; i < frames; ++i) {
    const StepStatus s = update();
    if (s.code != StepCode::Ok) worst = s;
  }
  return worst;
}

void ToolSimulation::reset() {
  sim_.reset();
  contact_.reset_history();
}

ToolHapticLoop::ToolHapticLoop(ToolSimulation& tools, Index tool, const HapticSettings& settings)
    : tools_(tools), tool_(tool), settings_(settings) {
  require_index(tool, tools.contact().num_tools(), "haptics: tool");
  require_positive(settings.tick, "haptics: tick (ms)");
  require_positive(settings.f_max, "haptics: f_max (N)");
  const double dt = tools.simulation().settings().step.dt;
  const double n = settings.tick / dt;
  require(std::abs(n - std::round(n)) < 1e-9 * n && std::round(n) >= 1, "haptics: tick ", settings.tick,
          " ms is not a whole multiple of the simulation step ", dt, " ms");
  updates_per_tick_ = static_cast<int>(std::round(n));
}

Vec3 ToolHapticLoop::tick(const Vec3& x_device) {
  const auto start = std::chrono::steady_clock::now();
  HapticSample s;
  s.t = tools_.simulation().time();
  s.tool = x_device;
  if (x_device.allFinite()) {  // a non-finite device position leaves the tool where it was
    Pose p = tools_.contact().state(tool_).pose;
    p.position = x_device;
    tools_.set_pose(tool_, p);
  }
  for (int i = 0; i < updates_per_tick_; ++i) tools_.update();
  Vec3 F = tools_.contact().state(tool_).force;  // reaction on the tool
  const double norm = F.norm();
  s.saturated = norm > settings_.f_max;
  if (s.saturated) F *= settings_.f_max / norm;
  s.contact = tools_.contact().state(tool_).pose.position;
  s.force = -F;  // HapticSample convention: force on the model; the device gets -force
  s.compute_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  last_ = s;
  if (settings_.record) samples_.push_back(s);
  return F;
}

TickStats run_tool_trajectory(ToolHapticLoop& loop, const Trajectory& path, double duration) {
  require(!path.empty(), "run_tool_trajectory: empty trajectory");
  if (duration < 0) duration = path.back().t;
  const std::size_t first = loop.samples().size();
  const double tick = loop.settings().tick;
  const long ticks = static_cast<long>(std::floor(duration / tick + 1e-9));
  for (long k = 0; k < ticks; ++k) loop.tick(trajectory_position(path, static_cast<double>(k) * tick));
  const std::vector<HapticSample> run(loop.samples().begin() + static_cast<long>(first),
                                      loop.samples().end());
  return tick_stats(run);
}

}  // namespace medspring
