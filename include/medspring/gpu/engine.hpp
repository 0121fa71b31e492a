// The CUDA backend (docs/gpu.md): spring networks stepped on an NVIDIA GPU with the CPU engine's physics
// (physics/kernels.hpp), its substep rule and its guard. Built only with MEDSPRING_CUDA (library
// MedSpring::gpu); `medspring::gpu::built()` and the apps tell a build without it.
//
//   gpu::Engine e({&model}, {.dt = 0.5});            // fp64, state on the device, x = x0
//   e.set_loads(0, {{.node = 223, .force = {0, 0, -1}}});
//   for (int f = 0; f < 1000; ++f) e.step();         // one frame each, substeps as step()
//   MatX3 x = e.positions(0);                        // synchronous copy back
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "medspring/core/error.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/physics/spring_table.hpp"
#include "medspring/physics/state.hpp"
#include "medspring/physics/trace_table.hpp"

namespace medspring::gpu {

/// A GPU-side failure: no device, a driver older than the runtime, out of device memory, a model
/// feature the GPU path lacks. what() names the cause and the CPU alternative.
class GpuError : public Error {
 public:
  using Error::Error;
};

enum class Precision { Double, Float };
Precision parse_precision(const std::string& text);  // "fp64" | "double" | "fp32" | "float"
std::string to_string(Precision p);

struct DeviceInfo {
  int index = 0;
  std::string name;  // e.g. "NVIDIA H100 80GB HBM3"
  int major = 0, minor = 0;
  int multiprocessors = 0;
  std::size_t memory_bytes = 0;
  std::size_t shared_per_block = 0;  // shared memory one block may use (opt-in limit; 227 KiB on an H100)
  int driver_version = 0, runtime_version = 0;  // e.g. 13000
};

/// True when this build has the CUDA backend (MEDSPRING_CUDA). Always callable.
bool built();

/// The device `index`, or GpuError: a build without CUDA, no device / no driver, a driver older than the
/// runtime, a device below compute capability 9.0 (the kernels are built for sm_90).
DeviceInfo require_device(int index = 0);

/// GpuError naming the feature and the CPU alternative when a model of this kind (Body::kind(): "surface",
/// "hybrid" run; "smrm", "tree" do not) or these options cannot run on the GPU path.
void require_supported(const std::string& body_kind, bool local_overlay = false, bool tools = false);

struct Options {
  Precision precision = Precision::Double;
  int device = 0;
  /// Replay each frame as a CUDA graph (memset, load upload, substep kernels, readback of the frame's
  /// scalars): removes the launch gaps of small models. Captured once per substep count.
  bool graphs = true;
  int block = 256;  // threads per block of the grid kernel
  /// Grid: one thread per node, one launch per substep (large models). PerBlock: one thread block per
  /// model, a frame's substeps in one launch with the model's positions and velocities in shared memory
  /// (on request). Auto: kernel_for() below (the grid kernel).
  enum class Kernel { Auto, Grid, PerBlock };
  Kernel kernel = Kernel::Auto;
  /// Compact parameters (docs/gpu.md): where the batch shares its parameters and they take at most
  /// compact_max_classes distinct values (a uniform tube: 8 spring classes, 1 node class; the real kidney:
  /// a class per stiffness), a 2-byte class per spring end and node instead of three reals each -- fewer
  /// bytes per substep, the same values, so the same results bit for bit (SpringTable.Compact*,
  /// GpuCompact.*). Measured on an H100 (bench --gpu --compact): 1M-node tube fp64 118.9 against 130.0 µs
  /// per substep, 16M 1,838 against 1,938 µs, 8,448 real kidneys 415 against 441 µs; fp32 the same within
  /// 1 %; the 1,200-node tube 6.56 against 6.21 µs (one more dependent load), won back by the gather batch.
  bool compact_params = true;
  /// The most distinct (k, k', 1/k) triples (and node triples) compact parameters take; more keep the
  /// per-entry arrays. 65,536: a 2-byte class, so that a real mesh's table becomes a per-spring table.
  int compact_max_classes = 65536;
  /// Spring-table entries each thread of the grid kernel gathers at a time (1, 2 or 4; 0: automatic):
  /// their other ends' positions and parameters are loaded before any force is formed
  /// (hd::gather_spring_forces), so that more loads are in flight; the same terms summed in the same
  /// order for every value. Automatic: 2 where the launch is one wave (rows x models <= 1,024 per
  /// multiprocessor: latency-bound, measured 1.2k tube 5.29 against 6.56 µs, one kidney 11.8 against
  /// 13.5 µs), 1 otherwise (more registers cost occupancy: 1M tube 139.8 against 118.9 µs).
  int gather_batch = 0;
  /// The grid kernel's block order for a batch: RowsFirst (default) launches a model's row blocks side
  /// by side; ModelsFirst the same rows of consecutive models side by side, so that co-resident blocks
  /// share the table in L1 -- measured slower (8,448 kidneys fp64 568 against 441 µs: each model's
  /// positions are fetched once per row block, far apart in time). The same arithmetic either way.
  enum class BatchOrder { RowsFirst, ModelsFirst };
  BatchOrder batch_order = BatchOrder::RowsFirst;
  /// Models per thread of the grid kernel for a batch (0 or 1: one model per thread, as before; 2 or 4):
  /// thread r takes row r of M consecutive models and loads each spring-table entry (other end, rest
  /// length, parameters or class) once for them (hd::node_substep_models): the table's traffic divided
  /// by M, M position gathers in flight per entry (gather_batch is then not used). The same arithmetic
  /// per model (physics_tests HdModels.*: bit for bit). Needs a batch that shares its spring parameters
  /// (copies of one model with their own loads; node parameters may differ) and the grid kernel:
  /// GpuError otherwise. Measured slower (8,448 real kidneys, H200 fp64: M = 2 477 µs, M = 4 793, against
  /// 414 per substep: the shared table stays in L2, and M models' registers cost occupancy): off.
  int models_per_thread = 0;
  /// Packed spring table (docs/gpu.md, "Packed table"; pack_spring_table): each table entry one 32-bit
  /// word -- the other end's offset from its row's node and a class of (L0, k, k', 1/k) -- instead of
  /// 4 + 2 + sizeof(R) bytes (compact) or 4 + 4 sizeof(R): the grid kernel reads 4 bytes per entry and
  /// the classes from L1; the same values, so the same results (physics_tests PackedTable.*). Where the
  /// batch shares its springs and the table fits (2^16 classes at most, offsets in the other bits);
  /// otherwise the unpacked table runs and pack_report() says why. Grid kernel only, not with
  /// models_per_thread > 1 (GpuError). Measured (H100, docs/gpu-measurements.md): faster beyond one wave
  /// (1M-node tube fp64 86.0 against 119.0 µs per substep, 16M 1,192 against 1,739, 8,448 real kidneys 388
  /// against 418), slower in one wave (1,200-node tube 5.66 against 5.40): off by default; turn it on for
  /// models beyond about 10^5 nodes or large batches.
  bool packed_table = false;
};

/// The kernel a batch of `batch` models of `nodes` nodes runs on `device` (docs/gpu.md): PerBlock when
/// the option asks for it (GpuError when one model's state, 9 n reals, does not fit in the shared memory
/// of one block), otherwise Grid -- Auto included: the grid kernel was measured faster on an H200 both for
/// one real kidney and for a batch of 8,448 (docs/gpu.md).
Options::Kernel kernel_for(const Options& options, int batch, Index nodes, const DeviceInfo& device);

/// B spring networks of the same topology (same nodes and spring ends; masses, damping, return springs,
/// stiffnesses, rest positions and loads may differ per model) stepped together, one launch per
/// substep. Every model takes its own substeps, as the CPU engine's step() takes them for it (the count
/// from its own stiffening and stable step, its loads at its own substep times), so each trajectory is
/// the one the CPU engine computes, to rounding; a model with fewer substeps than the batch's most idles
/// through the rest of the frame's launches. One exception: a guard trip in any model rolls back the
/// whole batch (every model halves its step for the rest of that frame). A model with
/// bending terms, or models of different topology, are refused (GpuError). The models must outlive the
/// engine (it keeps pointers for the stable-step rule).
class Engine {
 public:
  Engine(const std::vector<const Model*>& models, const StepSettings& settings, const Options& options = {});
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  int batch() const;
  Index nodes() const;
  Options::Kernel kernel() const;  // Grid or PerBlock (kernel_for)
  const DeviceInfo& device() const;
  Precision precision() const;
  const StepSettings& settings() const;

