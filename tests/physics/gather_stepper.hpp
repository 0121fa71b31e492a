// A CPU stepper that runs the GPU path's arithmetic: the spring table (sliced ELL gather, no scatter)
// and hd::node_substep from physics/kernels.hpp, with step()'s substep rule (no rollbacks). Used to
// check on the CPU that the functions the CUDA kernels run give the engine's results (docs/gpu.md).
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "medspring/physics/integrators.hpp"
#include "medspring/physics/spring_table.hpp"
#include "medspring/physics/stability.hpp"

namespace medspring::testing {

template <class R>
struct GatherStepper {
  const Model& m;
  SpringTableArrays<R> T;
  NodeArrayData<R> N;
  std::vector<PointLoad> loads;
  LoadSlots slots;
  std::vector<R> x, v, xo, vo, rows;
  std::vector<double> rows_d;
  double t = 0, stiffening = 1;
  long substeps = 0;
  int failures = 0;

  // compact: the parameters as classes (compact_spring_params / compact_node_params) where they fit.
  explicit GatherStepper(const Model& model, std::vector<PointLoad> L = {}, bool compact = false)
      : m(model), T(make_spring_table<R>(model)), N(make_node_arrays<R>(model)), loads(std::move(L)) {
    if (compact) {
      compact_spring_params(T);
      compact_node_params(N);
    }
    slots = make_load_slots(loads, m.num_nodes());
    N.load_slot = slots.slot;
    x = N.x0;
    v.assign(x.size(), R(0));
    xo = x;
    vo = v;
    rows.assign(3 * std::max<std::size_t>(1, slots.nodes.size()), R(0));
    rows_d.assign(rows.size(), 0.0);
  }

  void frame(const StepSettings& s) {
    const double hs = dt_safe(m, stiffening, s.safety);
    long subs = 1;
    if (s.dt > hs * (1.0 + 1e-12))
      subs = static_cast<long>(std::min<double>(std::ceil(s.dt / hs), s.max_substeps));
    const double h = s.dt / static_cast<double>(subs);
    const double t0 = t;
    const auto nodes = N.view();
    const auto table = T.view();
    for (long k = 0; k < subs; ++k) {
      load_rows(loads, slots, t, rows_d.data());
      for (std::size_t q = 0; q < rows.size(); ++q) rows[q] = static_cast<R>(rows_d[q]);
      const bool stiff = k == subs - 1;
      R st = R(1);
      for (int a = 0; a < nodes.nodes; ++a) {
        int code;
        if (m.has_soft_springs)
          code = stiff
                     ? hd::node_substep<true, true>(nodes, table, a, static_cast<R>(h), R(1e30), rows.data(),
                                                    x.data(), v.data(), xo.data(), vo.data(), st)
                     : hd::node_substep<true, false>(nodes, table, a, static_cast<R>(h), R(1e30), rows.data(),
                                                     x.data(), v.data(), xo.data(), vo.data(), st);
        else
          code =
              stiff ? hd::node_substep<false, true>(nodes, table, a, static_cast<R>(h), R(1e30), rows.data(),
                                                    x.data(), v.data(), xo.data(), vo.data(), st)
                    : hd::node_substep<false, false>(nodes, table, a, static_cast<R>(h), R(1e30), rows.data(),
                                                     x.data(), v.data(), xo.data(), vo.data(), st);
        failures += code != hd::kNodeOk;
      }
      if (stiff) stiffening = static_cast<double>(st);
      std::swap(x, xo);
      std::swap(v, vo);
      t += h;
      ++substeps;
    }
    t = t0 + s.dt;
  }
};

/// The one-block-per-model kernel's algorithm on the CPU (src/gpu/kernels.cu, block_frame_kernel): the
/// table's rows dealt to `threads` threads (RowOrder::Balanced), two position buffers and velocities
/// updated in place, hd::block_rows for thread t = 0 .. threads - 1 in turn between the "barriers" of a
/// substep, the stiffening of the frame's last substep, the guard's first failing substep.
template <class R>
struct BlockStepper {
  const Model& m;
  int threads;
  SpringTableArrays<R> T;
  NodeArrayData<R> N;
  std::vector<PointLoad> loads;
  LoadSlots slots;
  std::vector<R> x, xb, v, rows;
  std::vector<double> rows_d;
  double t = 0, stiffening = 1;
  long substeps = 0;
  int failures = 0;

  BlockStepper(const Model& model, std::vector<PointLoad> L, int block_threads,
               RowOrder order = RowOrder::Balanced)
      : m(model),
        threads(block_threads),
        T(make_spring_table<R>(model, order, block_threads)),
        N(make_node_arrays<R>(model)),
        loads(std::move(L)) {
    slots = make_load_slots(loads, m.num_nodes());
    N.load_slot = slots.slot;
    x = N.x0;
    xb = x;
    v.assign(x.size(), R(0));
    rows.assign(3 * std::max<std::size_t>(1, slots.nodes.size()), R(0));
    rows_d.assign(rows.size(), 0.0);
  }

