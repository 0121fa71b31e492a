#include "gpu_bench.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "compare.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/stability.hpp"

#ifdef MEDSPRING_HAS_CUDA
#include "medspring/gpu/engine.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/model_package.hpp"
#endif

namespace medspring::bench {

namespace fs = std::filesystem;

GpuBenchOptions parse_gpu_bench_args(const std::vector<std::string>& args) {
  GpuBenchOptions o;
  auto value = [&](std::size_t& i) -> const std::string& {
    require(i + 1 < args.size(), "bench --gpu: ", args[i], " needs a value");
    return args[++i];
  };
  auto number = [](const std::string& text, const std::string& what) {
    std::size_t used = 0;
    long v = -1;
    try {
      v = std::stol(text, &used);
    } catch (...) {
      used = 0;
    }
    require(used == text.size() && v >= 0, "bench --gpu: ", what, ": expected a non-negative integer (got '",
            text, "')");
    return v;
  };
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--sizes") {
      o.sizes.clear();
      std::stringstream ss(value(i));
      for (std::string item; std::getline(ss, item, ',');) {
        const long n = number(item, "--sizes");
        require(n >= 100, "bench --gpu: --sizes: a tube needs at least 100 nodes (got ", n, ")");
        o.sizes.push_back(n);
      }
    } else if (a == "--batch") {
      o.batch = static_cast<int>(number(value(i), "--batch"));
    } else if (a == "--cpu-max") {
      o.cpu_max_nodes = number(value(i), "--cpu-max");
    } else if (a == "--no-torch") {
      o.torch = false;
    } else if (a == "--compact") {
      o.compact = true;
    } else if (a == "--packed") {
      o.packed = true;
    } else if (a == "--gather") {
      o.gathers.clear();
      std::stringstream ss(value(i));
      for (std::string item; std::getline(ss, item, ',');) {
        const long g = number(item, "--gather");
        require(g == 0 || g == 1 || g == 2 || g == 4,
                "bench --gpu: --gather: each value must be 0 (automatic), 1, 2 or 4 (got ", g, ")");
        o.gathers.push_back(static_cast<int>(g));
      }
    } else if (a == "--models-per-thread") {
      o.models_per_thread.clear();
      std::stringstream ss(value(i));
      for (std::string item; std::getline(ss, item, ',');) {
        const long m = number(item, "--models-per-thread");
        require(m == 1 || m == 2 || m == 4,
                "bench --gpu: --models-per-thread: each value must be 1, 2 or 4 (got ", m, ")");
        if (m > 1) o.models_per_thread.push_back(static_cast<int>(m));
      }
    } else if (a == "--out") {
      o.out = value(i);
    } else if (a == "--kidney") {
      o.kidney = value(i);
    } else if (a == "--device") {
      o.device = static_cast<int>(number(value(i), "--device"));
    } else {
      throw InvalidInput(
          cat("bench --gpu: unknown argument '", a,
              "' (expected --sizes, --batch, --kidney, --cpu-max, --no-torch, --compact, --gather, "
              "--models-per-thread, --packed, --out, --device)"));
    }
  }
  return o;
}

#ifndef MEDSPRING_HAS_CUDA

int run_gpu_bench(const GpuBenchOptions&) {
  std::cerr
      << "error: bench --gpu: this build has no CUDA backend, so no GPU can be used (configure with a "
         "CUDA compiler, -DMEDSPRING_CUDA=ON; see docs/gpu.md). Nothing was measured; `medspring bench` "
         "times the CPU engine.\n";
  return 2;
}

#else

