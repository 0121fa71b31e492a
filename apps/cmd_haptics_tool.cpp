// `medspring haptics SCENE_OR_MODEL --trajectory FILE --tool sphere:R`: the 1 kHz haptic loop with a
// rigid tool (docs/tools.md) instead of the single-node coupling: the tool follows the recorded poses,
// collides with the deformed surface, and the device gets the reaction force; per-tick compute time
// and the force/torque trace.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "builtin_models.hpp"
#include "commands.hpp"
#include "medspring/core/check.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/sim/tool_sim.hpp"
#include "scene_support.hpp"

namespace medspring::cli {

int cmd_haptics_tool(const Args& args, const std::string& trajectory_file) {
  if (args.get("node"))
    throw InvalidInput("--node applies to the node coupling; --tool finds its own contacts");
  const Tool tool = parse_tool(*args.get("tool"));
  const auto out = args.get("out");
  const bool force = args.flag("force");
  if (out) check_output_folder(*out, force);
  const ToolPath path = read_tool_path_file(trajectory_file);

  const std::string source = args.positional()[0];
  BodyPtr body;
  SimulationSettings settings;
  std::string model_name = source;
  if (is_builtin_model(source)) {
    body = builtin_model(source, !args.flag("linear")).body;
  } else {
    if (args.flag("linear")) throw InvalidInput("--linear applies to a model name; a scene sets its own law");
    const Scene scene = load_scene(source);
    FileLoader loader;
    const BuiltScene built = build_scene(scene, &loader);  // the scene's loads and tools are ignored
    body = built.body;
    settings = built.settings;
    model_name = scene.name;
  }
  if (args.flag("local")) settings.local.enabled = true;
  settings.normals = false;  // a graphics-thread job (§2.5), not part of the haptic tick

  HapticSettings hs;
  hs.f_max = args.number("f-max", hs.f_max);
  ContactSettings cs;
  cs.friction = args.number("friction", 0.0);
  Simulation sim(body, settings);
  ToolSimulation tools(sim, cs);
  const Index k = tools.add_tool(tool, path.front().pose);
  ToolHapticLoop loop(tools, k, hs);
  const double duration = args.number("duration", path.back().t);
  require_positive(duration, "--duration (ms)");

  struct Row {
    Vec3 torque;
    double area, penetration, grasp;
  };
  std::vector<Row> rows;
  const long ticks = static_cast<long>(std::floor(duration / hs.tick + 1e-9));
  rows.reserve(static_cast<std::size_t>(ticks));
  for (long i = 0; i < ticks; ++i) {
    const ToolKeyframe f = tool_path_at(path, static_cast<double>(i) * hs.tick);
    Pose p = tools.contact().state(k).pose;
    p.rotation = f.pose.rotation;
    tools.set_pose(k, p);
    if (f.opening >= 0 && tool.kind == ToolKind::Grasper) tools.set_opening(k, f.opening);
    loop.tick(f.pose.position);
    const ToolState& st = tools.contact().state(k);
    rows.push_back({st.torque, st.area, st.penetration, st.grasp_force.norm()});
  }
  const TickStats st = tick_stats(loop.samples());
  long saturated = 0;
  double peak = 0, peak_pen = 0;
  for (const HapticSample& s : loop.samples()) {
    saturated += s.saturated ? 1 : 0;
    peak = std::max(peak, s.force.norm());
  }
  for (const Row& r : rows) peak_pen = std::max(peak_pen, r.penetration);
  const Vec3 last = ticks > 0 ? Vec3(-loop.last().force) : Vec3::Zero();
  std::string trace_path;
  if (out) {
    StagedOutput stage(*out, force);
    std::ofstream csv(stage.dir() / "force_trace.csv");
    csv << "time_ms,tool_x,tool_y,tool_z,reaction_x,reaction_y,reaction_z,torque_x,torque_y,torque_z,"
           "contact_area_mm2,penetration_mm,grasp_force_N,saturated,compute_us\n";
    csv.precision(17);
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const HapticSample& s = loop.samples()[i];
      const Row& r = rows[i];
      csv << s.t << ',' << s.tool.x() << ',' << s.tool.y() << ',' << s.tool.z() << ',' << -s.force.x() << ','
          << -s.force.y() << ',' << -s.force.z() << ',' << r.torque.x() << ',' << r.torque.y() << ','
          << r.torque.z() << ',' << r.area << ',' << r.penetration << ',' << r.grasp << ','
          << (s.saturated ? 1 : 0) << ',' << s.compute_us << '\n';
    }
    csv.close();
    if (!csv) throw IoError(cat((stage.dir() / "force_trace.csv").string(), ": write failed"));
    stage.commit();
    trace_path = (stage.target() / "force_trace.csv").string();
  }
  if (args.flag("json")) {
    nlohmann::json j = {{"model", model_name},
                        {"kind", body->kind()},
                        {"tool", to_string(tool.kind)},
                        {"tool_radius_mm", tool.radius},
                        {"contact_stiffness_n_per_mm3", tools.contact().stiffness()},
                        {"local", settings.local.enabled},
                        {"ticks", st.ticks},
                        {"tick_ms", hs.tick},
                        {"updates_per_tick", loop.updates_per_tick()},
                        {"median_us", st.median_us},
                        {"p99_us", st.p99_us},
                        {"max_us", st.max_us},
                        {"mean_us", st.mean_us},
                        {"peak_force_n", peak},
                        {"peak_penetration_mm", peak_pen},
                        {"saturated_ticks", saturated},
                        {"final_reaction_n", {last.x(), last.y(), last.z()}},
                        {"warnings", sim.state().warnings.total()}};
    if (!trace_path.empty()) j["trace"] = trace_path;
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  std::printf("%s (%s): %s tool of radius %g mm (contact stiffness %.4g N/mm^3, max %g N)%s\n",
              model_name.c_str(), body->kind().c_str(), to_string(tool.kind).c_str(), tool.radius,
              tools.contact().stiffness(), hs.f_max, settings.local.enabled ? ", local deformation on" : "");
  std::printf("  %ld ticks of %g ms (%d updates each): compute median %.1f us, p99 %.1f us, max %.1f us\n",
              st.ticks, hs.tick, loop.updates_per_tick(), st.median_us, st.p99_us, st.max_us);
  std::printf(
      "  peak force %.4f N, peak penetration %.4f mm, %ld saturated ticks, final reaction (%.5f, %.5f, %.5f) "
      "N\n",
      peak, peak_pen, saturated, last.x(), last.y(), last.z());
  if (!trace_path.empty()) std::printf("  wrote %s\n", trace_path.c_str());
  return 0;
}

}  // namespace medspring::cli