  /// Loads of model b, held until changed; evaluated at the start of every substep as step() does.
  void set_loads(int b, const std::vector<PointLoad>& loads);
  /// Positions, velocities and stiffening of model b from a CPU state (the time taken from model 0's).
  void upload(int b, const State& state);

  /// One frame of settings.dt for every model: the CPU engine's substep rule (from the stiffening of the
  /// previous frame), guard and rollbacks. Waits for the frame's scalars (a few bytes).
  StepStatus step();

  /// Synchronous copies of model b's positions / velocities.
  MatX3 positions(int b) const;
  MatX3 velocities(int b) const;

  /// Asynchronous readback of every model's positions into pinned, double-buffered host memory:
  /// request_positions() enqueues a copy of the current positions after the work issued so far;
  /// poll_positions(b, out) copies the newest finished snapshot of model b into out and returns true
  /// if one finished since the last poll (never blocks the GPU or waits for it).
  void request_positions();
  bool poll_positions(int b, MatX3& out);

  /// The haptic loop's read (docs/gpu.md): request_node() enqueues a copy of node `node` of model b's
  /// current position (3 reals, not the state) into pinned, double-buffered host memory after the work
  /// issued so far; poll_node(out) returns true with the newest finished one (never waits for the GPU).
  void request_node(int b, Index node);
  bool poll_node(Vec3& out);

