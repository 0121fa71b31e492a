#include "medspring/sim/haptics.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"

namespace medspring {

HapticLoop::HapticLoop(Simulation& sim, Index contact, const HapticSettings& settings)
    : sim_(sim), contact_(contact), settings_(settings) {
  require_index(contact, sim.body().num_surface_nodes(), "haptics: contact surface node");
  require_positive(settings.tick, "haptics: tick (ms)");
  require_nonnegative(settings.k_vc, "haptics: k_vc (N/mm)");
  require_nonnegative(settings.b_vc, "haptics: b_vc (N ms/mm)");
  require_positive(settings.f_max, "haptics: f_max (N)");
  const double dt = sim.settings().step.dt;
  const double n = settings.tick / dt;
  require(std::abs(n - std::round(n)) < 1e-9 * n && std::round(n) >= 1, "haptics: tick ", settings.tick,
          " ms is not a whole multiple of the simulation step ", dt, " ms");
  updates_per_tick_ = static_cast<int>(std::round(n));
}

Vec3 HapticLoop::tick(const Vec3& x_tool) {
  const auto start = std::chrono::steady_clock::now();
  const Vec3 x_c = sim_.global_surface().row(contact_).transpose();
  Vec3 v_tool = Vec3::Zero(), v_c = Vec3::Zero();
  if (!first_) {
    v_tool = (x_tool - tool_prev_) / settings_.tick;
    v_c = (x_c - contact_prev_) / settings_.tick;
  }
  Vec3 F = settings_.k_vc * (x_tool - x_c) + settings_.b_vc * (v_tool - v_c);  // §2.5 virtual coupling
  const double norm = F.norm();
  const bool saturated = norm > settings_.f_max;
  if (saturated) F *= settings_.f_max / norm;  // device maximum
  if (!F.allFinite()) F.setZero();             // a non-finite tool position pushes nothing
  HapticSample s;
  s.t = sim_.time();
  s.tool = x_tool;
  s.contact = x_c;
  s.force = F;
  s.saturated = saturated;
  sim_.set_tool_force(contact_, F);
  for (int i = 0; i < updates_per_tick_; ++i) sim_.update();
  s.compute_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  tool_prev_ = x_tool;
  contact_prev_ = x_c;
  first_ = false;
  last_ = s;
  if (settings_.record) samples_.push_back(s);
  return -F;
}

void HapticLoop::release() {
  sim_.clear_tool_force();
  first_ = true;
}

namespace {

bool parse_number(const std::string& field, double& value) {
  const char* begin = field.c_str();
  while (*begin == ' ' || *begin == '\t') ++begin;
  if (*begin == '\0') return false;
  char* end = nullptr;
  value = std::strtod(begin, &end);
  while (*end == ' ' || *end == '\t' || *end == '\r') ++end;
  return *end == '\0' && std::isfinite(value);
}

}  // namespace

Trajectory read_trajectory(std::istream& in, const std::string& name) {
  Trajectory path;
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
    if (!line.empty() && line.back() == ',') fields.emplace_back();
    double v0 = 0;
    if (header_allowed && !fields.empty() && !parse_number(fields[0], v0)) {  // header row
      header_allowed = false;
      continue;
    }
    header_allowed = false;
    require(fields.size() == 4, name, ":", number, ": expected 4 fields (time_ms, x, y, z), found ",
            fields.size());
    TrajectoryPoint p;
    double v[4];
    for (int k = 0; k < 4; ++k)
      require(parse_number(fields[static_cast<std::size_t>(k)], v[k]), name, ":", number, ": field ", k + 1,
              " '", fields[static_cast<std::size_t>(k)], "' is not a finite number");
    p.t = v[0];
    p.x = Vec3(v[1], v[2], v[3]);
    require(path.empty() || p.t > path.back().t, name, ":", number, ": time ", p.t,
            " ms is not after the previous row's ", path.empty() ? 0.0 : path.back().t, " ms");
    path.push_back(p);
  }
  require(!path.empty(), name, ": no trajectory rows (expected CSV: time_ms, x, y, z)");
  return path;
}

Trajectory read_trajectory_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw IoError(cat(file.string(), ": cannot open the trajectory file"));
  return read_trajectory(in, file.string());
}

Vec3 trajectory_position(const Trajectory& path, double t) {
  require(!path.empty(), "trajectory_position: empty trajectory");
  if (t <= path.front().t) return path.front().x;
  if (t >= path.back().t) return path.back().x;
  const auto it = std::upper_bound(path.begin(), path.end(), t,
                                   [](double value, const TrajectoryPoint& p) { return value < p.t; });
  const TrajectoryPoint& b = *it;
  const TrajectoryPoint& a = *(it - 1);
  const double s = (t - a.t) / (b.t - a.t);
  return (1 - s) * a.x + s * b.x;
}

TickStats tick_stats(const std::vector<HapticSample>& samples) {
  TickStats st;
  st.ticks = static_cast<long>(samples.size());
  if (samples.empty()) return st;
  std::vector<double> us;
  us.reserve(samples.size());
  for (const HapticSample& s : samples) us.push_back(s.compute_us);
  std::sort(us.begin(), us.end());
  const std::size_t n = us.size();
  st.median_us = n % 2 ? us[n / 2] : 0.5 * (us[n / 2 - 1] + us[n / 2]);
  st.p99_us = us[std::min(n - 1, static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(n))) - 1)];
  st.max_us = us.back();
  double sum = 0;
  for (double u : us) sum += u;
  st.mean_us = sum / static_cast<double>(n);
  return st;
}

TickStats run_trajectory(HapticLoop& loop, const Trajectory& path, double duration) {
  require(!path.empty(), "run_trajectory: empty trajectory");
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
