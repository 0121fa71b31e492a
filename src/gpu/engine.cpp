// The GPU engine's host side: device arrays, the frame loop (the CPU engine's substep rule, guard and
// rollbacks), CUDA graphs, asynchronous readback. The kernels are in kernels.cu.
#include "medspring/gpu/engine.hpp"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <utility>

#include "launch.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/spring_table.hpp"
#include "medspring/physics/stability.hpp"

namespace medspring::gpu {

namespace {

constexpr const char* kCpuAlternative = "the CPU engine (leave out --gpu / --device cuda)";

void check(cudaError_t e, const char* what) {
  if (e == cudaSuccess) return;
  cudaGetLastError();  // clear a sticky launch error for the next call
  if (e == cudaErrorMemoryAllocation)
    throw GpuError(cat("GPU: out of device memory while ", what,
                       "; use a smaller model or batch, --precision fp32 (half the bytes), or ",
                       kCpuAlternative));
  if (e == cudaErrorInsufficientDriver)
    throw GpuError(cat("GPU: the NVIDIA driver is older than the CUDA runtime this build uses (", what,
                       "); update the driver, or use ", kCpuAlternative));
  if (e == cudaErrorNoDevice)
    throw GpuError(cat("GPU: no CUDA device found (", what, "); use ", kCpuAlternative));
  throw GpuError(cat("GPU: ", what, " failed: ", cudaGetErrorName(e), " (", cudaGetErrorString(e), ")"));
}

template <class T>
struct DeviceArray {
  T* p = nullptr;
  std::size_t n = 0;
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() {
    if (p) cudaFree(p);
  }
  void allocate(std::size_t count, const char* what) {
    if (p) cudaFree(p);
    p = nullptr;
    n = count;
    check(cudaMalloc(reinterpret_cast<void**>(&p), std::max<std::size_t>(count, 1) * sizeof(T)), what);
  }
  void upload(const T* h, std::size_t count, std::size_t offset, const char* what) {
    check(cudaMemcpy(p + offset, h, count * sizeof(T), cudaMemcpyHostToDevice), what);
  }
};

template <class T>
struct PinnedArray {
  T* p = nullptr;
  std::size_t n = 0;
  PinnedArray() = default;
  PinnedArray(const PinnedArray&) = delete;
  PinnedArray& operator=(const PinnedArray&) = delete;
  ~PinnedArray() {
    if (p) cudaFreeHost(p);
  }
  void allocate(std::size_t count, const char* what) {
    if (p) cudaFreeHost(p);
    p = nullptr;
    n = count;
    check(cudaMallocHost(reinterpret_cast<void**>(&p), std::max<std::size_t>(count, 1) * sizeof(T)), what);
  }
};

// Same topology: node count and spring ends.
void require_same_topology(const Model& a, const Model& b, int index) {
  const bool same =
      a.num_nodes() == b.num_nodes() && a.springs.i == b.springs.i && a.springs.j == b.springs.j;
  if (!same)
    throw GpuError(cat("gpu::Engine: model ", index, " ('", b.name, "') has another topology than model 0 ('",
                       a.name, "'): a batch needs the same nodes and spring ends; run it in its own Engine"));
}

}  // namespace

Precision parse_precision(const std::string& text) {
  if (text == "fp64" || text == "double" || text == "float64") return Precision::Double;
  if (text == "fp32" || text == "float" || text == "float32") return Precision::Float;
  throw InvalidInput(cat("precision: unknown value '", text, "' (expected fp64 or fp32)"));
}

std::string to_string(Precision p) {
  return p == Precision::Double ? "fp64" : "fp32";
}

bool built() {
  return true;
}

DeviceInfo require_device(int index) {
  int driver = 0, runtime = 0;
  cudaDriverGetVersion(&driver);
  cudaRuntimeGetVersion(&runtime);
  if (driver == 0)
    throw GpuError(cat("GPU: no NVIDIA driver found (libcuda not loadable); use ", kCpuAlternative));
  if (driver < runtime)
    throw GpuError(cat("GPU: the NVIDIA driver supports CUDA ", driver / 1000, ".", (driver % 1000) / 10,
                       " but this build needs ", runtime / 1000, ".", (runtime % 1000) / 10,
                       "; update the driver, or use ", kCpuAlternative));
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e == cudaErrorNoDevice || (e == cudaSuccess && count == 0)) {
    cudaGetLastError();
    throw GpuError(cat("GPU: no CUDA device found; use ", kCpuAlternative));
  }
  check(e, "counting CUDA devices");
  if (index < 0 || index >= count)
    throw GpuError(cat("GPU: device ", index, " does not exist (", count, " device(s): 0..", count - 1, ")"));
  cudaDeviceProp prop{};
  check(cudaGetDeviceProperties(&prop, index), "reading the device properties");
  if (prop.major < 9)
    throw GpuError(cat("GPU: device ", index, " (", prop.name, ") has compute capability ", prop.major, ".",
                       prop.minor,
                       "; the kernels are built for 9.0 (Hopper: H100/H200) — rebuild with "
                       "-DCMAKE_CUDA_ARCHITECTURES=",
                       prop.major, prop.minor, ", or use ", kCpuAlternative));
  DeviceInfo d;
  d.index = index;
  d.name = prop.name;
  d.major = prop.major;
  d.minor = prop.minor;
  d.multiprocessors = prop.multiProcessorCount;
  d.memory_bytes = prop.totalGlobalMem;
  d.driver_version = driver;
  d.runtime_version = runtime;
  return d;
}

