// The GPU engine's backend: construction (the spring table and node arrays of every model on the
// device), loads, state transfers and the asynchronous readback (docs/gpu.md).
#include "backend.hpp"

#include <cstring>

#include "medspring/core/check.hpp"

namespace medspring::gpu::detail {

namespace {

// Same topology: node count and spring ends.
void require_same_topology(const Model& a, const Model& b, int index) {
  const bool same =
      a.num_nodes() == b.num_nodes() && a.springs.i == b.springs.i && a.springs.j == b.springs.j;
  if (!same)
    throw GpuError(cat("gpu::Engine: model ", index, " ('", b.name, "') has another topology than model 0 ('",
                       a.name, "'): a batch needs the same nodes and spring ends; run it in its own Engine"));
}

}  // namespace

template <class R>
Backend<R>::Backend(const std::vector<const Model*>& ms, const StepSettings& s, const Options& o,
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
  // The kernel, and the table for it (load balance, docs/gpu.md): heavy rows split into chunks and all
  // rows dealt by size over the block's threads for one block per model (make_split_table); heavy rows
  // split over the lanes of one warp for the grid kernel (make_grid_split_table; without heavy rows
  // RowOrder::HeavyLast).
  kernel = kernel_for(o, B, n, dev);
  per_block = kernel == Options::Kernel::PerBlock;
  block_threads = std::min(kBlockThreads, std::max(32, (n + 31) / 32 * 32));
  SplitTableArrays<R> S0;
  if (per_block) {
    S0 = make_split_table<R>(m0, block_threads);
    const std::size_t bytes = block_shared_bytes<R>(n, S0.parts());
    if (bytes + 32 * sizeof(double) > dev.shared_per_block) {  // the chunks' slots did not fit after all
      if (o.kernel == Options::Kernel::PerBlock)
        throw GpuError(cat("GPU: one block per model needs ", bytes + 32 * sizeof(double),
                           " bytes of shared memory for '", m0.name, "'; the device allows ",
                           dev.shared_per_block, " per block: use the grid kernel (Auto)"));
      per_block = false;
      kernel = Options::Kernel::Grid;
    }
  }
  if (per_block) {
    parts = S0.parts();
    check(prepare_block_frame<R>(block_shared_bytes<R>(n, parts)),
          "allocating shared memory for the block kernel");
    split_rows = static_cast<int>(S0.part.size());
    split_heavy = static_cast<int>(S0.heavy_node.size());
    part.assign(S0.part, "allocating the spring table", "uploading the spring table");
    heavy_node.assign(S0.heavy_node, "allocating the spring table", "uploading the spring table");
    part_begin.assign(S0.part_begin, "allocating the spring table", "uploading the spring table");
  }
  // The grid kernel: heavy rows split over the lanes of one warp where the model has nodes of more than
  // kHeavyDegree springs (make_grid_split_table); otherwise one row per node, HeavyLast.
  GridSplitArrays<R> G0;
  if (!per_block) {
    G0 = make_grid_split_table<R>(m0);
    if (!G0.heavy_node.empty()) {
      grid_rows = G0.rows();
      parts = G0.parts();
      part.assign(G0.part, "allocating the spring table", "uploading the spring table");
      lead.assign(G0.lead, "allocating the spring table", "uploading the spring table");
      heavy_node.assign(G0.heavy_node, "allocating the spring table", "uploading the spring table");
      part_begin.assign(G0.part_begin, "allocating the spring table", "uploading the spring table");
      grid_parts.allocate(3 * static_cast<std::size_t>(parts) * uB, "allocating the split rows' sums");
    }
  }
  const bool grid_split = grid_rows > 0;
  auto table_of = [&](const Model& m) {
    if (per_block) return make_split_table<R>(m, block_threads).table;
    return grid_split ? make_grid_split_table<R>(m).table : make_spring_table<R>(m, RowOrder::HeavyLast);
  };
  // Topology from model 0, parameters from every model.
  SpringTableArrays<R> T0 =
      per_block ? std::move(S0.table) : (grid_split ? std::move(G0.table) : table_of(m0));
  entries = T0.entries();
  if (!T0.row_node.empty()) {
    row_node.assign(T0.row_node, "allocating the spring table", "uploading the spring table");
  }
  slice_begin.assign(T0.slice_begin, "allocating the spring table", "uploading the spring table");
  slice_width.assign(T0.slice_width, "allocating the spring table", "uploading the spring table");
  // Parameters shared by the batch: where every model's spring parameters (node arrays) equal model 0's
  // -- a batch of one model, or of copies of it with their own loads (the kidney batch of a dataset) --
  // they are stored once (stride 0) and read from L2 by every model, instead of B copies read from
  // device memory in every substep. The state and the load slots are always per model.
  auto node_arrays_of = [&](const Model& m, std::size_t ub) {
    NodeArrayData<R> N = make_node_arrays<R>(m);
    // fp32: positions relative to the rest shape's centre (origin), so that rounding scales with the
    // organ's size, not with its distance from the scanner's origin (the real kidney lies 250-356 mm
    // from it: an fp32 ulp of 3e-5 mm there). The physics is translation-invariant; fp64: origin 0.
    if constexpr (std::is_same_v<R, float>) {
      const Vec3 c = 0.5 * (m.x0.colwise().minCoeff() + m.x0.colwise().maxCoeff()).transpose();
      for (int d = 0; d < 3; ++d) origin[3 * ub + static_cast<std::size_t>(d)] = c[d];
      for (std::size_t q = 0; q < 3 * un; ++q)
        N.x0[q] = static_cast<R>(m.x0.data()[q] - c[static_cast<Index>(q % 3)]);
    }
    return N;
  };
  origin.assign(3 * uB, 0.0);
  const NodeArrayData<R> N0 = node_arrays_of(m0, 0);
  bool nodes_shared = true, table_shared = true;
  for (int b = 1; b < B; ++b) {
    const Model& m = *ms[static_cast<std::size_t>(b)];
    require_same_topology(m0, m, b);
    if (&m == &m0 || !(nodes_shared || table_shared)) continue;
    const SpringTableArrays<R> T = table_of(m);
    table_shared = table_shared && T.L0 == T0.L0 && T.k == T0.k && T.kp == T0.kp && T.ik == T0.ik;
    const NodeArrayData<R> N = node_arrays_of(m, static_cast<std::size_t>(b));
    nodes_shared = nodes_shared && N.x0 == N0.x0 && N.mass == N0.mass && N.damping == N0.damping &&
                   N.kr == N0.kr && N.fixed == N0.fixed;
  }
  param_models[0] = nodes_shared ? 1 : B;
  param_models[1] = table_shared ? 1 : B;
  if (o.packed_table) {  // packed entries (pack_spring_table): the grid kernel, one table for the batch
    if (per_block)
      throw GpuError(
          "gpu::Options::packed_table applies to the grid kernel; this batch runs one block per "
          "model: use kernel Grid (or Auto), or packed_table off");
    if (o.models_per_thread > 1)
      throw GpuError(cat("gpu::Options::packed_table is not combined with models_per_thread = ",
                         o.models_per_thread, " (yet): use one of them"));
    if (table_shared) {
      pack = pack_spring_table(T0);
      if (!pack.fits)  // the table is left as it is: the per-entry (or compact) path runs
        pack_note = cat("packed table: '", m0.name, "' does not fit (", pack.classes, " classes in ",
                        pack.class_bits, " bits, offsets up to ", pack.max_offset, " of at most ",
                        pack.offset_limit, "): the unpacked table runs");
    } else {
      pack_note = "packed table: the batch's models differ in their springs: the unpacked table runs";
    }
  }
  if (o.models_per_thread > 1) {  // several models per thread: one table for the batch, the grid kernel
    if (per_block)
      throw GpuError(cat("gpu::Options::models_per_thread = ", o.models_per_thread,
                         " applies to the grid kernel; this batch runs one block per model: use kernel Grid "
                         "(or Auto), or models_per_thread 1"));
    if (!table_shared)
      throw GpuError(cat("gpu::Options::models_per_thread = ", o.models_per_thread,
                         " needs a batch that shares its spring parameters (copies of one model with their "
                         "own loads); the models of this batch differ in rest lengths or stiffnesses: use "
                         "models_per_thread 1"));
  }
  const auto uBn = static_cast<std::size_t>(param_models[0]), uBt = static_cast<std::size_t>(param_models[1]);
  // Compact parameters (Options::compact_params, docs/gpu.md): shared parameters with few distinct
  // values are stored as a 2-byte class per entry (node) and the classes' values.
  bool compact_table = false, compact_nodes = false;
  if (pack.fits) {  // the packed words and their classes; no per-entry other, L0, k, k', 1/k
    packed.assign(T0.packed, "allocating the packed spring table", "uploading the packed spring table");
    cL0.assign(T0.cL0, "allocating the spring classes", "uploading the spring classes");
    ck.assign(T0.ck, "allocating the spring classes", "uploading the spring classes");
    ckp.assign(T0.ckp, "allocating the spring classes", "uploading the spring classes");
    cik.assign(T0.cik, "allocating the spring classes", "uploading the spring classes");
  } else {
    other.allocate(entries, "allocating the spring table");
    other.upload(T0.other.data(), entries, 0, "uploading the spring table");
  }
  if (o.compact_params && table_shared && !pack.fits) {
    SpringTableArrays<R> Tc;
    Tc.k = T0.k;
    Tc.kp = T0.kp;
    Tc.ik = T0.ik;
    if ((compact_table = compact_spring_params(Tc, o.compact_max_classes))) {
      spring_cls.assign(Tc.cls, "allocating the spring classes", "uploading the spring classes");
      ck.assign(Tc.ck, "allocating the spring classes", "uploading the spring classes");
      ckp.assign(Tc.ckp, "allocating the spring classes", "uploading the spring classes");
      cik.assign(Tc.cik, "allocating the spring classes", "uploading the spring classes");
    }
  }
  if (o.compact_params && nodes_shared) {
    NodeArrayData<R> Nc;
    Nc.mass = N0.mass;
    Nc.damping = N0.damping;
    Nc.kr = N0.kr;
    if ((compact_nodes = compact_node_params(Nc, o.compact_max_classes))) {
      node_cls.assign(Nc.cls, "allocating the node classes", "uploading the node classes");
      cmass.assign(Nc.cmass, "allocating the node classes", "uploading the node classes");
      cdamping.assign(Nc.cdamping, "allocating the node classes", "uploading the node classes");
      ckr.assign(Nc.ckr, "allocating the node classes", "uploading the node classes");
    }
  }
  if (!pack.fits) L0.allocate(entries * uBt, "allocating the spring table");
  if (!compact_table && !pack.fits)
    for (DeviceArray<R>* a : {&k, &kp, &ik}) a->allocate(entries * uBt, "allocating the spring table");
  if (!compact_nodes)
    for (DeviceArray<R>* a : {&mass, &damping, &kr}) a->allocate(un * uBn, "allocating the node arrays");
  x0.allocate(3 * un * uBn, "allocating the node arrays");
  fixed.allocate(un * uBn, "allocating the node arrays");
  load_slot.allocate(un * uB, "allocating the node arrays");
  for (int p = 0; p < 2; ++p) {
    xb[p].allocate(3 * un * uB, "allocating the state");
    vb[p].allocate(3 * un * uB, "allocating the state");
  }
  std::vector<R> zero(3 * un, R(0));
  for (int b = 0; b < B; ++b) {
    const Model& m = *ms[static_cast<std::size_t>(b)];
    soft = soft || m.has_soft_springs;
    const bool same = b == 0 || &m == &m0;
    const auto ub = static_cast<std::size_t>(b);
    if (ub < uBt && !pack.fits) {
      const SpringTableArrays<R> T = same ? SpringTableArrays<R>{} : table_of(m);
      const SpringTableArrays<R>& Tb = same ? T0 : T;
      L0.upload(Tb.L0.data(), entries, ub * entries, "uploading the spring table");
      if (!compact_table) {
        k.upload(Tb.k.data(), entries, ub * entries, "uploading the spring table");
        kp.upload(Tb.kp.data(), entries, ub * entries, "uploading the spring table");
        ik.upload(Tb.ik.data(), entries, ub * entries, "uploading the spring table");
      }
    }
    const NodeArrayData<R> N = same ? NodeArrayData<R>{} : node_arrays_of(m, ub);
    const NodeArrayData<R>& Nb = same ? N0 : N;
    if (same)
      std::copy(origin.begin(), origin.begin() + 3, origin.begin() + 3 * static_cast<std::ptrdiff_t>(ub));
    if (ub < uBn) {
      x0.upload(Nb.x0.data(), 3 * un, ub * 3 * un, "uploading the node arrays");
      if (!compact_nodes) {
        mass.upload(Nb.mass.data(), un, ub * un, "uploading the node arrays");
        damping.upload(Nb.damping.data(), un, ub * un, "uploading the node arrays");
        kr.upload(Nb.kr.data(), un, ub * un, "uploading the node arrays");
      }
      fixed.upload(Nb.fixed.data(), un, ub * un, "uploading the node arrays");
    }
    load_slot.upload(Nb.load_slot.data(), un, ub * un, "uploading the node arrays");
    for (int p = 0; p < 2; ++p) {
      xb[p].upload(Nb.x0.data(), 3 * un, ub * 3 * un, "uploading the state");
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
  stiffening.assign(uB, 1.0);
  model_substeps.assign(uB, 0);
  h_host.allocate(uB, "allocating pinned memory");
  count_host.allocate(uB, "allocating pinned memory");
  h_dev.allocate(uB, "allocating the per-model steps");
  count_dev.allocate(uB, "allocating the per-model substep counts");
}

template <class R>
Backend<R>::~Backend() {
  clear_graphs();
  if (stream) cudaStreamSynchronize(stream);
  if (copy_stream) cudaStreamSynchronize(copy_stream);
  for (int w = 0; w < 2; ++w) {
    for (cudaEvent_t e : {staged[w], copied[w], node_staged[w], node_copied[w]})
      if (e) cudaEventDestroy(e);
  }
  if (stream) cudaStreamDestroy(stream);
  if (copy_stream) cudaStreamDestroy(copy_stream);
}

template <class R>
void Backend<R>::clear_graphs() {
  for (auto& g : graphs) cudaGraphExecDestroy(g.second);
  graphs.clear();
}

template <class R>
std::size_t Backend<R>::row_count(long subs) const {
  return static_cast<std::size_t>(subs) * static_cast<std::size_t>(B) * 3 * static_cast<std::size_t>(rows);
}

template <class R>
void Backend<R>::ensure_capacity(long subs) {
  if (subs <= capacity) return;
  check(cudaStreamSynchronize(stream), "finishing the work in flight");
  clear_graphs();
  capacity = std::max(subs, 2 * capacity);
  rows_host.allocate(row_count(capacity), "allocating pinned memory for the load table");
  rows_dev.allocate(row_count(capacity), "allocating the load table");
  const auto slots_needed = static_cast<std::size_t>(capacity) * static_cast<std::size_t>(B);
  stiff_dev.allocate(slots_needed, "allocating the stiffening slots");
  stiff_host.allocate(slots_needed, "allocating pinned memory");
}

template <class R>
void Backend<R>::set_loads(int b, const std::vector<PointLoad>& L) {
  require(b >= 0 && b < B, "gpu::Engine::set_loads: model ", b, " out of range (batch of ", B, ")");
  LoadSlots S = make_load_slots(L, n);
  const auto ub = static_cast<std::size_t>(b);
  if (S.nodes == slots[ub].nodes) {  // the same loaded nodes (a haptic tick): only the forces change,
    loads[ub] = L;                   // which the host's load table of the next frame picks up
    return;
  }
  check(cudaStreamSynchronize(stream), "finishing the work in flight");
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

template <class R>
void Backend<R>::upload(int b, const State& st) {
  require(b >= 0 && b < B, "gpu::Engine::upload: model ", b, " out of range (batch of ", B, ")");
  require(st.x.rows() == n && st.v.rows() == n, "gpu::Engine::upload: state of ", st.x.rows(),
          " nodes for a model of ", n);
  check(cudaStreamSynchronize(stream), "finishing the work in flight");
  std::vector<R> h(3 * static_cast<std::size_t>(n));
  const auto off = static_cast<std::size_t>(b) * h.size();
  const double* o = origin.data() + 3 * static_cast<std::size_t>(b);
  for (std::size_t q = 0; q < h.size(); ++q) h[q] = static_cast<R>(st.x.data()[q] - o[q % 3]);
  xb[cur].upload(h.data(), h.size(), off, "uploading the state");
  for (std::size_t q = 0; q < h.size(); ++q) h[q] = static_cast<R>(st.v.data()[q]);
  vb[cur].upload(h.data(), h.size(), off, "uploading the state");
  if (b == 0) t = st.t;
  stiffening[static_cast<std::size_t>(b)] = st.stiffening;
}

template <class R>
MatX3 Backend<R>::fetch(int b, bool velocities) {
  require(b >= 0 && b < B, "gpu::Engine: model ", b, " out of range (batch of ", B, ")");
  check(cudaStreamSynchronize(stream), "finishing the work in flight");
  std::vector<R> h(3 * static_cast<std::size_t>(n));
  const DeviceArray<R>& src = velocities ? vb[cur] : xb[cur];
  check(cudaMemcpy(h.data(), src.p + static_cast<std::size_t>(b) * h.size(), h.size() * sizeof(R),
                   cudaMemcpyDeviceToHost),
        "copying the state back");
  MatX3 out(n, 3);
  const double* o = origin.data() + 3 * static_cast<std::size_t>(b);
  for (std::size_t q = 0; q < h.size(); ++q)
    out.data()[q] = static_cast<double>(h[q]) + (velocities ? 0.0 : o[q % 3]);
  return out;
}

template <class R>
void Backend<R>::request_positions() {
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
  check(cudaMemcpyAsync(snapshot[w].p, staging[w].p, count * sizeof(R), cudaMemcpyDeviceToHost, copy_stream),
        "reading back the positions");
  check(cudaEventRecord(copied[w], copy_stream), "ordering the readback");
  requested[w] = true;
  snap_seq[w] = next_seq++;
  next_snap = 1 - w;
}

template <class R>
bool Backend<R>::poll_positions(int b, MatX3& out) {
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
  const double* o = origin.data() + 3 * static_cast<std::size_t>(b);
  for (Index q = 0; q < 3 * n; ++q) out.data()[q] = static_cast<double>(src[q]) + o[q % 3];
  seen[static_cast<std::size_t>(b)] = snap_seq[best];
  return true;
}

template <class R>
void Backend<R>::request_node(int b, Index node) {
  require(b >= 0 && b < B, "gpu::Engine::request_node: model ", b, " out of range (batch of ", B, ")");
  require(node >= 0 && node < n, "gpu::Engine::request_node: node ", node, " out of range (", n, " nodes)");
  if (!node_staging.p) {
    node_staging.allocate(6, "allocating the node readback");
    node_host.allocate(6, "allocating pinned memory for the node readback");
    for (int w = 0; w < 2; ++w) {
      check(cudaEventCreateWithFlags(&node_staged[w], cudaEventDisableTiming), "creating an event");
      check(cudaEventCreateWithFlags(&node_copied[w], cudaEventDisableTiming), "creating an event");
    }
  }
  const int w = node_next;
  // As request_positions, for 3 reals: staged on the compute stream (ordered after the substeps issued
  // so far, before the buffer is written again), copied to pinned memory on the copy stream.
  if (node_requested[w]) check(cudaStreamWaitEvent(stream, node_copied[w], 0), "ordering the node readback");
  const std::size_t at =
      (static_cast<std::size_t>(b) * static_cast<std::size_t>(n) + static_cast<std::size_t>(node)) * 3;
  check(cudaMemcpyAsync(node_staging.p + 3 * w, xb[cur].p + at, 3 * sizeof(R), cudaMemcpyDeviceToDevice,
                        stream),
        "staging the node readback");
  check(cudaEventRecord(node_staged[w], stream), "ordering the node readback");
  check(cudaStreamWaitEvent(copy_stream, node_staged[w], 0), "ordering the node readback");
  check(cudaMemcpyAsync(node_host.p + 3 * w, node_staging.p + 3 * w, 3 * sizeof(R), cudaMemcpyDeviceToHost,
                        copy_stream),
        "reading back the node");
  check(cudaEventRecord(node_copied[w], copy_stream), "ordering the node readback");
  node_requested[w] = true;
  node_model[w] = b;
  node_seq[w] = next_seq++;
  node_next = 1 - w;
}

template <class R>
bool Backend<R>::poll_node(Vec3& out) {
  int best = -1;
  for (int w = 0; w < 2; ++w) {
    if (!node_requested[w] || node_seq[w] <= node_seen) continue;
    const cudaError_t e = cudaEventQuery(node_copied[w]);
    if (e == cudaErrorNotReady) continue;
    check(e, "reading back the node");
    if (best < 0 || node_seq[w] > node_seq[best]) best = w;
  }
  if (best < 0) return false;
  const R* p = node_host.p + 3 * best;
  const double* o = origin.data() + 3 * static_cast<std::size_t>(node_model[best]);
  out = Vec3(static_cast<double>(p[0]) + o[0], static_cast<double>(p[1]) + o[1],
             static_cast<double>(p[2]) + o[2]);
  node_seen = node_seq[best];
  return true;
}

template <class R>
Engine::DeviceState Backend<R>::device_state() {
  check(cudaStreamSynchronize(stream), "finishing the work in flight");
  Engine::DeviceState d;
  d.x = xb[cur].p;
  d.v = vb[cur].p;
  d.batch = B;
  d.nodes = n;
  d.precision = precision;
  d.device = device.index;
  d.origin = origin.data();
  return d;
}

template <class R>
std::size_t Backend<R>::device_bytes() const {
  std::size_t total = 0;
  for (const DeviceArray<R>* a :
       {&x0,  &mass, &damping, &kr,       &L0,  &k,     &kp,    &ik,    &ck,    &ckp,
        &cik, &cL0,  &cmass,   &cdamping, &ckr, &xb[0], &xb[1], &vb[0], &vb[1], &grid_parts})
    total += a->n * sizeof(R);
  total += (spring_cls.n + node_cls.n) * sizeof(unsigned short) + packed.n * sizeof(unsigned);
  total += fixed.n + (load_slot.n + row_node.n + slice_begin.n + slice_width.n + other.n + part.n +
                      heavy_node.n + part_begin.n + lead.n) *
                         sizeof(int);
  return total;
}

template struct Backend<double>;
template struct Backend<float>;

}  // namespace medspring::gpu::detail