namespace {

TubeSize tube_size(long n) {
  if (n == 1200) return {40, 30};
  if (n == 120000) return {400, 300};
  const auto side = static_cast<Index>(std::lround(std::sqrt(static_cast<double>(n))));
  return {std::max<Index>(side, 4), std::max<Index>(side, 4)};
}

std::vector<PointLoad> tube_load(const Model& m, const TubeSize& t) {
  PointLoad L;
  L.node = (t.rings / 2) * t.spokes;  // a node of the middle ring, as bench --compare
  L.force = Vec3(0, 0, -0.5);
  L.t_ramp = 0;
  (void)m;
  return {L};
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Times `frame` until budget_s is spent (at least 5, at most max_samples calls): median µs.
template <class F>
double time_frames(F&& frame, double budget_s, long max_samples = 2000) {
  using clock = std::chrono::steady_clock;
  std::vector<double> us;
  const auto start = clock::now();
  while (static_cast<long>(us.size()) < max_samples) {
    const auto t0 = clock::now();
    frame();
    us.push_back(std::chrono::duration<double, std::micro>(clock::now() - t0).count());
    if (us.size() >= 5 && std::chrono::duration<double>(clock::now() - start).count() > budget_s) break;
  }
  return median(us);
}

std::string json_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o;
}

// The same step in PyTorch (eager, scatter with index_add_): arrays of the model in raw files.
constexpr const char* kTorchScript = R"PY(
import json, sys, numpy as np, torch
d, prec = sys.argv[1], sys.argv[2]
meta = json.load(open(d + "/meta.json"))
dt = torch.float64 if prec == "fp64" else torch.float32
dev = torch.device("cuda")
def load(name, kind=np.float64):
    return np.fromfile(d + "/" + name + ".bin", dtype=kind)
n = meta["nodes"]
x0 = torch.tensor(load("x0").reshape(n, 3), dtype=dt, device=dev)
mass = torch.tensor(load("mass"), dtype=dt, device=dev)[:, None]
damp = torch.tensor(load("damping"), dtype=dt, device=dev)[:, None]
kr = torch.tensor(load("kr"), dtype=dt, device=dev)[:, None]
free = torch.tensor(load("free", np.uint8), device=dev).bool()[:, None]
i = torch.tensor(load("i", np.int32).astype(np.int64), device=dev)
j = torch.tensor(load("j", np.int32).astype(np.int64), device=dev)
L0 = torch.tensor(load("L0"), dtype=dt, device=dev)
k = torch.tensor(load("k"), dtype=dt, device=dev)
kp = torch.tensor(load("kp"), dtype=dt, device=dev)
fext = torch.zeros_like(x0); fext[meta["load_node"]] = torch.tensor(meta["load"], dtype=dt, device=dev)
h = meta["h"]
x = x0.clone(); v = torch.zeros_like(x0)
c = 1.0 / (mass + h * damp)
def step(x, v):
    e = x[j] - x[i]
    L = torch.linalg.vector_norm(e, dim=1)
    dd = L - L0
    t = (dd * (k + kp * dd * dd) / L)[:, None] * e
    f = fext - kr * (x - x0)
    f.index_add_(0, i, t)
    f.index_add_(0, j, -t)
    vn = torch.where(free, (mass * v + h * f) * c, v)
    return x + h * vn * free, vn
for _ in range(20): x, v = step(x, v)
torch.cuda.synchronize()
reps = 200 if n <= 200000 else 20
ms = []
for _ in range(10):
    a = torch.cuda.Event(enable_timing=True); b = torch.cuda.Event(enable_timing=True)
    a.record()
    for _ in range(reps): x, v = step(x, v)
    b.record(); b.synchronize()
    ms.append(a.elapsed_time(b) / reps)
ms.sort()
print(json.dumps({"substep_us": 1e3 * ms[len(ms) // 2], "torch": torch.__version__,
                  "finite": bool(torch.isfinite(x).all().item())}))
)PY";

constexpr const char* kPlotScript = R"PY(
import json, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
r = json.load(open(sys.argv[1]))
fig, ax = plt.subplots(figsize=(6.4, 4.6))
for key, label in [("gpu_fp64_substep_us", "GPU fp64 (kernel, graph)"), ("gpu_fp32_substep_us", "GPU fp32 (kernel, graph)"),
                   ("torch_fp64_substep_us", "PyTorch fp64 (eager)"), ("cpu_substep_us", "CPU engine, 1 thread")]:
    pts = [(t["nodes"], t[key]) for t in r["tubes"] if t.get(key)]
    if pts:
        ax.loglog(*zip(*pts), marker="o", label=label)
ax.set_xlabel("nodes"); ax.set_ylabel("µs per substep"); ax.grid(True, which="both", alpha=0.3)
ax.set_title("medspring bench --gpu: " + r["device"]["name"]); ax.legend()
fig.tight_layout(); fig.savefig(sys.argv[2], dpi=130)
)PY";