  /// Device pointers of the current positions and velocities, (B, n, 3) row-major in the precision's
  /// type, after the work issued so far has finished (synchronizes the engine's stream). Valid until the
  /// next step(), upload() or time_substeps(): the engine alternates between two buffers. For zero-copy
  /// hand-over (DLPack) to CuPy / PyTorch.
  struct DeviceState {
    void* x = nullptr;
    void* v = nullptr;
    int batch = 0;
    Index nodes = 0;
    Precision precision = Precision::Double;
    int device = 0;
    /// The device positions are x - origin, model b's origin at origin[3 b .. 3 b + 2] (host memory, valid
    /// with the engine): 0 in fp64; in fp32 the centre of model b's rest shape, so that rounding scales
    /// with the model's size rather than its distance from the coordinate origin. Velocities are as is.
    const double* origin = nullptr;
  };
  DeviceState device_state();

  /// Device-side trace sampling (docs/gpu.md, "Study runs on the GPU"): set_trace_probes takes one
  /// TraceProbe per model (physics/trace_table.hpp: the surface as DOF rows with its rest positions, the
  /// traced points); request_traces() enqueues, after the work issued so far, the reduction of the current
  /// positions (hd::trace_sample per model: max |u| over the surface, |u| of each point) and the copy of
  /// its B x trace_width() doubles to pinned host memory; traces(out) waits for the last request's values.
  void set_trace_probes(const std::vector<TraceProbe>& probes);
  int trace_width() const;  // 1 + the most traced points of a model (0 before set_trace_probes)
  void request_traces();
  void traces(std::vector<double>& out);

  double time() const;             // ms
  double stiffening() const;       // max kappa/k over the batch at the models' last evaluations
  double stiffening(int b) const;  // model b's
  std::uint64_t frames() const;
  std::uint64_t substeps() const;       // the batch's launches: per frame the most substeps any model took
  std::uint64_t substeps(int b) const;  // model b's substeps (its CPU run's State::substeps)
  const Warnings& warnings() const;
  /// Options::packed_table: whether the table was packed (fits), its classes, class bits and largest
  /// offset; packed_table_note(): why a requested packed table was not used ("" when it was, or was not
  /// requested).
  PackReport pack_report() const;
  std::string packed_table_note() const;
  /// Device bytes of the model and state arrays (the payload of one substep is about this much).
  std::size_t device_bytes() const;

  /// Benchmark aid: median device time (µs) of one substep over `repeats` replays (events around each)
  /// of a CUDA graph of `count` substeps of dt / (the current substep count), without host work, the
  /// stiffening or the guard's readback; loads as at the current time. Advances every model's state by
  /// count x repeats substeps (count is rounded up to even) but not the clock.
  double time_substeps(int count = 100, int repeats = 20);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// Device-to-device copy bandwidth (GB/s, bytes read + written per second), median of `repeats`
/// copies of `bytes`: the ceiling a memory-bound kernel is compared with.
double measured_copy_bandwidth(std::size_t bytes = std::size_t(1) << 30, int repeats = 20, int device = 0);

}  // namespace medspring::gpu
