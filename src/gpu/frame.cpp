// The GPU engine's frame loop: the CPU engine's substep rule (physics/stability.hpp), guard and rollbacks,
// the load table of a batch of substeps, CUDA graphs, and the substep timing (docs/gpu.md).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "backend.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/stability.hpp"

namespace medspring::gpu::detail {

template <class R>
detail::SubstepArgs<R> Backend<R>::args(int parity, long kk, R h, bool stiff) {
  detail::SubstepArgs<R> A;
  A.nodes = {static_cast<int>(n), x0.p, mass.p, damping.p, kr.p, fixed.p, load_slot.p};
  A.table = {static_cast<int>(n), row_node.p, slice_begin.p, slice_width.p, other.p, L0.p, k.p, kp.p, ik.p};
  if (spring_cls.p) {  // compact parameters (shared: entry_stride 0)
    A.table.cls = spring_cls.p;
    A.table.ck = ck.p;
    A.table.ckp = ckp.p;
    A.table.cik = cik.p;
  }
  if (packed.p) {  // packed entries (shared: entry_stride 0)
    A.table.other = nullptr;
    A.table.packed = packed.p;
    A.table.class_bits = pack.class_bits;
    A.table.cL0 = cL0.p;
    A.table.ck = ck.p;
    A.table.ckp = ckp.p;
    A.table.cik = cik.p;
  }
  if (node_cls.p) {
    A.nodes.cls = node_cls.p;
    A.nodes.cmass = cmass.p;
    A.nodes.cdamping = cdamping.p;
    A.nodes.ckr = ckr.p;
  }
  A.node_stride = param_models[0] > 1 ? n : 0;  // 0: the batch shares model 0's parameters
  A.slot_stride = n;
  A.entry_stride = param_models[1] > 1 ? static_cast<long long>(entries) : 0;
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
  A.h_model = h_dev.p;
  A.count_model = count_dev.p;
  A.vmax2 = static_cast<R>(settings.v_max * settings.v_max);
  A.substep = static_cast<int>(kk);
  A.soft = soft;
  A.stiff = stiff;
  A.guard = settings.guard;
  const long long table_rows = grid_rows > 0 ? grid_rows : static_cast<long long>(n);
  // Automatic gather batch (Options::gather_batch): 2 where the launch is one wave (latency-bound), else 1.
  const long long wave = 1024ll * std::max(1, device.multiprocessors);
  A.gather = options.gather_batch > 0 ? options.gather_batch : table_rows * B <= wave ? 2 : 1;
  // gridDim.y is at most 65,535 row blocks (16.7M rows of 256): larger models keep rows on x.
  A.models_first = B > 1 && options.batch_order == Options::BatchOrder::ModelsFirst &&
                   (table_rows + options.block - 1) / options.block <= 65535;
  A.models_per_thread = options.models_per_thread > 1 ? options.models_per_thread : 1;
  A.stiff_bits = stiff_dev.p + (stiff ? kk * B : 0);
  A.scalars = scalars_dev.p;
  if (grid_rows > 0) {
    A.split = {grid_rows, part.p, lead.p, part_begin.p, heavy_node.p};
    A.parts = grid_parts.p;
    A.parts_stride = 3ll * parts;
  }
  return A;
}

template <class R>
detail::BlockArgs<R> Backend<R>::block_args(int parity, int count, R h, int stiff_mode, bool guard) {
  detail::BlockArgs<R> A;
  A.s = args(parity, 0, h, stiff_mode != 0);
  A.s.guard = guard;
  A.s.stiff_bits = stiff_dev.p;
  A.load_substep_stride = static_cast<long long>(B) * 3 * rows;
  A.count = count;
  A.stiff_mode = stiff_mode;
  A.threads = block_threads;
  A.split = {split_rows, part.p, split_heavy, heavy_node.p, part_begin.p};
  A.parts = parts;
  return A;
}

// Enqueues a batch of `launches` substeps from the current buffers, model b taking count_host[b] of them
// with step h_host[b] (no host work, capturable). The grid kernel: one launch per substep, ping-pong
// between the buffers (a model past its count carries its state over); the block kernel: one launch,
// into the other buffer. The stiffening is evaluated in each model's last substep: with every model
// taking all the launches only the last launch evaluates it, otherwise every launch does (slot kk, b).
template <class R>
void Backend<R>::enqueue(long launches, bool uniform, int rollbacks) {
  const auto uB = static_cast<std::size_t>(B);
  check(cudaMemcpyAsync(scalars_dev.p, scalars_host_init.p, sizeof(detail::FrameScalars),
                        cudaMemcpyHostToDevice, stream),
        "resetting the frame scalars");
  check(cudaMemsetAsync(stiff_dev.p, 0, static_cast<std::size_t>(launches) * uB * sizeof(unsigned long long),
                        stream),
        "resetting the stiffening slots");
  check(cudaMemcpyAsync(rows_dev.p, rows_host.p, row_count(launches) * sizeof(R), cudaMemcpyHostToDevice,
                        stream),
        "uploading the load table");
  check(cudaMemcpyAsync(h_dev.p, h_host.p, uB * sizeof(R), cudaMemcpyHostToDevice, stream),
        "uploading the models' steps");
  check(cudaMemcpyAsync(count_dev.p, count_host.p, uB * sizeof(int), cudaMemcpyHostToDevice, stream),
        "uploading the models' substep counts");
  const bool every = rollbacks == settings.max_rollbacks;
  if (per_block) {
    check(detail::launch_block_frame(
              block_args(cur, static_cast<int>(launches), R(0), every ? 2 : 1, settings.guard), stream),
          "launching the block kernel");
  } else {
    for (long kk = 0; kk < launches; ++kk) {
      const bool stiff = every || !uniform || kk == launches - 1;
      check(detail::launch_substep(args(cur, kk, R(0), stiff), options.block, stream),
            "launching the substep kernel");
    }
  }
  check(cudaMemcpyAsync(scalars_host.p, scalars_dev.p, sizeof(detail::FrameScalars), cudaMemcpyDeviceToHost,
                        stream),
        "reading the frame scalars");
  check(cudaMemcpyAsync(stiff_host.p, stiff_dev.p,
                        static_cast<std::size_t>(launches) * uB * sizeof(unsigned long long),
                        cudaMemcpyDeviceToHost, stream),
        "reading the stiffening");
}

template <class R>
void Backend<R>::run_batch(long launches, bool uniform, int rollbacks) {
  const bool graph = options.graphs && rollbacks == 0 && launches <= 64;
  if (!graph) {
    enqueue(launches, uniform, rollbacks);
    return;
  }
  const auto key = std::make_pair(2 * launches + (uniform ? 1 : 0), cur);
  auto it = graphs.find(key);
  if (it == graphs.end()) {
    cudaGraph_t g = nullptr;
    check(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal), "capturing a CUDA graph");
    try {
      enqueue(launches, uniform, rollbacks);
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

// One frame. Every model takes its own substeps, as its CPU run (step()) takes them: the count from its
// own stiffening of the previous frame and dt_safe, loads at its own substep times. A guard trip in any
// model rolls back the batch: every model keeps the substeps before the failing launch and halves its
// step for the rest of the frame (the failing model as step() does; the others then take more, smaller
// substeps than their CPU runs would -- documented in docs/gpu.md).
template <class R>
StepStatus Backend<R>::step() {
  StepStatus status;
  const StepSettings& s = settings;
  const double T = s.dt;
  const auto uB = static_cast<std::size_t>(B);
  left_m.assign(uB, 1);
  h_m.assign(uB, T);
  tt_m.assign(uB, t);
  bool capped = false;
  for (std::size_t b = 0; b < uB; ++b) {
    const double hs = dt_safe(*models[b], stiffening[b], s.safety);
    if (T <= hs * (1.0 + 1e-12)) continue;
    if (!s.substep) {
      ++warnings.unstable_refused;
      status.code = StepCode::Refused;
      return status;
    }
    const double need = std::ceil(T / hs);
    capped = capped || need > s.max_substeps;
    left_m[b] = static_cast<long>(std::min<double>(need, s.max_substeps));
    h_m[b] = T / static_cast<double>(left_m[b]);
  }
  if (capped) ++warnings.substeps_capped;
  const double t0 = t;
  frame_m.assign(uB, 0);
  int rollbacks = 0;
  for (;;) {
    const long launches = *std::max_element(left_m.begin(), left_m.end());
    const bool uniform = *std::min_element(left_m.begin(), left_m.end()) == launches;
    ensure_capacity(launches);
    // The load table: model b's substep kk at the time its CPU run evaluates it (t accumulated by h).
    row_scratch.resize(3 * static_cast<std::size_t>(rows));
    for (std::size_t b = 0; b < uB; ++b) {
      h_host.p[b] = static_cast<R>(h_m[b]);
      count_host.p[b] = static_cast<int>(left_m[b]);
      double tk = tt_m[b];
      for (long kk = 0; kk < left_m[b]; ++kk) {
        std::fill(row_scratch.begin(), row_scratch.end(), 0.0);
        load_rows(loads[b], slots[b], tk, row_scratch.data());
        R* dst = rows_host.p + (static_cast<std::size_t>(kk) * uB + b) * 3 * static_cast<std::size_t>(rows);
        for (std::size_t q = 0; q < row_scratch.size(); ++q) dst[q] = static_cast<R>(row_scratch[q]);
        tk += h_m[b];
      }
    }
    run_batch(launches, uniform, rollbacks);
    check(cudaStreamSynchronize(stream), "running a frame");
    const detail::FrameScalars fs = *scalars_host.p;
    const bool failed = fs.fail_first != INT_MAX;
    const long done = failed ? fs.fail_first : launches;  // launches before the first failure
    long most = 0;
    for (std::size_t b = 0; b < uB; ++b) {
      const long left = left_m[b];
      const long done_b = std::min(done, left);                        // model b's substeps that succeeded
      const long last = failed ? std::min(done, left - 1) : left - 1;  // its last substep that ran
      if (left > 0 && (last == left - 1 || rollbacks == s.max_rollbacks)) {
        double v = 0;
        std::memcpy(&v, &stiff_host.p[static_cast<std::size_t>(last) * uB + b], sizeof v);
        stiffening[b] = std::max(1.0, v);
      }
      for (long kk = 0; kk < done_b; ++kk) tt_m[b] += h_m[b];
      frame_m[b] += done_b;
      model_substeps[b] += static_cast<std::uint64_t>(done_b);
      left_m[b] = left - done_b;
      most = std::max(most, done_b);
    }
    if (!per_block) {
      cur = (cur + static_cast<int>(done & 1)) & 1;
    } else if (!failed) {
      cur = 1 - cur;
    } else if (done > 0) {
      // The block kernel's models ran on past the first failure (each stops at its own): its output is
      // discarded and the substeps before the failure re-run from the intact buffer, guard off (the same
      // arithmetic on the same input: the same states, bit for bit). count_dev still holds each model's
      // count of the failed launch; `done` caps it.
      check(detail::launch_block_frame(block_args(cur, static_cast<int>(done), R(0), 0, false), stream),
            "launching the block kernel");
      cur = 1 - cur;
    }
    substeps += static_cast<std::uint64_t>(most);
    if (!failed) break;
    ++(fs.fail_code == hd::kNodeNonFinite ? warnings.nonfinite : warnings.velocity_limit);
    ++warnings.rollbacks;
    if (++rollbacks > s.max_rollbacks) {  // dropped frame, as step(): positions kept, velocities zeroed
      ++warnings.failed;
      status.code = StepCode::Failed;
      status.substeps = static_cast<int>(*std::max_element(frame_m.begin(), frame_m.end()));
      check(cudaMemsetAsync(vb[cur].p, 0, vb[cur].n * sizeof(R), stream), "zeroing the velocities");
      t = t0 + T;
      ++frames;
      return status;
    }
    status.code = StepCode::RolledBack;
    for (std::size_t b = 0; b < uB; ++b) {
      left_m[b] *= 2;
      h_m[b] *= 0.5;
    }
  }
  status.substeps = static_cast<int>(*std::max_element(frame_m.begin(), frame_m.end()));
  t = t0 + T;
  ++frames;
  return status;
}

template <class R>
double Backend<R>::time_substeps(int count, int repeats) {
  count += count & 1;
  require(count >= 2 && repeats >= 1, "gpu::Engine::time_substeps: count >= 2 and repeats >= 1");
  const StepSettings& s = settings;
  double hs = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < models.size(); ++b)
    hs = std::min(hs, dt_safe(*models[b], stiffening[b], s.safety));
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
  for (int half = 0; per_block && half < 2; ++half) {  // two launches of count / 2: back to buffer cur
    detail::BlockArgs<R> A = block_args((cur + half) & 1, count / 2, static_cast<R>(h), 0, false);
    A.load_substep_stride = 0;  // the same loads for every substep
    A.s.count_model = nullptr;  // every model count / 2 substeps of h
    A.s.h_model = nullptr;
    const cudaError_t e = detail::launch_block_frame(A, stream);
    if (e != cudaSuccess) {
      cudaStreamEndCapture(stream, &g);
      if (g) cudaGraphDestroy(g);
      check(e, "launching the block kernel");
    }
  }
  for (int kk = 0; !per_block && kk < count; ++kk) {
    detail::SubstepArgs<R> A = args(cur, kk, static_cast<R>(h), false);
    A.loads = rows_dev.p;     // the same loads for every substep
    A.count_model = nullptr;  // every model every substep, with h
    A.h_model = nullptr;
    A.substep = 0;  // no guard skipping between substeps
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

template struct Backend<double>;
template struct Backend<float>;

}  // namespace medspring::gpu::detail
