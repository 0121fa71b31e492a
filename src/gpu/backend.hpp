// The GPU engine's backend (private to src/gpu): device arrays of a batch of models and its frame loop,
// one instantiation per precision. backend.cpp: construction, loads, state transfers, asynchronous
// readback; frame.cpp: the frame loop (the CPU engine's substep rule, guard and rollbacks), CUDA graphs,
// the substep timing. The kernels are in kernels.cu.
#pragma once

#include <cuda_runtime_api.h>

#include <climits>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "device.hpp"
#include "launch.hpp"
#include "medspring/gpu/engine.hpp"
#include "medspring/physics/spring_table.hpp"
#include "sample.hpp"

namespace medspring::gpu {

struct Engine::Impl {
  virtual ~Impl() = default;
  DeviceInfo device;
  Precision precision = Precision::Double;
  std::vector<const Model*> models;
  StepSettings settings;
  Options options;
  Options::Kernel kernel = Options::Kernel::Grid;
  double t = 0;
  std::vector<double> stiffening;             // per model: max kappa/k at its last stiffening evaluation
  std::uint64_t frames = 0, substeps = 0;     // substeps: the batch's (per frame the most any model took)
  std::vector<std::uint64_t> model_substeps;  // per model, as its CPU run counts them
  Warnings warnings;
  PackReport pack;        // Options::packed_table: what pack_spring_table found (fits: packed)
  std::string pack_note;  // why a requested packed table was not used ("" otherwise)

  virtual void set_loads(int b, const std::vector<PointLoad>& loads) = 0;
  virtual void upload(int b, const State& st) = 0;
  virtual StepStatus step() = 0;
  virtual MatX3 fetch(int b, bool velocities) = 0;
  virtual void request_positions() = 0;
  virtual bool poll_positions(int b, MatX3& out) = 0;
  virtual void request_node(int b, Index node) = 0;
  virtual bool poll_node(Vec3& out) = 0;
  virtual Engine::DeviceState device_state() = 0;
  virtual std::size_t device_bytes() const = 0;
  virtual double time_substeps(int count, int repeats) = 0;
  // The device-side trace reduction (traces.cpp, sample.cu).
  virtual void set_trace_probes(const std::vector<TraceProbe>& probes) = 0;
  virtual int trace_width() const = 0;
  virtual void request_traces() = 0;
  virtual void traces(std::vector<double>& out) = 0;
};

namespace detail {

template <class R>
struct Backend final : Engine::Impl {
  int B = 1;
  Index n = 0;
  std::size_t entries = 0;
  bool soft = false;
  bool per_block = false;  // Options::Kernel::PerBlock (kernel_for): one block per model
  int block_threads = 0;   // its block size
  cudaStream_t stream = nullptr, copy_stream = nullptr;

