// Native reference for the WebAssembly tests (web/test/wasm_matches_native.mjs): runs the haptic loop of
// a bundled model or a model package exactly as the browser engine (web/src/engine.cpp) configures it,
// and writes the force trace in the format of `medspring haptics` (force_trace.csv).
//
//   medspring_web_reference MODEL|PACKAGE.msm --node N (--trajectory FILE | --press MM --out-trajectory FILE)
//                           [--linear] [--local] [--params k,eta,kr,beta] --out-trace FILE
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "builtin_models.hpp"
#include "medspring/core/check.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/sim/haptics.hpp"

using namespace medspring;

namespace {

std::string need(int& i, int argc, char** argv) {
  if (i + 1 >= argc) throw InvalidInput(cat(argv[i], ": missing value"));
  return argv[++i];
}

// Press the node 'mm' towards the centroid of the rest surface over 100 ms, hold to 600 ms, withdraw by
// 700 ms, rest to 1000 ms (the shape of examples/haptics/kidney_press.csv).
std::string press_csv(const Body& body, Index node, double mm) {
  const MatX3& R = body.rest_surface();
  const Vec3 x0 = R.row(node).transpose();
  const Vec3 c = R.colwise().mean().transpose();
  const Vec3 d = (c - x0).normalized() * mm;
  std::ostringstream os;
  os.precision(17);
  os << "time_ms,x,y,z\n";
  for (auto [t, s] :
       std::vector<std::pair<double, double>>{{0, 0}, {100, 1}, {600, 1}, {700, 0}, {1000, 0}}) {
    const Vec3 p = x0 + s * d;
    os << t << "," << p.x() << "," << p.y() << "," << p.z() << "\n";
  }
  return os.str();
}

int run(int argc, char** argv) {
  if (argc < 2) throw InvalidInput("usage: medspring_web_reference MODEL|PACKAGE.msm --node N ...");
  const std::string model = argv[1];
  long node = -1;
  double press = 0;
  bool linear = false, local = false;
  std::string trajectory_file, out_trajectory, out_trace, params;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--node")
      node = std::stol(need(i, argc, argv));
    else if (a == "--press")
      press = std::stod(need(i, argc, argv));
    else if (a == "--trajectory")
      trajectory_file = need(i, argc, argv);
    else if (a == "--out-trajectory")
      out_trajectory = need(i, argc, argv);
    else if (a == "--out-trace")
      out_trace = need(i, argc, argv);
    else if (a == "--params")
      params = need(i, argc, argv);
    else if (a == "--linear")
      linear = true;
    else if (a == "--local")
      local = true;
    else
      throw InvalidInput(cat("unknown option ", a));
  }
  if (node < 0 || out_trace.empty()) throw InvalidInput("--node and --out-trace are required");

  // The body, as the browser Engine builds it (web/src/engine.cpp: constructor, then setParams).
  ModelPackage package;
  BodyPtr body;
  if (cli::is_builtin_model(model)) {
    body = cli::builtin_model(model, !linear).body;
    package = package_of(*body, model, "bundled procedural model");
  } else {
    package = read_model_package(model);
    if (tissue_params(package).nonlinear == linear) {
      TissueParams t = tissue_params(package);
      t.nonlinear = !linear;
      set_tissue_params(package, t);
    }
    body = make_body(package);
  }
  if (!params.empty()) {
    TissueParams t = tissue_params(package);
    if (std::sscanf(params.c_str(), "%lf,%lf,%lf,%lf", &t.k, &t.eta, &t.kr, &t.beta) != 4)
      throw InvalidInput(cat("--params: expected k,eta,kr,beta (got ", params, ")"));
    set_tissue_params(package, t);
    body = make_body(package);
  }
  SimulationSettings settings;
  settings.local.enabled = local;
  settings.normals = false;
  Simulation sim(body, settings);

  std::string csv;
  if (!trajectory_file.empty()) {
    std::ifstream in(trajectory_file);
    if (!in) throw IoError(cat(trajectory_file, ": cannot open"));
    csv.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  } else {
    require_positive(press, "--press");
    csv = press_csv(*body, static_cast<Index>(node), press);
  }
  if (!out_trajectory.empty()) std::ofstream(out_trajectory) << csv;
  std::istringstream in(csv);
  const Trajectory path = read_trajectory(in, "trajectory");
  HapticLoop loop(sim, static_cast<Index>(node));
  const TickStats st = run_trajectory(loop, path);

  std::ofstream out(out_trace);
  out.precision(17);
  out << "time_ms,tool_x,tool_y,tool_z,contact_x,contact_y,contact_z,reaction_x,reaction_y,reaction_z,"
         "saturated,"
         "compute_us\n";
  for (const HapticSample& s : loop.samples()) {
    out << s.t;
    for (int c = 0; c < 3; ++c) out << "," << s.tool(c);
    for (int c = 0; c < 3; ++c) out << "," << s.contact(c);
    for (int c = 0; c < 3; ++c) out << "," << -s.force(c);
    out << "," << (s.saturated ? 1 : 0) << "," << s.compute_us << "\n";
  }
  if (!out) throw IoError(cat(out_trace, ": cannot write"));
  std::printf("%s: %ld ticks, median %.1f us, p99 %.1f us per tick\n", model.c_str(), st.ticks, st.median_us,
              st.p99_us);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "medspring_web_reference: error: " << e.what() << "\n";
    return 1;
  }
}