  void frame(const StepSettings& s) {
    const double hs = dt_safe(m, stiffening, s.safety);
    long subs = 1;
    if (s.dt > hs * (1.0 + 1e-12))
      subs = static_cast<long>(std::min<double>(std::ceil(s.dt / hs), s.max_substeps));
    const double hstep = s.dt / static_cast<double>(subs);  // the clock advances in double, as step()
    const R h = static_cast<R>(hstep);
    const R vmax2 = static_cast<R>(s.v_max * s.v_max);
    const double t0 = t;
    const auto nodes = N.view();
    const auto table = T.view();
    for (long kk = 0; kk < subs; ++kk) {  // the kernel's substep loop
      load_rows(loads, slots, t, rows_d.data());
      for (std::size_t q = 0; q < rows.size(); ++q) rows[q] = static_cast<R>(rows_d[q]);
      const bool stiff_now = kk == subs - 1;
      R block_stiff = R(1);
      int block_code = hd::kNodeOk;
      for (int tt = 0; tt < threads; ++tt) {  // the block's threads, one after the other
        R stiff = R(1);
        const int code =
            m.has_soft_springs
                ? (stiff_now ? hd::block_rows<true, true>(nodes, table, tt, threads, h, vmax2, rows.data(),
                                                          x.data(), v.data(), xb.data(), stiff)
                             : hd::block_rows<true, false>(nodes, table, tt, threads, h, vmax2, rows.data(),
                                                           x.data(), v.data(), xb.data(), stiff))
                : (stiff_now ? hd::block_rows<false, true>(nodes, table, tt, threads, h, vmax2, rows.data(),
                                                           x.data(), v.data(), xb.data(), stiff)
                             : hd::block_rows<false, false>(nodes, table, tt, threads, h, vmax2, rows.data(),
                                                            x.data(), v.data(), xb.data(), stiff));
        block_stiff = std::max(block_stiff, stiff);
        block_code = std::max(block_code, code);
      }
      if (stiff_now) stiffening = static_cast<double>(block_stiff);
      failures += block_code != hd::kNodeOk;
      std::swap(x, xb);
      t += hstep;
      ++substeps;
    }
    t = t0 + s.dt;
  }
};

/// The block kernel with heavy rows split (kernels_split.hpp) on the CPU: phase 1 for every thread, the
/// "barrier", phase 2 for every thread, per substep.
template <class R>
struct SplitStepper {
  const Model& m;
  int threads;
  SplitTableArrays<R> S;
  NodeArrayData<R> N;
  std::vector<PointLoad> loads;
  LoadSlots slots;
  std::vector<R> x, xb, v, rows, parts;
  std::vector<double> rows_d;
  double t = 0, stiffening = 1;
  long substeps = 0;
  int failures = 0;

  SplitStepper(const Model& model, std::vector<PointLoad> L, int block_threads, int chunk = 0)
      : m(model),
        threads(block_threads),
        S(make_split_table<R>(model, block_threads, chunk)),
        N(make_node_arrays<R>(model)),
        loads(std::move(L)) {
    slots = make_load_slots(loads, m.num_nodes());
    N.load_slot = slots.slot;
    x = N.x0;
    xb = x;
    v.assign(x.size(), R(0));
    parts.assign(3 * static_cast<std::size_t>(std::max(1, S.parts())), R(0));
    rows.assign(3 * std::max<std::size_t>(1, slots.nodes.size()), R(0));
    rows_d.assign(rows.size(), 0.0);
  }

  template <bool Soft, bool Stiff>
  int phase1(int tt, R h, R vmax2, R& stiff) {
    return hd::split_phase1<Soft, Stiff>(N.view(), S.table.view(), S.view(), tt, threads, h, vmax2,
                                         rows.data(), x.data(), v.data(), xb.data(), parts.data(), stiff);
  }