  // Model arrays (node arrays and spring parameters per model, topology shared). param_models: how many
  // copies of the node parameters and of the spring parameters are stored (1: shared by the batch).
  int param_models[2]{1, 1};
  DeviceArray<R> x0, mass, damping, kr, L0, k, kp, ik;
  // Options::compact_params (shared parameters only): 2-byte classes instead of k, kp, ik (mass,
  // damping, kr), which are then left unallocated.
  DeviceArray<unsigned short> spring_cls, node_cls;
  DeviceArray<R> ck, ckp, cik, cmass, cdamping, ckr;
  // Options::packed_table (shared table only, where it fits): one word per entry (offset, class) and the
  // classes' (L0, k, k', 1/k) in cL0, ck, ckp, cik; other, L0, k, kp, ik then unallocated.
  DeviceArray<unsigned> packed;
  DeviceArray<R> cL0;
  DeviceArray<unsigned char> fixed;
  DeviceArray<int> load_slot, row_node, slice_begin, slice_width, other;
  // The block kernel's split rows (hd::SplitRows): chunk slot per row, split nodes, their slots.
  DeviceArray<int> part, heavy_node, part_begin;
  int split_rows = 0, split_heavy = 0, parts = 0;
  // The grid kernel's split rows (hd::GridSplit; part, heavy_node, part_begin shared with the above):
  // lead row flags and the chunks' force sums (parts per model).
  DeviceArray<int> lead;
  DeviceArray<R> grid_parts;
  int grid_rows = 0;
  // Positions on the device are x - origin (model b's at 3 b): fp32, the rest shape's centre; fp64, 0.
  std::vector<double> origin;
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
  // Each model's substeps and step in the current batch of substeps (SubstepArgs::count_model, h_model),
  // and the host's per-model frame loop state.
  PinnedArray<R> h_host;
  PinnedArray<int> count_host;
  DeviceArray<R> h_dev;
  DeviceArray<int> count_dev;
  std::vector<long> left_m, frame_m;
  std::vector<double> h_m, tt_m;
  // Frame scalars.
  detail::FrameScalars scalars_init{INT_MAX, 0};
  PinnedArray<detail::FrameScalars> scalars_host_init, scalars_host;
  DeviceArray<detail::FrameScalars> scalars_dev;
  DeviceArray<unsigned long long> stiff_dev;
  PinnedArray<unsigned long long> stiff_host;
  // Graphs per (2 x substeps + whether every model takes them all, parity of cur).
  std::map<std::pair<long, int>, cudaGraphExec_t> graphs;
  // Asynchronous readback: device staging + pinned host snapshots, double-buffered.
  DeviceArray<R> staging[2];
  PinnedArray<R> snapshot[2];
  cudaEvent_t staged[2]{}, copied[2]{};
  std::uint64_t snap_seq[2]{0, 0}, next_seq = 1;
  std::vector<std::uint64_t> seen;
  bool requested[2]{false, false};
  int next_snap = 0;
  // The haptic read of one node: 3 reals per request, double-buffered the same way.
  DeviceArray<R> node_staging;  // 2 x 3
  PinnedArray<R> node_host;     // 2 x 3
  cudaEvent_t node_staged[2]{}, node_copied[2]{};
  std::uint64_t node_seq[2]{0, 0}, node_seen = 0;
  bool node_requested[2]{false, false};
  int node_model[2]{0, 0};
  int node_next = 0;

  Backend(const std::vector<const Model*>& ms, const StepSettings& s, const Options& o,
          const DeviceInfo& dev);
  ~Backend() override;
  void clear_graphs();
  std::size_t row_count(long subs) const;
  void ensure_capacity(long subs);
  void set_loads(int b, const std::vector<PointLoad>& L) override;
  void upload(int b, const State& st) override;
  detail::SubstepArgs<R> args(int parity, long kk, R h, bool stiff);
  // Enqueues a batch of `launches` substeps from the current buffers, model b taking count_host[b] of
  // them with step h_host[b] (no host work, capturable); uniform: every model takes all of them.
  void enqueue(long launches, bool uniform, int rollbacks);
  void run_batch(long launches, bool uniform, int rollbacks);
  // The block kernel's arguments for `count` substeps from buffer `parity` (into the other buffer).
  detail::BlockArgs<R> block_args(int parity, int count, R h, int stiff_mode, bool guard);
  StepStatus step() override;
  MatX3 fetch(int b, bool velocities) override;
  void request_positions() override;
  bool poll_positions(int b, MatX3& out) override;
  void request_node(int b, Index node) override;
  bool poll_node(Vec3& out) override;
  Engine::DeviceState device_state() override;
  double time_substeps(int count, int repeats) override;
  std::size_t device_bytes() const override;
  // The trace reduction (traces.cpp): its table, output and readback.
  TraceBuffers trace;
  void set_trace_probes(const std::vector<TraceProbe>& probes) override;
  int trace_width() const override { return trace.table.batch > 0 ? trace.table.width() : 0; }
  void request_traces() override;
  void traces(std::vector<double>& out) override;
};

extern template struct Backend<double>;
extern template struct Backend<float>;

}  // namespace detail
}  // namespace medspring::gpu
