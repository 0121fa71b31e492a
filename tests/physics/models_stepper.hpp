// Several models per thread on the CPU (hd::node_substep_models, physics/kernels_models.hpp; the grid
// kernel's substep_models_kernel in src/gpu/kernels.cu): a batch of B models of one topology laid out as
// the GPU backend lays it out (states B x 3n, node parameters per model or shared, load slots and rows per
// model, one spring table), stepped by groups of M models per "thread", against each model stepped alone
// by hd::node_substep (or, with heavy rows split, hd::grid_split_gather / _finish) from its own arrays.
#pragma once

#include <algorithm>
#include <random>
#include <vector>

#include "medspring/physics/kernels_models.hpp"
#include "medspring/physics/spring_table.hpp"

namespace medspring::testing {

template <class R>
struct ModelsBatch {
  std::vector<const Model*> models;
  int M = 2;
  bool split = false;                 // the grid kernel's split rows (make_grid_split_table, chunk below)
  GridSplitArrays<R> G;               // the split rows (used when split)
  SpringTableArrays<R> T;             // the table shared by the batch: G's when split, else HeavyLast
  std::vector<NodeArrayData<R>> own;  // each model's node arrays (the reference's)
  NodeArrayData<R> all;               // the batch's node arrays (stride n, or 0 when shared)
  bool shared_nodes = true;
  int n = 0, B = 0, rows_per_model = 1;
  std::vector<LoadSlots> slots;
  std::vector<std::vector<PointLoad>> loads;
  // Reference: per model. Batch: B x 3n.
  std::vector<std::vector<R>> rx, rv, rxo, rvo, rparts;
  std::vector<R> x, v, xo, vo, parts, rows;
  std::vector<R> rstiff, stiff;
  std::vector<int> rcode, code;
  int parts_per_model = 0;

  ModelsBatch(const std::vector<const Model*>& ms, std::vector<std::vector<PointLoad>> L, int per_thread,
              int chunk, bool compact)
      : models(ms), M(per_thread), loads(std::move(L)) {
    const Model& m0 = *ms[0];
    n = static_cast<int>(m0.num_nodes());
    B = static_cast<int>(ms.size());
    G = make_grid_split_table<R>(m0, chunk);
    split = !G.heavy_node.empty();
    T = split ? G.table : make_spring_table<R>(m0, RowOrder::HeavyLast);  // the table both ways run
    if (compact) compact_spring_params(T, 65536);
    parts_per_model = std::max(1, G.parts());
    for (int b = 0; b < B; ++b) {
      own.push_back(make_node_arrays<R>(*ms[static_cast<std::size_t>(b)]));
      slots.push_back(make_load_slots(loads[static_cast<std::size_t>(b)], n));
      own.back().load_slot = slots.back().slot;
      rows_per_model = std::max(rows_per_model, static_cast<int>(slots.back().nodes.size()));
      const NodeArrayData<R>& o = own.back();
      shared_nodes = shared_nodes && o.x0 == own[0].x0 && o.mass == own[0].mass &&
                     o.damping == own[0].damping && o.kr == own[0].kr && o.fixed == own[0].fixed;
    }
    all = own[0];
    all.load_slot.clear();
    if (!shared_nodes) {
      all = NodeArrayData<R>{};
      all.nodes = n;
      for (const NodeArrayData<R>& o : own) {
        all.x0.insert(all.x0.end(), o.x0.begin(), o.x0.end());
        all.mass.insert(all.mass.end(), o.mass.begin(), o.mass.end());
        all.damping.insert(all.damping.end(), o.damping.begin(), o.damping.end());
        all.kr.insert(all.kr.end(), o.kr.begin(), o.kr.end());
        all.fixed.insert(all.fixed.end(), o.fixed.begin(), o.fixed.end());
      }
    } else if (compact) {
      compact_node_params(all);
    }
    for (const NodeArrayData<R>& o : own)
      all.load_slot.insert(all.load_slot.end(), o.load_slot.begin(), o.load_slot.end());
    // Each model's state: its rest shape displaced at random (a few % of a spring), a small velocity.
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> jitter(-0.2, 0.2);
    const auto n3 = 3 * static_cast<std::size_t>(n);
    for (int b = 0; b < B; ++b) {
      std::vector<R> xb(own[static_cast<std::size_t>(b)].x0), vb(n3);
      for (std::size_t q = 0; q < n3; ++q) {
        xb[q] += static_cast<R>(jitter(rng));
        vb[q] = static_cast<R>(0.01 * jitter(rng));
      }
      rx.push_back(xb);
      rv.push_back(vb);
      x.insert(x.end(), xb.begin(), xb.end());
      v.insert(v.end(), vb.begin(), vb.end());
    }
    rxo = rx;
    rvo = rv;
    xo = x;
    vo = v;
    rparts.assign(static_cast<std::size_t>(B), std::vector<R>(3 * static_cast<std::size_t>(parts_per_model)));
    parts.assign(3 * static_cast<std::size_t>(parts_per_model) * static_cast<std::size_t>(B), R(0));
    rows.assign(3 * static_cast<std::size_t>(rows_per_model) * static_cast<std::size_t>(B), R(0));
  }

