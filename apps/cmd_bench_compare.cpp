// `medspring bench --compare` and `medspring bench --scaling --out DIR` (docs/performance.md).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.hpp"
#include "compare.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/parallel.hpp"

namespace medspring::cli {

namespace fs = std::filesystem;

namespace {

// Log-log plot of time per update against nodes, one line per engine (and thread count), with the fitted
// exponents in the legend. Run with /usr/bin/python3 (matplotlib), like the paper command's figures.
constexpr const char* kPlotScript = R"PY(import json, math, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
data = json.load(open(sys.argv[1]))
series = {}
for r in data["results"]:
    key = r["engine"] + ("" if r["engine"] != "medspring" else " %d thread%s" % (r["threads"], "s" if r["threads"] > 1 else ""))
    series.setdefault(key, []).append((r["nodes"], r["median_us"] / 1000.0))
fits = {f["series"]: f["exponent"] for f in data["fits"]}
fig, ax = plt.subplots(figsize=(6.4, 4.6))
for key, pts in sorted(series.items()):
    pts.sort()
    label = key + (" (N^%.2f)" % fits[key] if key in fits else "")
    ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", label=label)
ax.set_xlabel("nodes")
ax.set_ylabel("time per update (ms)")
ax.set_title("tube, nonlinear, one 0.5 ms update (one run)")
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=120)
)PY";

std::string series_name(const bench::CompareResult& r) {
  if (r.engine != "medspring") return r.engine;
  return cat("medspring ", r.threads, r.threads > 1 ? " threads" : " thread");
}

}  // namespace