std::string python() {
  const char* env = std::getenv("MEDSPRING_PYTHON");
  return env && *env ? env : "python3";
}

std::string run_capture(const std::string& command) {
  std::string out;
  FILE* p = popen(command.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  const int rc = pclose(p);
  return rc == 0 ? out : std::string();
}

template <class T>
void write_raw(const fs::path& p, const T* data, std::size_t count) {
  std::ofstream f(p, std::ios::binary);
  f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(count * sizeof(T)));
  if (!f) throw IoError(cat(p.string(), ": cannot write"));
}

// Returns the PyTorch step's µs per substep, or < 0 (reason in `why`).
double torch_step(const Model& m, const std::vector<PointLoad>& loads, double h, const std::string& precision,
                  const fs::path& dir, std::string& why) {
  fs::create_directories(dir);
  write_raw(dir / "x0.bin", m.x0.data(), static_cast<std::size_t>(m.x0.size()));
  write_raw(dir / "mass.bin", m.mass.data(), static_cast<std::size_t>(m.mass.size()));
  write_raw(dir / "damping.bin", m.damping.data(), static_cast<std::size_t>(m.damping.size()));
  write_raw(dir / "kr.bin", m.kr.data(), static_cast<std::size_t>(m.kr.size()));
  std::vector<std::uint8_t> free(m.fixed.size());
  for (std::size_t a = 0; a < free.size(); ++a) free[a] = m.fixed[a] ? 0 : 1;
  write_raw(dir / "free.bin", free.data(), free.size());
  write_raw(dir / "i.bin", m.springs.i.data(), m.springs.i.size());
  write_raw(dir / "j.bin", m.springs.j.data(), m.springs.j.size());
  write_raw(dir / "L0.bin", m.springs.L0.data(), m.springs.L0.size());
  write_raw(dir / "k.bin", m.springs.k.data(), m.springs.k.size());
  write_raw(dir / "kp.bin", m.springs.kp.data(), m.springs.kp.size());
  {
    std::ofstream meta(dir / "meta.json");
    meta.precision(17);
    meta << "{\"nodes\": " << m.num_nodes() << ", \"load_node\": " << loads[0].node << ", \"load\": ["
         << loads[0].force[0] << ", " << loads[0].force[1] << ", " << loads[0].force[2] << "], \"h\": " << h
         << "}\n";
    std::ofstream(dir / "torch_step.py") << kTorchScript;
  }
  const std::string out = run_capture(
      cat("'", python(), "' '", (dir / "torch_step.py").string(), "' '", dir.string(), "' ", precision));
  const auto p = out.find("\"substep_us\": ");
  if (p == std::string::npos) {
    why = "the PyTorch step failed (see its output above)";
    return -1;
  }
  return std::stod(out.substr(p + 14));
}

}  // namespace