  hd::ModelStrides strides() const {
    hd::ModelStrides S;
    S.state = 3ll * n;
    S.node = shared_nodes ? 0 : n;
    S.slot = n;
    S.loads = 3ll * rows_per_model;
    S.parts = 3ll * parts_per_model;
    return S;
  }

  // One substep of every model at time t with step h (model b: h * (1 + b / 64), so the models' steps
  // differ as count_model / h_model make them), both ways; `active`: the models that take it (the others
  // are left alone, as the kernel's carry-over). Stiff: the stiffening of each model into rstiff / stiff.
  template <bool Soft, bool Stiff>
  void substep(double t, R h, R vmax2, const std::vector<bool>& active) {
    std::vector<double> rd(3 * static_cast<std::size_t>(rows_per_model));
    for (int b = 0; b < B; ++b) {
      std::fill(rd.begin(), rd.end(), 0.0);
      load_rows_at(b, t, rd);
      for (std::size_t q = 0; q < rd.size(); ++q)
        rows[static_cast<std::size_t>(b) * rd.size() + q] = static_cast<R>(rd[q]);
    }
    const auto table = T.view();
    const hd::GridSplit GS = G.view();
    const int nrows = split ? G.rows() : n;
    rstiff.assign(static_cast<std::size_t>(B), R(1));
    stiff.assign(static_cast<std::size_t>(B), R(1));
    rcode.assign(static_cast<std::size_t>(B), hd::kNodeOk);
    code.assign(static_cast<std::size_t>(B), hd::kNodeOk);
    auto hb = [&](int b) { return h * (R(1) + R(b) / R(64)); };
    // Reference: each model alone.
    for (int b = 0; b < B; ++b) {
      const auto ub = static_cast<std::size_t>(b);
      if (!active[ub]) continue;
      const auto N = own[ub].view();
      const R* L = rows.data() + ub * 3 * static_cast<std::size_t>(rows_per_model);
      for (int r = 0; r < nrows; ++r) {
        const int c =
            split ? hd::grid_split_gather<Soft, Stiff>(N, table, GS, r, hb(b), vmax2, L, rx[ub].data(),
                                                       rv[ub].data(), rxo[ub].data(), rvo[ub].data(),
                                                       rparts[ub].data(), rstiff[ub])
                  : hd::node_substep<Soft, Stiff>(N, table, r, hb(b), vmax2, L, rx[ub].data(), rv[ub].data(),
                                                  rxo[ub].data(), rvo[ub].data(), rstiff[ub]);
        rcode[ub] = std::max(rcode[ub], c);
      }
      for (int r = 0; split && r < nrows; ++r)
        rcode[ub] =
            std::max(rcode[ub], hd::grid_split_finish(N, GS, r, hb(b), vmax2, L, rx[ub].data(), rv[ub].data(),
                                                      rxo[ub].data(), rvo[ub].data(), rparts[ub].data()));
    }
    // Batch: groups of M models, one "thread" per row and group.
    const hd::ModelStrides S = strides();
    const auto N = all.view();
    for (int b0 = 0; b0 < B; b0 += M) {
      unsigned mask = 0;
      R hs[8], st[8];
      for (int m = 0; m < M; ++m) {
        hs[m] = hb(b0 + m);
        st[m] = R(1);
        if (b0 + m < B && active[static_cast<std::size_t>(b0 + m)]) mask |= 1u << m;
      }
      hd::NodeArrays<R> Ng = hd::model_nodes(N, S, b0);  // the group's model 0 (as model_arrays)
      const long long off = S.state * b0;
      const R* L = rows.data() + S.loads * b0;
      R* P = parts.data() + S.parts * b0;
      int c = hd::kNodeOk;
      for (int r = 0; r < nrows; ++r) {
        int e;
        if (M == 2)
          e = split ? hd::grid_split_gather_models<Soft, Stiff, 2>(Ng, table, GS, S, mask, r, hs, vmax2, L,
                                                                   x.data() + off, v.data() + off,
                                                                   xo.data() + off, vo.data() + off, P, st)
                    : hd::node_substep_models<Soft, Stiff, 2>(Ng, table, S, mask, r, hs, vmax2, L,
                                                              x.data() + off, v.data() + off, xo.data() + off,
                                                              vo.data() + off, st);
        else
          e = split ? hd::grid_split_gather_models<Soft, Stiff, 4>(Ng, table, GS, S, mask, r, hs, vmax2, L,
                                                                   x.data() + off, v.data() + off,
                                                                   xo.data() + off, vo.data() + off, P, st)
                    : hd::node_substep_models<Soft, Stiff, 4>(Ng, table, S, mask, r, hs, vmax2, L,
                                                              x.data() + off, v.data() + off, xo.data() + off,
                                                              vo.data() + off, st);
        c = std::max(c, e);
      }
      for (int r = 0; split && r < nrows; ++r) {
        const int e =
            M == 2 ? hd::grid_split_finish_models<2>(Ng, GS, S, mask, r, hs, vmax2, L, x.data() + off,
                                                     v.data() + off, xo.data() + off, vo.data() + off, P)
                   : hd::grid_split_finish_models<4>(Ng, GS, S, mask, r, hs, vmax2, L, x.data() + off,
                                                     v.data() + off, xo.data() + off, vo.data() + off, P);
        c = std::max(c, e);
      }
      for (int m = 0; m < M && b0 + m < B; ++m) {
        stiff[static_cast<std::size_t>(b0 + m)] = st[m];
        code[static_cast<std::size_t>(b0 + m)] = c;  // the group's (the kernel reduces over the launch)
      }
    }
    // Swap the buffers of the models that ran (the others keep theirs: the carry-over).
    const auto n3 = 3 * static_cast<std::size_t>(n);
    for (int b = 0; b < B; ++b) {
      const auto ub = static_cast<std::size_t>(b);
      if (!active[ub]) continue;
      std::swap(rx[ub], rxo[ub]);
      std::swap(rv[ub], rvo[ub]);
      std::copy(xo.begin() + static_cast<std::ptrdiff_t>(ub * n3),
                xo.begin() + static_cast<std::ptrdiff_t>((ub + 1) * n3),
                x.begin() + static_cast<std::ptrdiff_t>(ub * n3));
      std::copy(vo.begin() + static_cast<std::ptrdiff_t>(ub * n3),
                vo.begin() + static_cast<std::ptrdiff_t>((ub + 1) * n3),
                v.begin() + static_cast<std::ptrdiff_t>(ub * n3));
    }
  }

  void load_rows_at(int b, double t, std::vector<double>& out) const {
    const auto ub = static_cast<std::size_t>(b);
    medspring::load_rows(loads[ub], slots[ub], t, out.data());
  }

  // Model b's batch state (positions or velocities) as a vector.
  std::vector<R> batch_state(int b, bool velocities) const {
    const auto n3 = 3 * static_cast<std::size_t>(n);
    const std::vector<R>& s = velocities ? v : x;
    return {s.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(b) * n3),
            s.begin() + static_cast<std::ptrdiff_t>((static_cast<std::size_t>(b) + 1) * n3)};
  }
};

}  // namespace medspring::testing