void require_supported(const std::string& kind, bool local_overlay, bool tools) {
  if (kind == "smrm" || kind == "tree" || kind == "vessel")
    throw GpuError(
        cat("GPU: model kind '", kind,
            "' (SMRM vessel: frames and medial reconstruction) is not ported to the GPU path; run it "
            "with ",
            kCpuAlternative));
  if (kind != "surface" && kind != "hybrid")
    throw GpuError(cat("GPU: model kind '", kind,
                       "' is not supported on the GPU path (surface and hybrid are); use ", kCpuAlternative));
  if (local_overlay)
    throw GpuError(
        cat("GPU: the local deformation overlay is not ported to the GPU path; use ", kCpuAlternative));
  if (tools)
    throw GpuError(cat("GPU: tools (contact) are not ported to the GPU path; use ", kCpuAlternative));
}

double measured_copy_bandwidth(std::size_t bytes, int repeats, int device) {
  require_device(device);
  check(cudaSetDevice(device), "selecting the device");
  DeviceArray<unsigned char> a, b;
  a.allocate(bytes, "allocating the bandwidth probe");
  b.allocate(bytes, "allocating the bandwidth probe");
  check(cudaMemset(a.p, 1, bytes), "filling the bandwidth probe");
  cudaEvent_t e0, e1;
  check(cudaEventCreate(&e0), "creating events");
  check(cudaEventCreate(&e1), "creating events");
  std::vector<float> ms;
  for (int r = 0; r < repeats + 2; ++r) {
    cudaEventRecord(e0);
    cudaMemcpyAsync(b.p, a.p, bytes, cudaMemcpyDeviceToDevice);
    cudaEventRecord(e1);
    check(cudaEventSynchronize(e1), "timing a device copy");
    float t = 0;
    cudaEventElapsedTime(&t, e0, e1);
    if (r >= 2) ms.push_back(t);  // two warm-up copies
  }
  cudaEventDestroy(e0);
  cudaEventDestroy(e1);
  std::sort(ms.begin(), ms.end());
  const double med = ms[ms.size() / 2];
  return 2.0 * static_cast<double>(bytes) / (med * 1e-3) / 1e9;
}

// ------------------------------------------------------------------------------------------------
// Engine

struct Engine::Impl {
  virtual ~Impl() = default;
  DeviceInfo device;
  Precision precision = Precision::Double;
  std::vector<const Model*> models;
  StepSettings settings;
  Options options;
  double t = 0, stiffening = 1.0;
  std::uint64_t frames = 0, substeps = 0;
  Warnings warnings;

  virtual void set_loads(int b, const std::vector<PointLoad>& loads) = 0;
  virtual void upload(int b, const State& st) = 0;
  virtual StepStatus step() = 0;
  virtual MatX3 fetch(int b, bool velocities) = 0;
  virtual void request_positions() = 0;
  virtual bool poll_positions(int b, MatX3& out) = 0;
  virtual std::size_t device_bytes() const = 0;
  virtual double time_substeps(int count, int repeats) = 0;
};

namespace {

template <class R>
struct Backend final : Engine::Impl {
  int B = 1;
  Index n = 0;
  std::size_t entries = 0;
  bool soft = false;
  cudaStream_t stream = nullptr, copy_stream = nullptr;

