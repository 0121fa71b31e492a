// `medspring haptics SCENE_OR_MODEL --trajectory FILE`: the 1 kHz haptic loop of ALGORITHMS.md §2.5
// driven by a recorded tool path; per-tick compute time and the force trace.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "builtin_models.hpp"
#include "commands.hpp"
#include "haptics_gpu.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/parallel.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/sim/haptics.hpp"
#include "scene_support.hpp"

namespace medspring::cli {

int cmd_haptics_tool(const Args& args, const std::string& trajectory_file);  // cmd_haptics_tool.cpp

int cmd_haptics(const Args& args) {
  args.require_known({"trajectory", "out", "force", "json", "node", "k-vc", "b-vc", "f-max", "local",
                      "linear", "duration", "tool", "friction", "threads", "device"});
  if (args.positional().size() != 1)
    throw InvalidInput("expected exactly one SCENE file or model name (see medspring haptics --help)");
  const auto traj_file = args.get("trajectory");
  if (!traj_file || traj_file->empty())
    throw InvalidInput("--trajectory FILE is required (see medspring haptics --help)");
  const auto out = args.get("out");
  const bool force = args.flag("force");
  const std::string device = args.get("device").value_or("cpu");
  if (device != "cpu" && device != "cuda")
    throw UsageError(cat("--device: expected cpu or cuda (got '", device, "')"));
  const bool gpu = device == "cuda";
  if (gpu && args.get("tool"))
    throw UsageError("--device cuda: rigid tools (--tool) are not ported to the GPU path; use --device cpu");
  if (gpu && args.get("threads")) throw UsageError("--threads applies to the CPU engine (--device cpu)");
  if (out) check_output_folder(*out, force);
  if (args.get("tool")) return cmd_haptics_tool(args, *traj_file);
  const Trajectory path = read_trajectory_file(*traj_file);

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
    const BuiltScene built = build_scene(scene, &loader);  // the scene's loads are ignored: the tool acts
    body = built.body;
    settings = built.settings;
    model_name = scene.name;
  }
  if (args.flag("local")) settings.local.enabled = true;
  settings.normals = false;  // a graphics-thread job (§2.5), not part of the haptic tick
  if (args.get("threads")) {
    const long threads = args.integer("threads", 1);
    require_thread_count(threads, "--threads");
    settings.step.threads = static_cast<int>(threads);
  }

  HapticSettings hs;
  hs.k_vc = args.number("k-vc", hs.k_vc);
  hs.b_vc = args.number("b-vc", hs.b_vc);
  hs.f_max = args.number("f-max", hs.f_max);
  const Index contact = args.get("node") ? static_cast<Index>(args.integer("node", 0))
                                         : nearest_node(body->rest_surface(), path.front().x);
  const double duration = args.number("duration", path.back().t);
  require_positive(duration, "--duration (ms)");
  std::vector<HapticSample> samples;
  TickStats st;
  int updates_per_tick = 1;
  std::uint64_t warnings = 0;
  HapticsGpuRun g;
  if (gpu) {  // gpu::HapticLoop (docs/gpu.md); no fallback to the CPU: errors name --device cpu
    g = run_haptics_gpu(*body, settings, contact, hs, path, duration);
    samples = std::move(g.samples);
    st = g.stats;
    updates_per_tick = g.updates_per_tick;
    warnings = g.warnings;
  } else {
    Simulation sim(body, settings);
    HapticLoop loop(sim, contact, hs);
    st = run_trajectory(loop, path, duration);
    samples = loop.samples();
    updates_per_tick = loop.updates_per_tick();
    warnings = sim.state().warnings.total();
  }

  long saturated = 0;
  double peak = 0;
  for (const HapticSample& s : samples) {
    saturated += s.saturated ? 1 : 0;
    peak = std::max(peak, s.force.norm());
  }
  const Vec3 last = samples.empty() ? Vec3::Zero() : Vec3(-samples.back().force);
  std::string trace_path;
  if (out) {
    StagedOutput stage(*out, force);
    std::ofstream csv(stage.dir() / "force_trace.csv");
    csv << "time_ms,tool_x,tool_y,tool_z,contact_x,contact_y,contact_z,reaction_x,reaction_y,reaction_z,"
           "saturated,compute_us\n";
    csv.precision(17);
    for (const HapticSample& s : samples)
      csv << s.t << ',' << s.tool.x() << ',' << s.tool.y() << ',' << s.tool.z() << ',' << s.contact.x() << ','
          << s.contact.y() << ',' << s.contact.z() << ',' << -s.force.x() << ',' << -s.force.y() << ','
          << -s.force.z() << ',' << (s.saturated ? 1 : 0) << ',' << s.compute_us << '\n';
    csv.close();
    if (!csv) throw IoError(cat((stage.dir() / "force_trace.csv").string(), ": write failed"));
    stage.commit();
    trace_path = (stage.target() / "force_trace.csv").string();
  }
  if (args.flag("json")) {
    nlohmann::json j = {{"model", model_name},
                        {"kind", body->kind()},
                        {"contact_node", contact},
                        {"local", settings.local.enabled},
                        {"ticks", st.ticks},
                        {"tick_ms", hs.tick},
                        {"updates_per_tick", updates_per_tick},
                        {"median_us", st.median_us},
                        {"p99_us", st.p99_us},
                        {"max_us", st.max_us},
                        {"mean_us", st.mean_us},
                        {"peak_force_n", peak},
                        {"saturated_ticks", saturated},
                        {"final_reaction_n", {last.x(), last.y(), last.z()}},
                        {"warnings", warnings},
                        {"device", device}};
    if (gpu) {
      j["gpu"] = g.device;
      j["stale_ticks"] = g.stale_ticks;
    }
    if (!trace_path.empty()) j["trace"] = trace_path;
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  std::printf("%s (%s): tool coupled to surface node %ld (k_vc %g N/mm, b_vc %g N ms/mm, max %g N)%s\n",
              model_name.c_str(), body->kind().c_str(), static_cast<long>(contact), hs.k_vc, hs.b_vc,
              hs.f_max, settings.local.enabled ? ", local deformation on" : "");
  std::printf("  %ld ticks of %g ms (%d updates each): compute median %.1f us, p99 %.1f us, max %.1f us\n",
              st.ticks, hs.tick, updates_per_tick, st.median_us, st.p99_us, st.max_us);
  if (gpu)
    std::printf("  on %s: %ld ticks used the previous tick's contact read\n", g.device.c_str(),
                g.stale_ticks);
  std::printf("  peak force %.4f N, %ld saturated ticks, final reaction (%.5f, %.5f, %.5f) N\n", peak,
              saturated, last.x(), last.y(), last.z());
  if (!trace_path.empty()) std::printf("  wrote %s\n", trace_path.c_str());
  return 0;
}

}  // namespace medspring::cli
