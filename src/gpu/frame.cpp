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

// Enqueues a batch of `left` substeps of h from the current buffers (no host work, capturable). The
// grid kernel: one launch per substep, ping-pong between the buffers; the block kernel: one launch,
// into the other buffer.
template <class R>
void Backend<R>::enqueue(long left, double h, int rollbacks) {
  check(cudaMemcpyAsync(scalars_dev.p, scalars_host_init.p, sizeof(detail::FrameScalars),
                        cudaMemcpyHostToDevice, stream),
        "resetting the frame scalars");
  check(cudaMemsetAsync(stiff_dev.p, 0, static_cast<std::size_t>(left) * sizeof(unsigned long long), stream),
        "resetting the stiffening slots");
  check(cudaMemcpyAsync(rows_dev.p, rows_host.p, row_count(left) * sizeof(R), cudaMemcpyHostToDevice, stream),
        "uploading the load table");
  if (per_block) {
    const int mode = rollbacks == settings.max_rollbacks ? 2 : 1;
    check(detail::launch_block_frame(
              block_args(cur, static_cast<int>(left), static_cast<R>(h), mode, settings.guard), stream),
          "launching the block kernel");
  } else {
    for (long kk = 0; kk < left; ++kk) {
      const bool stiff = kk == left - 1 || rollbacks == settings.max_rollbacks;
      check(detail::launch_substep(args(cur, kk, static_cast<R>(h), stiff), options.block, stream),
            "launching the substep kernel");
    }
  }
  check(cudaMemcpyAsync(scalars_host.p, scalars_dev.p, sizeof(detail::FrameScalars), cudaMemcpyDeviceToHost,
                        stream),
        "reading the frame scalars");
  check(
      cudaMemcpyAsync(stiff_host.p, stiff_dev.p, static_cast<std::size_t>(left) * sizeof(unsigned long long),
                      cudaMemcpyDeviceToHost, stream),
      "reading the stiffening");
}

template <class R>
void Backend<R>::run_batch(long left, double h, int rollbacks) {
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

template <class R>
StepStatus Backend<R>::step() {
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
    if (!per_block) {
      cur = (cur + static_cast<int>(done & 1)) & 1;
    } else if (!failed) {
      cur = 1 - cur;
    } else if (done > 0) {
      // The block kernel's models ran on past the first failure (each stops at its own): its output is
      // discarded and the `done` substeps before the failure re-run from the intact buffer, guard off
      // (the same arithmetic on the same input: the same states, bit for bit).
      check(detail::launch_block_frame(block_args(cur, static_cast<int>(done), static_cast<R>(h), 0, false),
                                       stream),
            "launching the block kernel");
      cur = 1 - cur;
    }
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

template <class R>
double Backend<R>::time_substeps(int count, int repeats) {
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
  for (int half = 0; per_block && half < 2; ++half) {  // two launches of count / 2: back to buffer cur
    detail::BlockArgs<R> A = block_args((cur + half) & 1, count / 2, static_cast<R>(h), 0, false);
    A.load_substep_stride = 0;  // the same loads for every substep
    const cudaError_t e = detail::launch_block_frame(A, stream);
    if (e != cudaSuccess) {
      cudaStreamEndCapture(stream, &g);
      if (g) cudaGraphDestroy(g);
      check(e, "launching the block kernel");
    }
  }
  for (int kk = 0; !per_block && kk < count; ++kk) {
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

template struct Backend<double>;
template struct Backend<float>;

}  // namespace medspring::gpu::detail