  // Model arrays (node arrays and spring parameters per model, topology shared).
  DeviceArray<R> x0, mass, damping, kr, L0, k, kp, ik;
  DeviceArray<unsigned char> fixed;
  DeviceArray<int> load_slot, slice_begin, slice_width, other;
  // State: ping-pong buffers, `cur` holds the current positions and velocities.
  DeviceArray<R> xb[2], vb[2];
  int cur = 0;
  // Loads: per model; the load table of a batch of substeps (substep k, model b, row r).
  std::vector<std::vector<PointLoad>> loads;
  std::vector<LoadSlots> slots;
  int rows = 0;       // rows per model (max over the batch, >= 1)
  long capacity = 0;  // substeps the load table, stiffening slots and graphs are sized for
  PinnedArray<R> rows_host;
  DeviceArray<R> rows_dev;
  std::vector<double> row_scratch;
  // Frame scalars.
  detail::FrameScalars scalars_init{INT_MAX, 0};
  PinnedArray<detail::FrameScalars> scalars_host_init, scalars_host;
  DeviceArray<detail::FrameScalars> scalars_dev;
  DeviceArray<unsigned long long> stiff_dev;
  PinnedArray<unsigned long long> stiff_host;
  // Graphs per (substeps, parity of cur).
  std::map<std::pair<long, int>, cudaGraphExec_t> graphs;
  // Asynchronous readback: device staging + pinned host snapshots, double-buffered.
  DeviceArray<R> staging[2];
  PinnedArray<R> snapshot[2];
  cudaEvent_t staged[2]{}, copied[2]{};
  std::uint64_t snap_seq[2]{0, 0}, next_seq = 1;
  std::vector<std::uint64_t> seen;
  bool requested[2]{false, false};
  int next_snap = 0;

  Backend(const std::vector<const Model*>& ms, const StepSettings& s, const Options& o,
          const DeviceInfo& dev) {
    device = dev;
    precision = std::is_same_v<R, double> ? Precision::Double : Precision::Float;
    models = ms;
    settings = s;
    options = o;
    B = static_cast<int>(ms.size());
    const Model& m0 = *ms[0];
    n = m0.num_nodes();
    check(cudaSetDevice(dev.index), "selecting the device");
    check(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), "creating a stream");
    check(cudaStreamCreateWithFlags(&copy_stream, cudaStreamNonBlocking), "creating a stream");
    for (int w = 0; w < 2; ++w) {
      check(cudaEventCreateWithFlags(&staged[w], cudaEventDisableTiming), "creating an event");
      check(cudaEventCreateWithFlags(&copied[w], cudaEventDisableTiming), "creating an event");
    }
    const auto un = static_cast<std::size_t>(n);
    const auto uB = static_cast<std::size_t>(B);
    // Topology from model 0, parameters from every model.
    const SpringTableArrays<R> T0 = make_spring_table<R>(m0);
    entries = T0.entries();
    slice_begin.allocate(T0.slice_begin.size(), "allocating the spring table");
    slice_begin.upload(T0.slice_begin.data(), T0.slice_begin.size(), 0, "uploading the spring table");
    slice_width.allocate(T0.slice_width.size(), "allocating the spring table");
    slice_width.upload(T0.slice_width.data(), T0.slice_width.size(), 0, "uploading the spring table");
    other.allocate(entries, "allocating the spring table");
    other.upload(T0.other.data(), entries, 0, "uploading the spring table");
    for (DeviceArray<R>* a : {&L0, &k, &kp, &ik}) a->allocate(entries * uB, "allocating the spring table");
    for (DeviceArray<R>* a : {&mass, &damping, &kr}) a->allocate(un * uB, "allocating the node arrays");
    x0.allocate(3 * un * uB, "allocating the node arrays");
    fixed.allocate(un * uB, "allocating the node arrays");
    load_slot.allocate(un * uB, "allocating the node arrays");
    for (int p = 0; p < 2; ++p) {
      xb[p].allocate(3 * un * uB, "allocating the state");
      vb[p].allocate(3 * un * uB, "allocating the state");
    }
    std::vector<R> zero(3 * un, R(0));
    for (int b = 0; b < B; ++b) {
      const Model& m = *ms[static_cast<std::size_t>(b)];
      if (b > 0) require_same_topology(m0, m, b);
      soft = soft || m.has_soft_springs;
      const bool same = b > 0 && &m == &m0;  // a batch of one model: its arrays once
      const SpringTableArrays<R> T = b == 0 || same ? SpringTableArrays<R>{} : make_spring_table<R>(m);
      const SpringTableArrays<R>& Tb = b == 0 || same ? T0 : T;
      const auto ub = static_cast<std::size_t>(b);
      L0.upload(Tb.L0.data(), entries, ub * entries, "uploading the spring table");
      k.upload(Tb.k.data(), entries, ub * entries, "uploading the spring table");
      kp.upload(Tb.kp.data(), entries, ub * entries, "uploading the spring table");
      ik.upload(Tb.ik.data(), entries, ub * entries, "uploading the spring table");
      const NodeArrayData<R> N = make_node_arrays<R>(m);
      x0.upload(N.x0.data(), 3 * un, ub * 3 * un, "uploading the node arrays");
      mass.upload(N.mass.data(), un, ub * un, "uploading the node arrays");
      damping.upload(N.damping.data(), un, ub * un, "uploading the node arrays");
      kr.upload(N.kr.data(), un, ub * un, "uploading the node arrays");
      fixed.upload(N.fixed.data(), un, ub * un, "uploading the node arrays");
      load_slot.upload(N.load_slot.data(), un, ub * un, "uploading the node arrays");
      for (int p = 0; p < 2; ++p) {
        xb[p].upload(N.x0.data(), 3 * un, ub * 3 * un, "uploading the state");
        vb[p].upload(zero.data(), 3 * un, ub * 3 * un, "uploading the state");
      }
    }
    loads.assign(uB, {});
    slots.assign(uB, LoadSlots{{}, std::vector<int>(un, -1)});
    rows = 1;
    scalars_host_init.allocate(1, "allocating pinned memory");
    *scalars_host_init.p = scalars_init;
    scalars_host.allocate(1, "allocating pinned memory");
    scalars_dev.allocate(1, "allocating the frame scalars");
    ensure_capacity(std::max<long>(8, 1));
    seen.assign(uB, 0);
  }

