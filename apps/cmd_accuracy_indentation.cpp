// Force–indentation of a rigid sphere for `medspring accuracy` (accuracy_indentation.hpp, issue 18).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "accuracy_indentation.hpp"
#include "accuracy_tables.hpp"
#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/sim/tool_sim.hpp"

namespace medspring::cli {

using json = nlohmann::json;

json hertz_validation_json(int level) {
  json rows = json::array();
  for (const auto& r : fem::validate_hertz(level)) rows.push_back(accuracy::validation_json(r));
  return rows;
}

namespace {

struct Press {
  double force = 0, penetration = 0, area = 0, time_ms = 0;
  double spread = 0, max_speed = 0;  // N: max - min of the force over the averaging window; mm/ms
  Index contacts = 0;
  bool at_rest = false;
};

// A sphere tool pressed along d to each depth (the centre at c0 + depth d) and held until the model is at
// rest; the pressing force is the reaction on the tool along -d.
std::vector<Press> spring_press(const BodyPtr& body, double R, const Vec3& c0, const Vec3& d,
                                const std::vector<double>& depths) {
  SimulationSettings ss;
  ss.normals = false;
  Simulation sim(body, ss);
  ToolSimulation tools(sim);
  Vec3 pos = c0 - 1.0 * d;
  const Index probe = tools.add_tool(Tool::sphere(R), Pose{pos, Quat::Identity()});
  const double dt = sim.settings().step.dt, speed = 0.02;  // mm/ms
  std::vector<Press> out;
  for (double depth : depths) {
    const Vec3 target = c0 + depth * d;
    Press p;
    const double start = sim.time();
    while ((target - pos).norm() > 1e-12) {
      const Vec3 step = target - pos;
      pos = step.norm() <= speed * dt ? target : Vec3(pos + step.normalized() * speed * dt);
      tools.set_pose(probe, Pose{pos, Quat::Identity()});
      tools.update();
    }
    const double hold_start = sim.time();
    while (sim.time() - hold_start < 6000) {
      for (int k = 0; k < 20; ++k) tools.update();
      if (sim.time() - hold_start >= 100 && sim.state().v.cwiseAbs().maxCoeff() < 1e-5) {
        p.at_rest = true;
        break;
      }
    }
    // the force averaged over 200 ms more (a model that is not at rest yet may still oscillate a little)
    double lo = INFINITY, hi = -INFINITY, sum = 0;
    const int window = static_cast<int>(std::lround(200.0 / dt));
    for (int k = 0; k < window; ++k) {
      tools.update();
      const double f = tools.contact().state(probe).force.dot(-d);
      sum += f, lo = std::min(lo, f), hi = std::max(hi, f);
    }
    p.max_speed = sim.state().v.cwiseAbs().maxCoeff();
    p.spread = hi - lo;
    const ToolState& st = tools.contact().state(probe);
    p.force = sum / window;
    p.penetration = st.penetration;
    p.area = st.area;
    p.contacts = st.contacts;
    p.time_ms = sim.time() - start;
    out.push_back(p);
  }
  return out;
}

// Least-squares slope of log F against log depth over the points with F > 0.
double loglog_slope(const std::vector<double>& depth, const std::vector<double>& F) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0;
  for (std::size_t i = 0; i < depth.size(); ++i) {
    if (!(F[i] > 0)) continue;
    const double x = std::log(depth[i]), y = std::log(F[i]);
    sx += x, sy += y, sxx += x * x, sxy += x * y, n += 1;
  }
  if (n < 2) return 0;
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace

json indentation_study(const IndentationOrgan& o, const IndentationSettings& s) {
  auto note = [&](const std::string& m) {
    if (s.note) s.note(m);
  };
  const Vec3 d = o.direction.normalized();
  const double R = s.radius;
  const Vec3 c0 = fem::first_touch_centre(o.surface.V, o.surface.F, R, o.site - 2 * R * d, d);
  const Vec3 touch = c0 + R * d;  // the point of first contact on the sphere's axis
  json j = {{"organ", o.name},
            {"radius_mm", R},
            {"direction", {d(0), d(1), d(2)}},
            {"touch_centre", {c0(0), c0(1), c0(2)}},
            {"depths_mm", s.depths},
            {"material", {{"E_kPa", s.material.E * 1e3}, {"nu", s.material.nu}}}};

  // Hertz with the organ's local curvature: 1/R1,2 = 1/R + k1,2, R_e = sqrt(R1 R2)
  const auto [k1, k2] = fem::principal_curvatures(o.surface.V, touch, d, 2.0 * R);
  const double a1 = 1 / R + k1, a2 = 1 / R + k2;
  json hertz = json::array();
  if (a1 > 0 && a2 > 0) {
    const double Re = 1 / std::sqrt(a1 * a2);
    for (double depth : s.depths) hertz.push_back(fem::hertz_force(s.material, Re, depth));
    j["curvature"] = {{"k1_per_mm", k1}, {"k2_per_mm", k2}, {"R_effective_mm", Re}};
  } else {
    j["curvature"] = {{"k1_per_mm", k1}, {"k2_per_mm", k2}, {"R_effective_mm", nullptr}};
  }
  j["hertz_N"] = hertz;

  // the FEM reference with a rigid sphere
  fem::OrganMeshSettings ms;
  ms.subdivisions = s.level - 1;
  note(cat(o.name, ": indentation FEM mesh (level ", s.level, ")"));
  const fem::OrganReference ref(o.surface, s.material, o.support, ms);
  fem::SphereIndentation si;
  si.radius = R;
  si.touch_centre = c0;
  si.direction = d;
  si.depths = s.depths;
  note(cat(o.name, ": indentation FEM, ", s.depths.size(), " depths"));
  const auto fem_pts = fem::sphere_indentation(ref.problem(), si);
  std::vector<double> fem_F;
  json fem_rows = json::array();
  double fem_seconds = 0;
  for (const auto& p : fem_pts) {
    fem_F.push_back(p.force);
    fem_seconds += p.solve_seconds;
    fem_rows.push_back({{"depth_mm", p.depth},
                        {"force_N", p.force},
                        {"contact_nodes", p.contact_nodes},
                        {"contact_radius_mm", p.contact_radius},
                        {"iterations", p.iterations},
                        {"converged", p.converged},
                        {"lateral_N", (p.reaction + p.force * d).norm()},
                        {"solve_s", p.solve_seconds}});
  }
  j["fem"] = {{"nodes", ref.mesh().num_nodes()},
              {"elements", ref.mesh().num_elements()},
              {"fixed_nodes", ref.fixed_fem_nodes().size()},
              {"level", s.level},
              {"total_solve_s", fem_seconds},
              {"slope", loglog_slope(s.depths, fem_F)},
              {"points", fem_rows}};

  // MedSpring: the hybrid kidney (Duffing), default and calibrated, with the same support pinned
  const std::vector<Index> support = fem::support_nodes(o.surface.V, o.support);
  json models = json::array();
  for (bool calibrated : {false, true}) {
    HybridSettings hs;
    if (calibrated) apply_tissue(TissueMaterial{s.material.E * 1e3, s.material.nu, ""}, o.calibration, hs);
    hs.fixed = support;
    const BodyPtr body = std::make_shared<HybridKidney>(o.surface, o.atoms, hs, o.name);
    note(cat(o.name, ": indentation, hybrid (Duffing) ", calibrated ? "calibrated" : "default"));
    const auto presses = spring_press(body, R, c0, d, s.depths);
    json rows = json::array();
    std::vector<double> F;
    double sum_err = 0;
    for (std::size_t i = 0; i < presses.size(); ++i) {
      const auto& p = presses[i];
      F.push_back(p.force);
      const double err = fem_F[i] > 0 ? 100 * (p.force - fem_F[i]) / fem_F[i] : 0.0;
      sum_err += std::abs(err);
      rows.push_back({{"depth_mm", s.depths[i]},
                      {"force_N", p.force},
                      {"error_pct", err},
                      {"penetration_mm", p.penetration},
                      {"contacts", p.contacts},
                      {"area_mm2", p.area},
                      {"at_rest", p.at_rest},
                      {"force_spread_N", p.spread},
                      {"max_speed_mm_per_ms", p.max_speed},
                      {"time_ms", p.time_ms}});
    }
    models.push_back({{"kind", "hybrid (Duffing)"},
                      {"calibrated", calibrated},
                      {"slope", loglog_slope(s.depths, F)},
                      {"mean_abs_error_pct", sum_err / static_cast<double>(presses.size())},
                      {"points", rows}});
  }
  j["models"] = models;
  return j;
}

namespace {
std::string fmt(double v, int digits = 3) {
  std::ostringstream o;
  o.precision(digits);
  o << v;
  return o.str();
}
}  // namespace

std::string indentation_markdown(const json& ind) {
  std::ostringstream md;
  md << "\n## Force–indentation of a rigid sphere (issue 18)\n\n"
        "A frictionless rigid sphere pressed into the body. FEM: node-to-sphere contact with an active set "
        "(the contact nodes' displacement along the indentation imposed on the sphere, lateral motion free; "
        "the force is the sum of CalculiX's reaction forces, fem/indentation.hpp). MedSpring: the sphere "
        "tool "
        "(docs/tools.md) moved to each depth at 0.02 mm/ms and held until the model is at rest (max |v| < "
        "1e-5 mm/ms, at most 6 s); the force is the reaction on the tool averaged over 200 ms more (a row "
        "that did not come to rest gives the half spread of the force and the last max |v|). Depth 0 = "
        "first touch of the surface.\n";
  if (ind.contains("hertz") && !ind["hertz"].empty()) {
    md << "\n### FEM indentation against Hertz (half-space)\n\nQuarter block 20 mm, E = 10 kPa, nu = 0.45, "
          "R = 10 mm; the far faces carry the Boussinesq field of the FEM's own force. Hertz: F = 4/3 E/(1 - "
          "nu^2) sqrt(R) d^1.5.\n\n| case | level | nodes | FEM N | Hertz N | error % | solve s |\n"
          "|---|---|---|---|---|---|---|\n";
    for (const auto& v : ind["hertz"])
      md << "| " << v["name"].get<std::string>() << " | " << v["level"] << " | " << v["nodes"] << " | "
         << fmt(v["fem"].get<double>(), 4) << " | " << fmt(v["analytic"].get<double>(), 4) << " | "
         << fmt(100 * v["rel_error"].get<double>(), 3) << " | " << fmt(v["solve_s"].get<double>(), 3)
         << " |\n";
  }
  if (ind.contains("organs"))
    for (const auto& o : ind["organs"]) {
      md << "\n### " << o["organ"].get<std::string>() << ": sphere R = " << o["radius_mm"].get<double>()
         << " mm\n\nFEM: " << o["fem"]["nodes"] << " nodes, " << o["fem"]["elements"] << " C3D10 (level "
         << o["fem"]["level"] << "), CalculiX " << fmt(o["fem"]["total_solve_s"].get<double>(), 3)
         << " s in all. Hertz-like: the Hertz law with the effective radius of the sphere and the organ's "
            "local "
            "principal curvatures (";
      const auto& c = o["curvature"];
      md << fmt(c["k1_per_mm"].get<double>()) << ", " << fmt(c["k2_per_mm"].get<double>()) << " 1/mm";
      if (!c["R_effective_mm"].is_null()) md << ", R_e = " << fmt(c["R_effective_mm"].get<double>()) << " mm";
      md << "), as if the organ were a half-space.\n\n| depth mm | FEM N | FEM contact nodes | Hertz-like N "
            "|";
      for (const auto& m : o["models"])
        md << " " << m["kind"].get<std::string>()
           << (m["calibrated"].get<bool>() ? " calibrated" : " default") << " N (error %) |";
      md << "\n|---|---|---|---|";
      for (std::size_t k = 0; k < o["models"].size(); ++k) md << "---|";
      md << "\n";
      for (std::size_t i = 0; i < o["depths_mm"].size(); ++i) {
        const auto& f = o["fem"]["points"][i];
        md << "| " << o["depths_mm"][i].get<double>() << " | " << fmt(f["force_N"].get<double>(), 4)
           << (f["converged"].get<bool>() ? "" : " (active set not settled)") << " | " << f["contact_nodes"]
           << " | " << (o["hertz_N"].size() > i ? fmt(o["hertz_N"][i].get<double>(), 4) : "-") << " |";
        for (const auto& m : o["models"]) {
          const auto& p = m["points"][i];
          md << " " << fmt(p["force_N"].get<double>(), 4) << " (" << fmt(p["error_pct"].get<double>(), 3)
             << ")";
          if (!p["at_rest"].get<bool>())
            md << " not at rest: ±" << fmt(p["force_spread_N"].get<double>() / 2, 2) << " N, |v| "
               << fmt(p["max_speed_mm_per_ms"].get<double>(), 2) << " mm/ms";
          md << " |";
        }
        md << "\n";
      }
      md << "\nLog–log slope of F against depth (Hertz: 1.5): FEM " << fmt(o["fem"]["slope"].get<double>());
      for (const auto& m : o["models"])
        md << ", " << m["kind"].get<std::string>()
           << (m["calibrated"].get<bool>() ? " calibrated " : " default ") << fmt(m["slope"].get<double>());
      md << ".\n";
    }
  return md.str();
}

}  // namespace medspring::cli