int cmd_bench_compare(const Args& args) {
  args.require_known(
      {"compare", "scaling", "json", "quick", "threads", "out", "no-bullet", "samples", "order", "sizes"});
  const bool scaling = args.flag("scaling"), json = args.flag("json"), quick = args.flag("quick");
  const long threads = args.integer("threads", 2);
  require_thread_count(threads, "--threads");
  std::optional<fs::path> out;
  if (scaling) {
    const auto o = args.get("out");
    if (!o || o->empty()) throw InvalidInput("bench --scaling: --out DIR is required");
    out = fs::path(*o);
    fs::create_directories(*out);
  }
  bench::CompareOptions opt;
  opt.threads = {1};
  if (threads != 1) opt.threads.push_back(static_cast<int>(threads));
  opt.bullet = !args.flag("no-bullet");
  opt.samples = args.integer("samples", quick ? 200 : 1000);
  require(opt.samples >= 1, "--samples: must be >= 1 (got ", opt.samples, ")");
  opt.budget_s = quick ? 0.5 : 2.0;
  opt.sizes = {{40, 30}, {100, 100}, {400, 250}};
  if (!quick) opt.sizes.push_back({1000, 1000});
  if (scaling && !quick) opt.sizes.push_back({2000, 1500});
  opt.order = args.get("order").value_or("built");
  require(opt.order == "built" || opt.order == "shuffled" || opt.order == "rcm",
          "--order: must be built, shuffled or rcm (got '", opt.order, "')");
  if (const auto list = args.get("sizes")) {  // e.g. --sizes 1.2k,1M
    const std::map<std::string, bench::TubeSize> known = {{"1.2k", {40, 30}},
                                                          {"10k", {100, 100}},
                                                          {"100k", {400, 250}},
                                                          {"1M", {1000, 1000}},
                                                          {"3M", {2000, 1500}}};
    opt.sizes.clear();
    std::stringstream ss(*list);
    for (std::string item; std::getline(ss, item, ',');) {
      const auto it = known.find(item);
      require(it != known.end(), "--sizes: unknown size '", item,
              "' (expected a list of 1.2k, 10k, 100k, 1M, 3M)");
      opt.sizes.push_back(it->second);
    }
    require(!opt.sizes.empty(), "--sizes: empty list (expected e.g. 1.2k,1M)");
  }
  const bool table = !json && !scaling;
  if (!json) {
    std::printf("# one run, one process; Bullet %s\n",
                bench::bullet_available() ? "built in" : "not built in");
    std::printf("%-10s %-9s %7s %4s %8s %11s %11s %9s %9s %10s %8s\n", "size", "engine", "threads", "used",
                "substeps", "median_us", "per_sub_us", "ns/spring", "vs_plain", "bytes/node", "build_s");
  }
  std::map<std::string, double> plain_us;  // per size
  std::vector<std::string> settings_lines;
  auto print = [&](const bench::CompareResult& r) {
    if (r.engine == "plain") plain_us[r.name] = r.timing.median_us;
    if (json) return;
    const auto p = plain_us.find(r.name);
    const double ratio = p != plain_us.end() && p->second > 0 ? r.timing.median_us / p->second : 0.0;
    std::printf("%-10s %-9s %7d %4d %8.2f %11.2f %11.2f %9.2f %9s %10.0f %8.2f\n", r.name.c_str(),
                r.engine.c_str(), r.threads, r.threads_used, r.substeps, r.timing.median_us,
                r.timing.median_us / r.substeps, r.ns_per_spring,
                ratio > 0 ? cat(ratio).substr(0, 5).c_str() : "-", r.bytes_per_node, r.build_s);
    std::fflush(stdout);
    if (r.name == "tube_1.2k" || r.engine == "bullet")
      settings_lines.push_back(cat(r.name, " ", r.engine, ": ", r.settings));
  };
  const std::vector<bench::CompareResult> results = bench::run_compare(opt, print);
  nlohmann::json res = nlohmann::json::array();
  for (const auto& r : results) {
    const auto p = plain_us.find(r.name);
    res.push_back({{"name", r.name},
                   {"engine", r.engine},
                   {"threads", r.threads},
                   {"threads_used", r.threads_used},
                   {"substeps", r.substeps},
                   {"median_us", r.timing.median_us},
                   {"p99_us", r.timing.p99_us},
                   {"mean_us", r.timing.mean_us},
                   {"min_us", r.timing.min_us},
                   {"samples", r.timing.samples},
                   {"nodes", r.nodes},
                   {"springs", r.springs},
                   {"ns_per_spring", r.ns_per_spring},
                   {"bytes_per_node", r.bytes_per_node},
                   {"vs_plain", p != plain_us.end() && p->second > 0 ? r.timing.median_us / p->second : 0.0},
                   {"build_s", r.build_s},
                   {"settings", r.settings}});
  }
  nlohmann::json fits = nlohmann::json::array();
  std::map<std::string, std::pair<std::string, int>> keys;
  for (const auto& r : results) keys[series_name(r)] = {r.engine, r.threads};
  for (const auto& [name, key] : keys)
    fits.push_back({{"series", name}, {"exponent", bench::fitted_exponent(results, key.first, key.second)}});
  if (table) {
    for (const auto& l : settings_lines) std::printf("# %s\n", l.c_str());
    for (const auto& f : fits)
      std::printf("# fitted exponent (time ~ N^e) %s: %.3f\n", f["series"].get<std::string>().c_str(),
                  f["exponent"].get<double>());
  }
  const nlohmann::json doc = {{"results", res}, {"fits", fits}};
  if (json) std::cout << doc.dump(2) << "\n";
  if (out) {
    const fs::path data = *out / "scaling.json", script = *out / "scaling_plot.py",
                   png = *out / "scaling.png";
    {
      std::ofstream f(data);
      f << doc.dump(2) << "\n";
      std::ofstream g(script);
      g << kPlotScript;
      if (!f || !g) throw IoError(cat("bench --scaling: cannot write into ", out->string()));
    }
    const char* py_env = std::getenv("MEDSPRING_PYTHON");
    const std::string python = py_env && *py_env ? py_env : "/usr/bin/python3";
    const std::string cmd =
        cat("'", python, "' '", script.string(), "' '", data.string(), "' '", png.string(), "'");
    if (std::system(cmd.c_str()) != 0)
      throw IoError(cat("bench --scaling: the plot failed (", cmd, "; needs python3-matplotlib)"));
    if (!json) {
      for (const auto& f : fits)
        std::printf("# fitted exponent (time ~ N^e) %s: %.3f\n", f["series"].get<std::string>().c_str(),
                    f["exponent"].get<double>());
      std::printf("wrote %s and %s\n", data.string().c_str(), png.string().c_str());
    }
  }
  return 0;
}

}  // namespace medspring::cli