  ~Backend() override {
    clear_graphs();
    if (stream) cudaStreamSynchronize(stream);
    if (copy_stream) cudaStreamSynchronize(copy_stream);
    for (int w = 0; w < 2; ++w) {
      if (staged[w]) cudaEventDestroy(staged[w]);
      if (copied[w]) cudaEventDestroy(copied[w]);
    }
    if (stream) cudaStreamDestroy(stream);
    if (copy_stream) cudaStreamDestroy(copy_stream);
  }

  void clear_graphs() {
    for (auto& g : graphs) cudaGraphExecDestroy(g.second);
    graphs.clear();
  }

  std::size_t row_count(long subs) const {
    return static_cast<std::size_t>(subs) * static_cast<std::size_t>(B) * 3 * static_cast<std::size_t>(rows);
  }

  void ensure_capacity(long subs) {
    if (subs <= capacity) return;
    check(cudaStreamSynchronize(stream), "finishing the work in flight");
    clear_graphs();
    capacity = std::max(subs, 2 * capacity);
    rows_host.allocate(row_count(capacity), "allocating pinned memory for the load table");
    rows_dev.allocate(row_count(capacity), "allocating the load table");
    stiff_dev.allocate(static_cast<std::size_t>(capacity), "allocating the stiffening slots");
    stiff_host.allocate(static_cast<std::size_t>(capacity), "allocating pinned memory");
  }

  void set_loads(int b, const std::vector<PointLoad>& L) override {
    require(b >= 0 && b < B, "gpu::Engine::set_loads: model ", b, " out of range (batch of ", B, ")");
    LoadSlots S = make_load_slots(L, n);
    check(cudaStreamSynchronize(stream), "finishing the work in flight");
    const auto ub = static_cast<std::size_t>(b);
    loads[ub] = L;
    slots[ub] = std::move(S);
    load_slot.upload(slots[ub].slot.data(), static_cast<std::size_t>(n), ub * static_cast<std::size_t>(n),
                     "uploading the load slots");
    int r = 1;
    for (const LoadSlots& s : slots) r = std::max(r, static_cast<int>(s.nodes.size()));
    if (r != rows) {  // the load table's shape changed: resize it, recapture the graphs
      rows = r;
      const long c = capacity;
      capacity = 0;
      ensure_capacity(c);
    }
  }

