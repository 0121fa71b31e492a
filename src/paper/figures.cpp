// The study's figures: key frames rendered with VTK (scripts/paper/render.py) and plots (plots.py), both
// run as python3 subprocesses from job files written here.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "internal.hpp"
#include "medspring/core/check.hpp"

namespace medspring::paper::detail {

namespace {

std::string sig(double x, int digits = 3) {
  std::ostringstream os;
  os << std::setprecision(digits) << x;
  return os.str();
}

json frame_at(const SceneRun& r, double t) {
  json best;
  double bd = INFINITY;
  for (const auto& f : r.summary["frames"]) {
    const double d = std::abs(f["time_ms"].get<double>() - t);
    if (d < bd) {
      bd = d;
      best = f;
    }
  }
  return best;
}

json render_job(const SceneRun& r, double t, const fs::path& png, const std::string& title,
                const std::string& subtitle, const Vec3& view, const Vec3& up, double range, bool arrow) {
  const json f = frame_at(r, t);
  json j = {{"png", png.string()},
            {"vtp", (r.dir / f["file"].get<std::string>()).string()},
            {"rest_vtp", (r.dir / frame_at(r, 0)["file"].get<std::string>()).string()},
            {"range", {0.0, range}},
            {"view", vec(view.normalized())},
            {"up", vec(up.normalized())},
            {"title", title},
            {"subtitle", cat(subtitle, "\nt = ", sig(f["time_ms"].get<double>(), 4), " ms")},
            {"color_label", "|u| (mm)"}};
  if (f.contains("atoms_file")) j["atoms_vtp"] = (r.dir / f["atoms_file"].get<std::string>()).string();
  if (arrow) {
    const double u = r.summary["contact_hold_mm"].get<double>();
    j["arrow"] = {{"point", vec(r.contact + u * r.dir_force)},
                  {"direction", vec(r.dir_force)},
                  {"length", 0.15 * r.size}};
  }
  return j;
}

Vec3 perpendicular(const Vec3& a, const Vec3& b) {
  Vec3 c = a.cross(b);
  if (c.norm() < 1e-9) c = a.unitOrthogonal();
  return c.normalized();
}

}  // namespace

void make_figures(const StudyOptions& o, const fs::path& root, const std::string& primary,
                  const std::vector<SceneRun>& runs, const std::vector<SceneRun>& tree_runs,
                  const json& cases) {
  const fs::path fig = root / "figures";
  json jobs = json::array();
  {
    const SceneRun& k = find_run(runs, primary, "kidney_1.0N_nonlinear");
    const Vec3 n = k.dir_force;
    const Vec3 side = perpendicular(n, k.axis);
    const Vec3 oblique = (-n + 0.75 * side).normalized();
    const Vec3 grazing = (side - 0.45 * n).normalized();  // low over the surface: the crater in relief
    const double range = k.summary["contact_peak_mm"].get<double>();
    const std::string what = cat(primary == "real" ? "real kidney" : "kidney phantom", ", 1.0 N, nonlinear");
    auto close_up = [&](json j) {
      j["focus"] = vec(k.contact);
      j["zoom"] = 1.7;
      return j;
    };
    jobs.push_back(
        render_job(k, kHold, fig / "fig9_A.png", "Fig. 9 A - force on", what, oblique, k.axis, range, true));
    jobs.push_back(close_up(render_job(k, kHold, fig / "fig9_B.png", "Fig. 9 B - force on, close-up", what,
                                       grazing, k.axis, range, true)));
    jobs.push_back(render_job(k, 505, fig / "fig9_C.png", "Fig. 9 C - 5 ms after release", what, oblique,
                              k.axis, range, false));
    jobs.push_back(
        close_up(render_job(k, 1000, fig / "fig9_D.png", "Fig. 9 D - 500 ms after release, close-up", what,
                            grazing, k.axis, range, false)));
  }
  {
    const std::string vw = primary == "real" ? "aorta (VMR 0159)" : "vessel phantom";
    auto vessel_pair = [&](const std::string& file, const std::string& a, const std::string& b,
                           const std::string& what) {
      const SceneRun& v = find_run(runs, primary, file);
      const Vec3 n = v.dir_force;
      const Vec3 view = perpendicular(v.tangent, n);
      const Vec3 oblique = (view - 0.8 * n + 0.3 * v.tangent).normalized();
      const double range = v.summary["max_disp_peak_mm"].get<double>();
      jobs.push_back(render_job(v, kHold, fig / (a + ".png"), "Fig. 10 " + a.substr(6) + " - " + what, vw,
                                view, -n, range, true));
      jobs.push_back(render_job(v, kHold, fig / (b + ".png"),
                                "Fig. 10 " + b.substr(6) + " - " + what + ", oblique", vw, oblique, -n, range,
                                true));
    };
    vessel_pair("vessel_light_nonlinear", "fig10_A", "fig10_B", "light force 0.05 N");
    vessel_pair("vessel_strong_nonlinear", "fig10_C", "fig10_D", "strong force 0.5 N");
    const SceneRun& v = find_run(runs, primary, "vessel_light_nonlinear_local");
    const Vec3 n = v.dir_force;
    const Vec3 view = perpendicular(v.tangent, n);
    const double zoom = std::max(1.0, v.size / (8.0 * std::max(v.radius, 1e-3)));  // the vessel's width fills
    json e =
        render_job(v, kHold, fig / "fig10_E.png", "Fig. 10 E - light force 0.05 N + local deformation", vw,
                   (view - 0.5 * n).normalized(), -n, v.summary["max_disp_peak_mm"].get<double>(), true);
    e["focus"] = vec(v.contact);
    e["zoom"] = std::max(1.0, 0.5 * zoom);
    jobs.push_back(e);
    const Vec3 fview = (0.6 * perpendicular(v.tangent, n) - n + 0.3 * v.tangent).normalized();
    json j = render_job(v, kHold, fig / "fig10_F.png", "Fig. 10 F - the local dent, close-up",
                        cat(vw, "; colour: the local displacement U of eq. (6)"), fview, -n, 1.0, false);
    j["array"] = "local_displacement_magnitude";
    j["color_label"] = "|U| (mm)";
    j["range"] = {0.0, std::max(1e-6, v.summary["local_hold_mm"].get<double>())};
    j["focus"] = vec(v.contact);
    j["zoom"] = zoom;
    jobs.push_back(j);
  }
  for (const std::string site : {"arch", "branch"}) {  // the tree under the strong force
    const auto it = std::find_if(tree_runs.begin(), tree_runs.end(),
                                 [&](const SceneRun& r) { return r.e.file == "tree_strong_" + site; });
    if (it == tree_runs.end()) continue;
    const SceneRun& v = *it;
    const Vec3 n = v.dir_force;
    const Vec3 view = (perpendicular(v.tangent, n) - 0.5 * n).normalized();
    json job = render_job(
        v, kHold, fig / ("tree_" + site + ".png"),
        "Vessel tree - strong force 0.5 N on the " + std::string(site == "arch" ? "arch" : "branch"),
        primary == "real" ? "VMR 0159 aorta with its branches" : "vessel tree phantom", view, -n,
        v.summary["max_disp_peak_mm"].get<double>(), true);
    job.erase("atoms_vtp");  // the run's atom file is one polyline in atom order, not the tree's branches
    jobs.push_back(job);
  }
  const fs::path jobs_file = root / "data" / "render_jobs.json";
  write_text(jobs_file, json{{"width", 1000}, {"height", 750}, {"jobs", jobs}}.dump(2));
  run_logged("rendering (VTK under xvfb-run)",
             o.display_prefix + shell_quote(o.python) + " " +
                 shell_quote((o.scripts_dir / "render.py").string()) + " " + shell_quote(jobs_file.string()),
             root / "logs" / "render.log");

  json plot_spec = {{"out_dir", fig.string()},
                    {"hold_time", kHold},
                    {"title_suffix", primary == "real" ? "" : " (phantoms)"},
                    {"kidney", json::array()},
                    {"vessel", json::array()}};
  for (const auto& r : runs)
    if (r.set == primary && !r.e.literal)
      plot_spec[r.e.group].push_back({{"dir", r.dir.string()},
                                      {"label", r.e.label},
                                      {"force", r.e.force},
                                      {"nonlinear", r.e.nonlinear},
                                      {"local", r.e.local}});
  const PaperTimes& ms = kPaperMassSpring;
  const PaperTimes& sm = kPaperSmrm;
  plot_spec["tables"] = {
      {"cases", cases},
      {"paper",
       {{"MS",
         {{"linear", 1000 * ms.linear}, {"nonlinear", 1000 * ms.nonlinear}, {"local", 1000 * ms.local}}},
        {"SMRM",
         {{"linear", 1000 * sm.linear}, {"nonlinear", 1000 * sm.nonlinear}, {"local", 1000 * sm.local}}}}}};
  const fs::path plots_file = root / "data" / "plots.json";
  write_text(plots_file, plot_spec.dump(2));
  run_logged("plots (matplotlib)",
             shell_quote(o.python) + " " + shell_quote((o.scripts_dir / "plots.py").string()) + " " +
                 shell_quote(plots_file.string()),
             root / "logs" / "plots.log");
  std::vector<std::string> pngs = {"fig9_displacement", "fig10_displacement", "force_displacement",
                                   "vessel_profile", "timing"};
  for (const auto& j : jobs) pngs.push_back(fs::path(j["png"].get<std::string>()).stem().string());
  for (const auto& p : pngs)
    if (!fs::exists(fig / (p + ".png"))) throw Error(cat("figures: ", p, ".png was not made (see logs/)"));
}

}  // namespace medspring::paper::detail