namespace {

// Row-name suffix of a gather batch: "" for 1, "-g2", "-g4", "-gauto" for 0 (Options::gather_batch).
std::string gather_suffix(int gather) {
  return gather == 0 ? "-gauto" : gather == 1 ? "" : cat("-g", gather);
}

struct KidneyVariant {
  gpu::Options::Kernel kernel;
  bool compact;
  int gather;
  gpu::Options::BatchOrder order;
  std::string name;
  int models_per_thread = 1;  // gpu::Options::models_per_thread
  bool packed = false;        // gpu::Options::packed_table
};

// The batch case's kernels: grid (rows first: a model's row blocks side by side; "grid-models": the same
// rows of consecutive models side by side) and one block per model; with --compact the same with compact
// parameters (as many classes as the kidney needs), the grid kernel for each --gather batch; for each
// --models-per-thread M the grid kernel with M models per thread ("grid-m2"; "grid-compact-m2" with
// --compact).
std::vector<KidneyVariant> kidney_variants(const GpuBenchOptions& o) {
  using K = gpu::Options::Kernel;
  constexpr auto rows = gpu::Options::BatchOrder::RowsFirst, models = gpu::Options::BatchOrder::ModelsFirst;
  std::vector<KidneyVariant> v{{K::Grid, false, 1, rows, "grid"},
                               {K::Grid, false, 1, models, "grid-models"},
                               {K::PerBlock, false, 1, rows, "block"}};
  if (o.compact) {
    for (const int g : o.gathers) v.push_back({K::Grid, true, g, rows, "grid-compact" + gather_suffix(g)});
    v.push_back({K::PerBlock, true, 1, rows, "block-compact"});
  }
  for (const int m : o.models_per_thread)
    v.push_back({K::Grid, o.compact, 1, rows, cat(o.compact ? "grid-compact-m" : "grid-m", m), m});
  if (o.packed) v.push_back({K::Grid, true, 1, rows, "grid-packed", 1, true});
  return v;
}

}  // namespace