  void upload(int b, const State& st) override {
    require(b >= 0 && b < B, "gpu::Engine::upload: model ", b, " out of range (batch of ", B, ")");
    require(st.x.rows() == n && st.v.rows() == n, "gpu::Engine::upload: state of ", st.x.rows(),
            " nodes for a model of ", n);
    check(cudaStreamSynchronize(stream), "finishing the work in flight");
    std::vector<R> h(3 * static_cast<std::size_t>(n));
    const auto off = static_cast<std::size_t>(b) * h.size();
    for (std::size_t q = 0; q < h.size(); ++q) h[q] = static_cast<R>(st.x.data()[q]);
    xb[cur].upload(h.data(), h.size(), off, "uploading the state");
    for (std::size_t q = 0; q < h.size(); ++q) h[q] = static_cast<R>(st.v.data()[q]);
    vb[cur].upload(h.data(), h.size(), off, "uploading the state");
    if (b == 0) {
      t = st.t;
      stiffening = st.stiffening;
    }
  }

  detail::SubstepArgs<R> args(int parity, long kk, R h, bool stiff) {
    detail::SubstepArgs<R> A;
    A.nodes = {static_cast<int>(n), x0.p, mass.p, damping.p, kr.p, fixed.p, load_slot.p};
    A.table = {static_cast<int>(n), slice_begin.p, slice_width.p, other.p, L0.p, k.p, kp.p, ik.p};
    A.node_stride = n;
    A.entry_stride = static_cast<long long>(entries);
    A.batch = B;
    A.loads = rows_dev.p +
              static_cast<std::size_t>(kk) * static_cast<std::size_t>(B) * 3 * static_cast<std::size_t>(rows);
    A.load_rows = rows;
    const int p = (parity + static_cast<int>(kk & 1)) & 1;
    A.x = xb[p].p;
    A.v = vb[p].p;
    A.xo = xb[1 - p].p;
    A.vo = vb[1 - p].p;
    A.h = h;
    A.vmax2 = static_cast<R>(settings.v_max * settings.v_max);
    A.substep = static_cast<int>(kk);
    A.soft = soft;
    A.stiff = stiff;
    A.guard = settings.guard;
    A.stiff_bits = stiff ? stiff_dev.p + kk : stiff_dev.p;
    A.scalars = scalars_dev.p;
    return A;
  }

  // Enqueues a batch of `left` substeps of h from the current buffers (no host work, capturable).
  void enqueue(long left, double h, int rollbacks) {
    check(cudaMemcpyAsync(scalars_dev.p, scalars_host_init.p, sizeof(detail::FrameScalars),
                          cudaMemcpyHostToDevice, stream),
          "resetting the frame scalars");
    check(
        cudaMemsetAsync(stiff_dev.p, 0, static_cast<std::size_t>(left) * sizeof(unsigned long long), stream),
        "resetting the stiffening slots");
    check(
        cudaMemcpyAsync(rows_dev.p, rows_host.p, row_count(left) * sizeof(R), cudaMemcpyHostToDevice, stream),
        "uploading the load table");
    for (long kk = 0; kk < left; ++kk) {
      const bool stiff = kk == left - 1 || rollbacks == settings.max_rollbacks;
      check(detail::launch_substep(args(cur, kk, static_cast<R>(h), stiff), options.block, stream),
            "launching the substep kernel");
    }
    check(cudaMemcpyAsync(scalars_host.p, scalars_dev.p, sizeof(detail::FrameScalars), cudaMemcpyDeviceToHost,
                          stream),
          "reading the frame scalars");
    check(cudaMemcpyAsync(stiff_host.p, stiff_dev.p,
                          static_cast<std::size_t>(left) * sizeof(unsigned long long), cudaMemcpyDeviceToHost,
                          stream),
          "reading the stiffening");
  }

