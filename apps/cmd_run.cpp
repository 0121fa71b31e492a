// `medspring run SCENE --out DIR`: build the scene's model, run it, write the ParaView series and traces.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>

#include "commands.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/parallel.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/parameter_docs.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/sim/checkpoint.hpp"
#include "scene_support.hpp"

namespace medspring::cli {

int cmd_run(const Args& args) {
  args.require_known({"out", "force", "quiet", "json", "static-curve", "checkpoint-every", "checkpoint",
                      "resume", "stop-at", "threads", "set"});
  if (args.positional().size() != 1)
    throw InvalidInput("expected exactly one SCENE file (see medspring run --help)");
  const auto out = args.get("out");
  if (!out || out->empty()) throw InvalidInput("--out DIR is required (see medspring run --help)");
  const bool force = args.flag("force");
  const bool json = args.flag("json");
  Progress progress(args.flag("quiet") || json);

  const long every = args.integer("checkpoint-every", 0);
  if (every < 0) throw InvalidInput(cat("--checkpoint-every: must be >= 0 updates (got ", every, ")"));
  const double stop_at = args.number("stop-at", std::numeric_limits<double>::infinity());
  if (!(stop_at > 0)) throw InvalidInput(cat("--stop-at: must be > 0 ms (got ", stop_at, ")"));
  // Checkpoints go beside the output folder (it is staged under a temporary name while running).
  std::filesystem::path checkpoint = args.get_or("checkpoint", "");
  if (checkpoint.empty() && (every > 0 || std::isfinite(stop_at)))
    checkpoint = std::filesystem::path(*out).lexically_normal().string() + ".mscp";
  std::optional<Checkpoint> resume;
  if (const auto file = args.get("resume")) resume = read_checkpoint(*file);  // refused early when bad

  check_output_folder(*out, force);  // before the model is built: a refusal costs nothing
  Scene scene = load_scene(args.positional()[0]);
  if (auto set = args.get("set")) apply_scene_settings(scene, *set);  // docs/parameters.md
  if (args.get("threads")) {  // overrides the scene's integrator.threads
    const long threads = args.integer("threads", 1);
    require_thread_count(threads, "--threads");
    scene.step.threads = static_cast<int>(threads);
  }
  FileLoader loader;
  progress.begin(cat("build ", scene.name));
  const BuiltScene built = build_scene(scene, &loader);
  progress.end(
      cat(to_string(scene.model.kind), " model, ", built.body->num_surface_nodes(), " surface nodes"));

  StagedOutput stage(*out, force);
  progress.begin(cat("run ", scene.name));
  SceneRunOptions run_options;
  run_options.static_curve = args.flag("static-curve");
  run_options.checkpoint_every = every;
  run_options.checkpoint = checkpoint;
  run_options.resume = resume ? &*resume : nullptr;
  run_options.stop_at = stop_at;
  const nlohmann::json summary = run_scene_to_folder(built, stage.dir(), progress, run_options);
  progress.end(cat(summary["updates"].get<long>(), " updates, ", summary["frames"].size(), " frames"));
  stage.commit();

  if (json) {
    nlohmann::json j = summary;
    j.erase("frames");
    j["out"] = stage.target().string();
    j["frames"] = summary["frames"].size();
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  auto num = [](const nlohmann::json& v) {
    return v.is_null() ? std::string("never") : cat(v.get<double>());
  };
  std::printf("%s: %s model, %ld surface nodes, %ld masses, %ld springs\n", scene.name.c_str(),
              to_string(scene.model.kind).c_str(), static_cast<long>(built.body->num_surface_nodes()),
              static_cast<long>(built.body->model().num_nodes()),
              static_cast<long>(built.body->model().num_springs()));
  std::printf("  %ld updates of %g ms, median %.1f us per update, %lu numerical warnings\n",
              summary["updates"].get<long>(), built.settings.step.dt,
              summary["median_update_us"].get<double>(), summary["warnings"].get<unsigned long>());
  if (!built.loads.empty()) {
    std::printf("  load node %ld: %.4f mm at release (peak %.4f mm); max surface displacement %.4f mm\n",
                static_cast<long>(built.loads.front().node), summary["contact_hold_mm"].get<double>(),
                summary["contact_peak_mm"].get<double>(), summary["max_disp_peak_mm"].get<double>());
    std::printf("  back within %g mm of rest %s ms after the release\n",
                summary["return_tolerance_mm"].get<double>(), num(summary["return_ms"]).c_str());
  }
  if (resume)
    std::printf("  resumed at %g ms (update %ld)\n", resume->state.t, summary["first_update"].get<long>());
  if (summary["stopped"].get<bool>())
    std::printf("  stopped at %g ms; continue with --resume %s\n", stop_at, checkpoint.string().c_str());
  else if (!checkpoint.empty())
    std::printf("  checkpoints in %s\n", checkpoint.string().c_str());
  std::printf("  wrote %s (%zu frames, %s)\n", stage.target().string().c_str(), summary["frames"].size(),
              summary["pvd"].is_null() ? "no series" : summary["pvd"].get<std::string>().c_str());
  return 0;
}

}  // namespace medspring::cli