  void frame(const StepSettings& s) {
    const double hs = dt_safe(m, stiffening, s.safety);
    long subs = 1;
    if (s.dt > hs * (1.0 + 1e-12))
      subs = static_cast<long>(std::min<double>(std::ceil(s.dt / hs), s.max_substeps));
    const double hstep = s.dt / static_cast<double>(subs);
    const R h = static_cast<R>(hstep);
    const R vmax2 = static_cast<R>(s.v_max * s.v_max);
    const double t0 = t;
    for (long kk = 0; kk < subs; ++kk) {
      load_rows(loads, slots, t, rows_d.data());
      for (std::size_t q = 0; q < rows.size(); ++q) rows[q] = static_cast<R>(rows_d[q]);
      const bool stiff_now = kk == subs - 1;
      R block_stiff = R(1);
      int code = hd::kNodeOk;
      for (int tt = 0; tt < threads; ++tt) {  // phase 1
        R stiff = R(1);
        const int c = m.has_soft_springs ? (stiff_now ? phase1<true, true>(tt, h, vmax2, stiff)
                                                      : phase1<true, false>(tt, h, vmax2, stiff))
                                         : (stiff_now ? phase1<false, true>(tt, h, vmax2, stiff)
                                                      : phase1<false, false>(tt, h, vmax2, stiff));
        block_stiff = std::max(block_stiff, stiff);
        code = std::max(code, c);
      }
      for (int tt = 0; tt < threads; ++tt)  // phase 2, after the barrier
        code = std::max(code, hd::split_phase2(N.view(), S.view(), tt, threads, h, vmax2, rows.data(),
                                               x.data(), v.data(), xb.data(), parts.data()));
      if (stiff_now) stiffening = static_cast<double>(block_stiff);
      failures += code != hd::kNodeOk;
      std::swap(x, xb);
      t += hstep;
      ++substeps;
    }
    t = t0 + s.dt;
  }
};

/// The grid kernel with heavy rows split (make_grid_split_table, hd::grid_split_gather / _finish): every
/// row's phase 1 (whole nodes advance, chunks write their sums), then — the warp barrier — every lead
/// row's phase 2, ping-pong buffers for x and v as the grid kernel.
template <class R>
struct GridSplitStepper {
  const Model& m;
  GridSplitArrays<R> G;
  NodeArrayData<R> N;
  std::vector<PointLoad> loads;
  LoadSlots slots;
  std::vector<R> x, xb, v, vb, rows, parts;
  std::vector<double> rows_d;
  double t = 0, stiffening = 1;
  long substeps = 0;
  int failures = 0;

  GridSplitStepper(const Model& model, std::vector<PointLoad> L, int chunk = 0)
      : m(model),
        G(make_grid_split_table<R>(model, chunk)),
        N(make_node_arrays<R>(model)),
        loads(std::move(L)) {
    slots = make_load_slots(loads, m.num_nodes());
    N.load_slot = slots.slot;
    x = N.x0;
    xb = x;
    v.assign(x.size(), R(0));
    vb = v;
    parts.assign(3 * static_cast<std::size_t>(std::max(1, G.parts())), R(0));
    rows.assign(3 * std::max<std::size_t>(1, slots.nodes.size()), R(0));
    rows_d.assign(rows.size(), 0.0);
  }

  template <bool Soft, bool Stiff>
  int gather(int r, R h, R vmax2, R& stiff) {
    return hd::grid_split_gather<Soft, Stiff>(N.view(), G.table.view(), G.view(), r, h, vmax2, rows.data(),
                                              x.data(), v.data(), xb.data(), vb.data(), parts.data(), stiff);
  }

  void frame(const StepSettings& s) {
    const double hs = dt_safe(m, stiffening, s.safety);
    long subs = 1;
    if (s.dt > hs * (1.0 + 1e-12))
      subs = static_cast<long>(std::min<double>(std::ceil(s.dt / hs), s.max_substeps));
    const double hstep = s.dt / static_cast<double>(subs);
    const R h = static_cast<R>(hstep);
    const R vmax2 = static_cast<R>(s.v_max * s.v_max);
    const double t0 = t;
    for (long kk = 0; kk < subs; ++kk) {
      load_rows(loads, slots, t, rows_d.data());
      for (std::size_t q = 0; q < rows.size(); ++q) rows[q] = static_cast<R>(rows_d[q]);
      const bool stiff_now = kk == subs - 1;
      R grid_stiff = R(1);
      int code = hd::kNodeOk;
      for (int r = 0; r < G.rows(); ++r) {  // phase 1: every thread of the grid
        R stiff = R(1);
        const int c = m.has_soft_springs ? (stiff_now ? gather<true, true>(r, h, vmax2, stiff)
                                                      : gather<true, false>(r, h, vmax2, stiff))
                                         : (stiff_now ? gather<false, true>(r, h, vmax2, stiff)
                                                      : gather<false, false>(r, h, vmax2, stiff));
        grid_stiff = std::max(grid_stiff, stiff);
        code = std::max(code, c);
      }
      for (int r = 0; r < G.rows(); ++r)  // phase 2, after each warp's barrier
        code = std::max(code, hd::grid_split_finish(N.view(), G.view(), r, h, vmax2, rows.data(), x.data(),
                                                    v.data(), xb.data(), vb.data(), parts.data()));
      if (stiff_now) stiffening = static_cast<double>(grid_stiff);
      failures += code != hd::kNodeOk;
      std::swap(x, xb);
      std::swap(v, vb);
      t += hstep;
      ++substeps;
    }
    t = t0 + s.dt;
  }
};

/// max |a - b| / max(1, max |b|) over the entries.
template <class R>
double relative_difference(const std::vector<R>& a, const MatX3& b) {
  double d = 0, s = 1;
  for (Index q = 0; q < b.size(); ++q) {
    d = std::max(d, std::abs(static_cast<double>(a[static_cast<std::size_t>(q)]) - b.data()[q]));
    s = std::max(s, std::abs(b.data()[q]));
  }
  return d / s;
}

}  // namespace medspring::testing