  void run_batch(long left, double h, int rollbacks) {
    const bool graph = options.graphs && rollbacks == 0 && left <= 64;
    if (!graph) {
      enqueue(left, h, rollbacks);
      return;
    }
    const auto key = std::make_pair(left, cur);
    auto it = graphs.find(key);
    if (it == graphs.end()) {
      cudaGraph_t g = nullptr;
      check(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal), "capturing a CUDA graph");
      try {
        enqueue(left, h, rollbacks);
      } catch (...) {
        cudaStreamEndCapture(stream, &g);
        if (g) cudaGraphDestroy(g);
        throw;
      }
      check(cudaStreamEndCapture(stream, &g), "capturing a CUDA graph");
      cudaGraphExec_t exec = nullptr;
      const cudaError_t e = cudaGraphInstantiate(&exec, g, 0);
      cudaGraphDestroy(g);
      check(e, "instantiating a CUDA graph");
      it = graphs.emplace(key, exec).first;
    }
    check(cudaGraphLaunch(it->second, stream), "launching a CUDA graph");
  }

  StepStatus step() override {
    StepStatus status;
    const StepSettings& s = settings;
    const double T = s.dt;
    long subs = 1;
    double hs = std::numeric_limits<double>::infinity();
    for (const Model* m : models) hs = std::min(hs, dt_safe(*m, stiffening, s.safety));
    if (T > hs * (1.0 + 1e-12)) {
      if (!s.substep) {
        ++warnings.unstable_refused;
        status.code = StepCode::Refused;
        return status;
      }
      const double need = std::ceil(T / hs);
      if (need > s.max_substeps) ++warnings.substeps_capped;
      subs = static_cast<long>(std::min<double>(need, s.max_substeps));
    }
    const double t0 = t;
    double h = T / static_cast<double>(subs);
    double tt = t0;
    long left = subs;
    int rollbacks = 0;
    while (left > 0) {
      ensure_capacity(left);
      // The load table: substep kk at the time the CPU engine evaluates it (t accumulated by h).
      row_scratch.resize(3 * static_cast<std::size_t>(rows));
      double tk = tt;
      for (long kk = 0; kk < left; ++kk) {
        for (int b = 0; b < B; ++b) {
          const auto ub = static_cast<std::size_t>(b);
          std::fill(row_scratch.begin(), row_scratch.end(), 0.0);
          load_rows(loads[ub], slots[ub], tk, row_scratch.data());
          R* dst = rows_host.p + (static_cast<std::size_t>(kk) * static_cast<std::size_t>(B) + ub) * 3 *
                                     static_cast<std::size_t>(rows);
          for (std::size_t q = 0; q < row_scratch.size(); ++q) dst[q] = static_cast<R>(row_scratch[q]);
        }
        tk += h;
      }
      run_batch(left, h, rollbacks);
      check(cudaStreamSynchronize(stream), "running a frame");
      const detail::FrameScalars fs = *scalars_host.p;
      const bool failed = fs.fail_first != INT_MAX;
      const long done = failed ? fs.fail_first : left;  // substeps that succeeded
      const long last = failed ? done : left - 1;       // last substep that ran (and evaluated forces)
      for (long kk = last; kk >= 0; --kk)
        if (kk == left - 1 || rollbacks == s.max_rollbacks) {
          double v = 0;
          std::memcpy(&v, &stiff_host.p[kk], sizeof v);
          stiffening = std::max(1.0, v);
          break;
        }
      cur = (cur + static_cast<int>(done & 1)) & 1;
      for (long kk = 0; kk < done; ++kk) tt += h;
      status.substeps += static_cast<int>(done);
      substeps += static_cast<std::uint64_t>(done);
      if (!failed) break;
      ++(fs.fail_code == hd::kNodeNonFinite ? warnings.nonfinite : warnings.velocity_limit);
      ++warnings.rollbacks;
      if (++rollbacks > s.max_rollbacks) {  // dropped frame, as step(): positions kept, velocities zeroed
        ++warnings.failed;
        status.code = StepCode::Failed;
        check(cudaMemsetAsync(vb[cur].p, 0, vb[cur].n * sizeof(R), stream), "zeroing the velocities");
        t = t0 + T;
        ++frames;
        return status;
      }
      status.code = StepCode::RolledBack;
      left = (left - done) * 2;
      h *= 0.5;
    }
    t = t0 + T;
    ++frames;
    return status;
  }

  MatX3 fetch(int b, bool velocities) override {
    require(b >= 0 && b < B, "gpu::Engine: model ", b, " out of range (batch of ", B, ")");
    check(cudaStreamSynchronize(stream), "finishing the work in flight");
    std::vector<R> h(3 * static_cast<std::size_t>(n));
    const DeviceArray<R>& src = velocities ? vb[cur] : xb[cur];
    check(cudaMemcpy(h.data(), src.p + static_cast<std::size_t>(b) * h.size(), h.size() * sizeof(R),
                     cudaMemcpyDeviceToHost),
          "copying the state back");
    MatX3 out(n, 3);
    for (std::size_t q = 0; q < h.size(); ++q) out.data()[q] = static_cast<double>(h[q]);
    return out;
  }

  void request_positions() override {
    const int w = next_snap;
    const std::size_t count = 3 * static_cast<std::size_t>(n) * static_cast<std::size_t>(B);
    if (!staging[w].p) {
      staging[w].allocate(count, "allocating the readback staging buffer");
      snapshot[w].allocate(count, "allocating pinned memory for the readback");
    }
    // The staging buffer may still be read by its previous host copy: the compute stream waits for it
    // (only when requests come faster than the PCIe copies finish).
    if (requested[w]) check(cudaStreamWaitEvent(stream, copied[w], 0), "ordering the readback");
    check(cudaMemcpyAsync(staging[w].p, xb[cur].p, count * sizeof(R), cudaMemcpyDeviceToDevice, stream),
          "staging the readback");
    check(cudaEventRecord(staged[w], stream), "ordering the readback");
    check(cudaStreamWaitEvent(copy_stream, staged[w], 0), "ordering the readback");
    check(
        cudaMemcpyAsync(snapshot[w].p, staging[w].p, count * sizeof(R), cudaMemcpyDeviceToHost, copy_stream),
        "reading back the positions");
    check(cudaEventRecord(copied[w], copy_stream), "ordering the readback");
    requested[w] = true;
    snap_seq[w] = next_seq++;
    next_snap = 1 - w;
  }

  bool poll_positions(int b, MatX3& out) override {
    require(b >= 0 && b < B, "gpu::Engine: model ", b, " out of range (batch of ", B, ")");
    int best = -1;
    for (int w = 0; w < 2; ++w) {
      if (!requested[w] || snap_seq[w] <= seen[static_cast<std::size_t>(b)]) continue;
      const cudaError_t e = cudaEventQuery(copied[w]);
      if (e == cudaErrorNotReady) continue;
      check(e, "reading back the positions");
      if (best < 0 || snap_seq[w] > snap_seq[best]) best = w;
    }
    if (best < 0) return false;
    out.resize(n, 3);
    const R* src = snapshot[best].p + static_cast<std::size_t>(b) * 3 * static_cast<std::size_t>(n);
    for (Index q = 0; q < 3 * n; ++q) out.data()[q] = static_cast<double>(src[q]);
    seen[static_cast<std::size_t>(b)] = snap_seq[best];
    return true;
  }

  double time_substeps(int count, int repeats) override {
    count += count & 1;
    require(count >= 2 && repeats >= 1, "gpu::Engine::time_substeps: count >= 2 and repeats >= 1");
    const StepSettings& s = settings;
    double hs = std::numeric_limits<double>::infinity();
    for (const Model* m : models) hs = std::min(hs, dt_safe(*m, stiffening, s.safety));
    const long subs = s.dt > hs * (1.0 + 1e-12) ? static_cast<long>(std::ceil(s.dt / hs)) : 1;
    const double h = s.dt / static_cast<double>(subs);
    ensure_capacity(1);
    row_scratch.assign(3 * static_cast<std::size_t>(rows), 0.0);
    for (int b = 0; b < B; ++b) {
      const auto ub = static_cast<std::size_t>(b);
      load_rows(loads[ub], slots[ub], t, row_scratch.data());
      for (std::size_t q = 0; q < row_scratch.size(); ++q)
        rows_host.p[ub * row_scratch.size() + q] = static_cast<R>(row_scratch[q]);
    }
    check(cudaMemcpyAsync(rows_dev.p, rows_host.p, row_count(1) * sizeof(R), cudaMemcpyHostToDevice, stream),
          "uploading the load table");
    check(cudaMemcpyAsync(scalars_dev.p, scalars_host_init.p, sizeof(detail::FrameScalars),
                          cudaMemcpyHostToDevice, stream),
          "resetting the frame scalars");
    cudaGraph_t g = nullptr;
    check(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal), "capturing a CUDA graph");
    for (int kk = 0; kk < count; ++kk) {
      detail::SubstepArgs<R> A = args(cur, kk, static_cast<R>(h), false);
      A.loads = rows_dev.p;  // the same loads for every substep
      A.substep = 0;         // no guard skipping between substeps
      A.guard = false;
      const cudaError_t e = detail::launch_substep(A, options.block, stream);
      if (e != cudaSuccess) {
        cudaStreamEndCapture(stream, &g);
        if (g) cudaGraphDestroy(g);
        check(e, "launching the substep kernel");
      }
    }
    check(cudaStreamEndCapture(stream, &g), "capturing a CUDA graph");
    cudaGraphExec_t exec = nullptr;
    const cudaError_t ie = cudaGraphInstantiate(&exec, g, 0);
    cudaGraphDestroy(g);
    check(ie, "instantiating a CUDA graph");
    cudaEvent_t e0, e1;
    check(cudaEventCreate(&e0), "creating an event");
    check(cudaEventCreate(&e1), "creating an event");
    std::vector<float> ms;
    for (int r = 0; r < repeats + 1; ++r) {  // the first replay warms up
      cudaEventRecord(e0, stream);
      cudaGraphLaunch(exec, stream);
      cudaEventRecord(e1, stream);
      const cudaError_t e = cudaEventSynchronize(e1);
      if (e != cudaSuccess) {
        cudaGraphExecDestroy(exec);
        check(e, "timing the substep kernel");
      }
      float v = 0;
      cudaEventElapsedTime(&v, e0, e1);
      if (r > 0) ms.push_back(v);
    }
    cudaEventDestroy(e0);
    cudaEventDestroy(e1);
    cudaGraphExecDestroy(exec);
    std::sort(ms.begin(), ms.end());
    return 1e3 * static_cast<double>(ms[ms.size() / 2]) / count;
  }

  std::size_t device_bytes() const override {
    std::size_t total = 0;
    for (const DeviceArray<R>* a :
         {&x0, &mass, &damping, &kr, &L0, &k, &kp, &ik, &xb[0], &xb[1], &vb[0], &vb[1]})
      total += a->n * sizeof(R);
    total += fixed.n + (load_slot.n + slice_begin.n + slice_width.n + other.n) * sizeof(int);
    return total;
  }
};

}  // namespace