int run_gpu_bench(const GpuBenchOptions& o) {
  const gpu::DeviceInfo dev = gpu::require_device(o.device);  // throws: no silent fallback
  std::cout << "GPU: " << dev.name << " (compute " << dev.major << "." << dev.minor << ", "
            << dev.multiprocessors << " SMs, " << dev.memory_bytes / (1u << 20) << " MiB; driver "
            << dev.driver_version << ", runtime " << dev.runtime_version << ")\n";
  const double copy_gbs = gpu::measured_copy_bandwidth(std::size_t(1) << 30, 20, o.device);
  std::cout << "measured device-to-device copy bandwidth: " << copy_gbs
            << " GB/s (read + write, 1 GiB, median of 20)\n";
  bool torch_ok = false;
  std::string torch_why = "disabled (--no-torch)";
  if (o.torch) {
    const std::string probe =
        run_capture(cat("'", python(), "' -c 'import torch; print(torch.cuda.is_available())' 2>/dev/null"));
    torch_ok = probe.find("True") != std::string::npos;
    if (!torch_ok) torch_why = "torch not importable or sees no GPU";
  }
  const fs::path work = o.out.empty() ? fs::temp_directory_path() / "medspring_gpu_bench" : fs::path(o.out);
  fs::create_directories(work);

  std::ostringstream js;
  js.precision(10);
  js << "{\n  \"device\": {\"name\": \"" << json_escape(dev.name) << "\", \"compute\": \"" << dev.major << "."
     << dev.minor << "\", \"multiprocessors\": " << dev.multiprocessors
     << ", \"memory_bytes\": " << dev.memory_bytes << ", \"driver\": " << dev.driver_version
     << ", \"runtime\": " << dev.runtime_version << "},\n"
     << "  \"copy_bandwidth_gbs\": " << copy_gbs << ",\n  \"torch\": " << (torch_ok ? "true" : "false")
     << ",\n  \"tubes\": [";
  std::printf("\n%-10s %-5s %12s %12s %10s %8s %12s %12s\n", "tube", "prec", "substep_us", "frame_us", "GB/s",
              "of_copy", "torch_us", "cpu_us");
  StepSettings s;  // 0.5 ms frames, guard on, as bench --compare
  bool first = true;
  for (const long n : o.sizes) {
    const TubeSize ts = tube_size(n);
    const auto t_build = std::chrono::steady_clock::now();
    const Model m = tube_model(ts);
    const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_build).count();
    const std::vector<PointLoad> loads = tube_load(m, ts);
    double cpu_us = -1, cpu_subs = 0;
    if (m.num_nodes() <= o.cpu_max_nodes) {
      State st = make_state(m, s);
      for (int f = 0; f < 20; ++f) step(m, st, s, &loads);
      const auto before = st.substeps;
      const auto frames_before = st.frames;
      cpu_us = time_frames([&] { step(m, st, s, &loads); }, 2.0);
      cpu_subs = static_cast<double>(st.substeps - before) / static_cast<double>(st.frames - frames_before);
    }
    // Variants: full parameter arrays (fp64, fp32), then with --compact compact parameters for each gather
    // batch of --gather (fp64c, fp32c; fp64c-g4: four entries gathered at a time), with --packed the
    // packed table (fp64p, fp32p).
    struct TubeVariant {
      bool compact;
      int gather;
      bool packed;
    };
    std::vector<TubeVariant> variants{{false, 1, false}};
    if (o.compact)
      for (const int g : o.gathers) variants.push_back({true, g, false});
    if (o.packed) variants.push_back({true, 1, true});
    for (const auto& [compact, gather, packed] : variants)
      for (const gpu::Precision p : {gpu::Precision::Double, gpu::Precision::Float}) {
        gpu::Options go;
        go.precision = p;
        go.device = o.device;
        go.compact_params = compact;
        go.gather_batch = gather;
        go.packed_table = packed;
        gpu::Engine e({&m}, s, go);
        if (packed && !e.pack_report().fits) std::cout << e.packed_table_note() << "\n";  // ran unpacked
        e.set_loads(0, loads);
        for (int f = 0; f < 20; ++f) e.step();
        const std::uint64_t sub0 = e.substeps(), fr0 = e.frames();
        const double frame_us = time_frames([&] { e.step(); }, compact ? 0.5 : 2.0);
        const double subs = static_cast<double>(e.substeps() - sub0) / static_cast<double>(e.frames() - fr0);
        const double substep_us = e.time_substeps(m.num_nodes() <= 200000 ? 200 : 20, 10);
        const double gbs = static_cast<double>(e.device_bytes()) / (substep_us * 1e-6) / 1e9;
        double torch_us = -1;
        std::string why = torch_why;
        if (torch_ok && !compact)
          torch_us = torch_step(m, loads, s.dt / subs, gpu::to_string(p), work / "torch_step", why);
        const double cpu_sub_us = cpu_us > 0 ? cpu_us / cpu_subs : -1;
        // fp64c: compact parameters; fp64c-g4: and four entries gathered at a time.
        const std::string key = gpu::to_string(p) +
                                (packed    ? "p"
                                 : compact ? "c"
                                           : "") +
                                (packed ? "" : gather_suffix(gather));
        std::printf("%-10s %-5s %12.2f %12.2f %10.0f %7.0f%% %12s %12s\n", size_name(m.num_nodes()).c_str(),
                    key.c_str(), substep_us, frame_us, gbs, 100.0 * gbs / copy_gbs,
                    torch_us > 0 ? cat(torch_us).c_str() : "-",
                    cpu_sub_us > 0 ? cat(cpu_sub_us).c_str() : "-");
        std::fflush(stdout);
        js << (first ? "\n" : ",\n") << "    {\"name\": \"" << size_name(m.num_nodes())
           << "\", \"nodes\": " << m.num_nodes() << ", \"springs\": " << m.num_springs()
           << ", \"precision\": \"" << key << "\", \"build_s\": " << build_s
           << ", \"substeps_per_frame\": " << subs << ", \"gpu_" << key << "_substep_us\": " << substep_us
           << ", \"gpu_frame_us\": " << frame_us << ", \"device_bytes\": " << e.device_bytes()
           << ", \"bandwidth_gbs\": " << gbs << ", \"fraction_of_copy\": " << gbs / copy_gbs;
        if (torch_us > 0) js << ", \"torch_" << key << "_substep_us\": " << torch_us;
        if (cpu_sub_us > 0) js << ", \"cpu_substep_us\": " << cpu_sub_us << ", \"cpu_frame_us\": " << cpu_us;
        js << "}";
        first = false;
      }
  }
  js << "\n  ]";
  if (o.batch > 0) {
    // The real kidney from a model package (medspring export of the bundled kidney scene) when given,
    // otherwise the procedural phantom of the same size.
    const HybridKidney phantom = hybrid_kidney_phantom();
    BodyPtr real;
    if (!o.kidney.empty()) real = make_body(read_model_package(o.kidney));
    const Model& km = real ? real->model() : phantom.model();
    const std::string kidney_name =
        real ? "real kidney " + fs::path(o.kidney).filename().string() : "kidney phantom";
    js << ",\n  \"batch\": [";
    bool bfirst = true;
    // One kidney (the latency of a single organ: the haptic case) and the whole batch (the throughput).
    for (const int batch : {1, o.batch})
      for (const gpu::Precision p : {gpu::Precision::Double, gpu::Precision::Float})
        for (const KidneyVariant& kv : kidney_variants(o)) {
          const std::vector<const Model*> models(static_cast<std::size_t>(batch), &km);
          gpu::Options go;
          go.precision = p;
          go.device = o.device;
          go.kernel = kv.kernel;
          go.compact_params = kv.compact;
          go.compact_max_classes = 65536;  // the real kidney: a stiffness per spring (a per-spring table)
          go.gather_batch = kv.gather;
          go.batch_order = kv.order;
          go.models_per_thread = kv.models_per_thread;
          go.packed_table = kv.packed;
          const std::string kname = kv.name;
          gpu::Engine e(models, s, go);
          if (kv.packed && !e.pack_report().fits) std::cout << e.packed_table_note() << "\n";
          for (int b = 0; b < batch; ++b) {
            PointLoad L;
            L.node = b % km.num_nodes();
            L.force = Vec3(0, 0, -0.2 - 0.6 * (b % 7) / 7.0);
            L.t_ramp = 10;
            e.set_loads(b, {L});
          }
          for (int f = 0; f < 10; ++f) e.step();
          const double substep_us = e.time_substeps(100, 10);
          const double rate = batch / (substep_us * 1e-6);
          // Whole frames through step() (the host's load table, the upload, the per-frame readback): median.
          std::vector<double> frame_us;
          for (int f = 0; f < 21; ++f) {
            const auto t0 = std::chrono::steady_clock::now();
            e.step();
            frame_us.push_back(
                std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
          }
          std::sort(frame_us.begin(), frame_us.end());
          const double frame_med = frame_us[frame_us.size() / 2];
          std::printf(
              "batch: %d %s (%d nodes each) %s, %s kernel: %.2f µs per substep, %.3g "
              "model-substeps/s; step() %.1f µs per frame\n",
              batch, kidney_name.c_str(), static_cast<int>(km.num_nodes()), gpu::to_string(p).c_str(),
              kname.c_str(), substep_us, rate, frame_med);
          js << (bfirst ? "\n" : ",\n") << "    {\"models\": " << batch << ", \"model\": \""
             << json_escape(kidney_name) << "\""
             << ", \"nodes_per_model\": " << km.num_nodes() << ", \"precision\": \"" << gpu::to_string(p)
             << "\", \"kernel\": \"" << kname << "\", \"substep_us\": " << substep_us
             << ", \"model_substeps_per_s\": " << rate << ", \"step_frame_us\": " << frame_med << "}";
          bfirst = false;
        }
    js << "\n  ]";
  }
  js << "\n}\n";
  if (!o.out.empty()) {
    const fs::path json = work / "gpu_bench.json", script = work / "gpu_bench_plot.py",
                   png = work / "gpu_bench.png";
    std::ofstream(json) << js.str();
    std::ofstream(script) << kPlotScript;
    std::cout << "wrote " << json.string() << "\n";
    if (std::system(cat("'", python(), "' '", script.string(), "' '", json.string(), "' '", png.string(), "'")
                        .c_str()) == 0)
      std::cout << "wrote " << png.string() << "\n";
    else
      std::cout << "no plot (matplotlib not importable by " << python() << ")\n";
  }
  if (!torch_ok) std::cout << "PyTorch step: " << torch_why << "\n";
  return 0;
}

#endif

}  // namespace medspring::bench