Engine::Engine(const std::vector<const Model*>& models, const StepSettings& settings,
               const Options& options) {
  require(!models.empty(), "gpu::Engine: no model given");
  require(models.size() <= 65535, "gpu::Engine: a batch holds at most 65535 models (got ", models.size(),
          "); split it into several engines");
  for (std::size_t b = 0; b < models.size(); ++b) {
    require(models[b] != nullptr, "gpu::Engine: model ", b, " is null");
    require(models[b]->finalized, models[b]->name,
            ": model is not finalized (call finalize or ModelBuilder::build)");
    if (models[b]->bending.size() > 0)
      throw GpuError(cat("GPU: model '", models[b]->name, "' has bending terms (", models[b]->bending.size(),
                         "), which the GPU path does not have; use ", kCpuAlternative));
    validate_step_settings(*models[b], settings);
  }
  if (settings.integrator != Integrator::SymplecticEuler)
    throw GpuError(cat("GPU: the ", to_string(settings.integrator),
                       " integrator is not ported to the GPU path (symplectic_euler is); use ",
                       kCpuAlternative));
  require(options.block >= 32 && options.block <= 1024 && options.block % 32 == 0,
          "gpu::Options::block: must be a multiple of 32 in 32..1024 (got ", options.block, ")");
  const DeviceInfo dev = require_device(options.device);
  if (options.precision == Precision::Double)
    impl_ = std::make_unique<Backend<double>>(models, settings, options, dev);
  else
    impl_ = std::make_unique<Backend<float>>(models, settings, options, dev);
}

Engine::~Engine() = default;

int Engine::batch() const {
  return static_cast<int>(impl_->models.size());
}
Index Engine::nodes() const {
  return impl_->models[0]->num_nodes();
}
const DeviceInfo& Engine::device() const {
  return impl_->device;
}
Precision Engine::precision() const {
  return impl_->precision;
}
void Engine::set_loads(int b, const std::vector<PointLoad>& loads) {
  impl_->set_loads(b, loads);
}
void Engine::upload(int b, const State& state) {
  impl_->upload(b, state);
}
StepStatus Engine::step() {
  return impl_->step();
}
MatX3 Engine::positions(int b) const {
  return impl_->fetch(b, false);
}
MatX3 Engine::velocities(int b) const {
  return impl_->fetch(b, true);
}
void Engine::request_positions() {
  impl_->request_positions();
}
bool Engine::poll_positions(int b, MatX3& out) {
  return impl_->poll_positions(b, out);
}
double Engine::time() const {
  return impl_->t;
}
double Engine::stiffening() const {
  return impl_->stiffening;
}
std::uint64_t Engine::frames() const {
  return impl_->frames;
}
std::uint64_t Engine::substeps() const {
  return impl_->substeps;
}
const Warnings& Engine::warnings() const {
  return impl_->warnings;
}
std::size_t Engine::device_bytes() const {
  return impl_->device_bytes();
}
double Engine::time_substeps(int count, int repeats) {
  return impl_->time_substeps(count, repeats);
}

}  // namespace medspring::gpu
