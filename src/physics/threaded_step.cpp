// The fused node-range step of large models (threaded_step.hpp).
#include "threaded_step.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "medspring/physics/kernels.hpp"
#include "spring_gather.hpp"
#include "spring_kernel.hpp"

namespace medspring {

void ThreadedStep::partition(const Model& m) {
  const int T = pool.size();
  const auto uT = static_cast<std::size_t>(T);
  const Index n = m.num_nodes(), ns = m.num_springs();
  const auto un = static_cast<std::size_t>(n);
  std::vector<Index> node_begin(uT + 1, 0);
  for (std::size_t t = 0; t <= uT; ++t)
    node_begin[t] = static_cast<Index>(static_cast<long long>(n) * static_cast<long long>(t) / T);
  auto owner = [&](Index a) {
    int t = n > 0 ? static_cast<int>(static_cast<long long>(a) * T / n) : 0;
    while (a >= node_begin[static_cast<std::size_t>(t) + 1]) ++t;
    while (a < node_begin[static_cast<std::size_t>(t)]) --t;
    return static_cast<std::size_t>(t);
  };
  part.assign(uT, Part{});
  for (std::size_t t = 0; t < uT; ++t) {
    part[t].n0 = node_begin[t];
    part[t].n1 = node_begin[t + 1];
  }
  kind.assign(un, 1);
  for (const Index a : m.free_nodes) kind[static_cast<std::size_t>(a)] = 0;
  // chunks of inner springs (runs of consecutive spring indices, at most kChunk long); the chunk of each
  // node's last inner spring; `init` first holds the largest node of its chunk + 1
  std::vector<Index> last_chunk(un, -1);
  for (Index s = 0; s < ns; ++s) {
    const Index i = m.springs.i[static_cast<std::size_t>(s)], j = m.springs.j[static_cast<std::size_t>(s)];
    const std::size_t ti = owner(i), tj = owner(j);
    if (ti == tj) {
      std::vector<Chunk>& C = part[ti].chunks;
      if (C.empty() || C.back().s1 != s || C.back().s1 - C.back().s0 >= detail::kChunk)
        C.push_back(Chunk{s, s, 0, 0});
      Chunk& c = C.back();
      c.s1 = s + 1;
      c.init = std::max(c.init, std::max(i, j) + 1);
      const auto k = static_cast<Index>(C.size()) - 1;
      last_chunk[static_cast<std::size_t>(i)] = k;
      last_chunk[static_cast<std::size_t>(j)] = k;
    } else {
      part[ti].cross.push_back(s);
      part[tj].cross.push_back(-(s + 1));
      for (const Index a : {i, j})
        if (kind[static_cast<std::size_t>(a)] == 0) kind[static_cast<std::size_t>(a)] = 2;
    }
  }
  has_boundary = false;
  for (Part& P : part) {
    for (Index a = P.n0; a < P.n1; ++a)
      if (kind[static_cast<std::size_t>(a)] == 2) P.boundary.push_back(a);
    has_boundary = has_boundary || !P.boundary.empty();
    const std::size_t nc = P.chunks.size();
    // init: forces of the nodes up to the largest one read so far; ready: the longest prefix of the
    // thread's nodes whose last inner spring has been swept (nodes without one: from the first chunk)
    Index init = P.n0;
    std::vector<Index> ready(nc, P.n0);
    for (std::size_t c = 0; c < nc; ++c) {
      init = std::max(init, P.chunks[c].init);
      P.chunks[c].init = init;
    }
    Index pm = 0;
    for (Index a = P.n0; a < P.n1 && nc > 0; ++a) {
      pm = std::max(pm, last_chunk[static_cast<std::size_t>(a)]);
      ready[static_cast<std::size_t>(pm)] = a + 1;
    }
    Index r = P.n0;
    for (std::size_t c = 0; c < nc; ++c) {
      r = std::max(r, ready[c]);
      P.chunks[c].ready = r;
    }
  }
  model = &m;
  x0 = m.x0.data();
  spring_i = m.springs.i.data();
  nodes = n;
  springs = ns;
}

namespace detail {

namespace {

constexpr int kOk = 0, kTooFast = 1, kNonFinite = 2;

// Restores the free interior nodes of [a0, a1) advanced in this substep (undo_symplectic's arithmetic).
void undo_range(const Model& m, State& st, double h, const std::uint8_t* kind, Index a0, Index a1) {
  for (Index a = a0; a < a1; ++a)
    if (kind[a] == 0) undo_symplectic(m, st, h, &a, 1);
}

// Symplectic Euler with implicit damping (§2.1) of the free interior nodes of [a0, a1), forces in st.f;
// the guard (§2.5) restores those of [undo_from, a) when node a fails.
template <bool Guard>
int advance_range(const Model& m, State& st, double h, double vmax2, const std::uint8_t* kind, Index a0,
                  Index a1, Index undo_from) {
  const double* G = st.f.data();
  const double* Mv = m.mass.data();
  const double* C = st.step_coef.data();
  double* X = st.x.data();
  double* V = st.v.data();
  for (Index a = a0; a < a1; ++a) {
    if (kind[a] != 0) continue;
    const Index q = 3 * a;
    double vn[3];
    const double v2 = hd::symplectic_velocity(Mv[a], C[a], h, V + q, G + q, vn);
    if constexpr (Guard) {
      if (!hd::velocity_ok(v2, vmax2)) {  // also catches NaN
        undo_range(m, st, h, kind, undo_from, a);
        return std::isfinite(v2) ? kTooFast : kNonFinite;
      }
    }
    V[q] = vn[0];
    V[q + 1] = vn[1];
    V[q + 2] = vn[2];
    hd::symplectic_position(h, X + q, vn, X + q);
  }
  return kOk;
}

// f_i += t e, f_j -= t e for the springs [0, nb) of a chunk, in spring order. The force of the end i of a
// run of springs with the same end i stays in registers over the run (loaded at its start, stored at its
// end, every other update of that node made to the registers too): the same additions in the same order
// as the plain scatter, without a store-to-load round trip per spring.
void scatter(Index nb, const Index* __restrict I, const Index* __restrict J, const double* __restrict F4,
             double* __restrict f) {
  if (nb <= 0) return;
  Index cur = 3 * I[0];
  double cx = f[cur], cy = f[cur + 1], cz = f[cur + 2];
  for (Index q = 0; q < nb; ++q) {
    const double fx = F4[4 * q], fy = F4[4 * q + 1], fz = F4[4 * q + 2];
    const Index a = 3 * I[q], b = 3 * J[q];
    if (a != cur) {
      f[cur] = cx;
      f[cur + 1] = cy;
      f[cur + 2] = cz;
      cur = a;
      cx = f[a];
      cy = f[a + 1];
      cz = f[a + 2];
    }
    cx += fx;
    cy += fy;
    cz += fz;
    if (b == cur) {
      cx -= fx;
      cy -= fy;
      cz -= fz;
    } else {
      f[b] -= fx;
      f[b + 1] -= fy;
      f[b + 2] -= fz;
    }
  }
  f[cur] = cx;
  f[cur + 1] = cy;
  f[cur + 2] = cz;
}

// Phase 1 of thread t: the fused sweep over its inner springs, then its crossing springs. After a failed
// node the sweep goes on without advancing nodes, so that st.f and the stiffening are complete.
template <bool Soft, bool Stiff, bool Guard>
void sweep(const Model& m, State& st, ThreadedStep& P, int t, double h, double vmax2) {
  ThreadedStep::Part& p = P.part[static_cast<std::size_t>(t)];
  const double* X = st.x.data();
  const double* FE = st.f_ext.data();
  double* f = st.f.data();
  const std::uint8_t* kind = P.kind.data();
  const SpringArrays S(m);
  double stiff = 1.0;
  std::int64_t stiff_bits = 0;        // spring_chunk_forces' running maximum
  alignas(64) double F4[4 * kChunk];  // the chunk's spring forces, rows (x, y, z, 0)
  Index init = p.n0, ready = p.n0;
  int code = kOk;
  for (const ThreadedStep::Chunk& c : p.chunks) {
    if (c.init > init) {
      return_forces(m, X, FE, f, init, c.init);
      init = c.init;
    }
    if constexpr (Soft) {
      for (Index s = c.s0; s < c.s1; ++s) add_spring_force<Soft, Stiff>(S, s, X, stiff, f);
    } else {  // forces vectorised (spring_gather.cpp), then scattered in spring order
      const Index nb = c.s1 - c.s0;
      spring_chunk_forces(m, c.s0, nb, X, F4, Stiff, stiff_bits);
      scatter(nb, S.I + c.s0, S.J + c.s0, F4, f);
    }
    if (c.ready > ready && code == kOk) {
      if (c.ready > init) {  // nodes without springs of their own
        return_forces(m, X, FE, f, init, c.ready);
        init = c.ready;
      }
      code = advance_range<Guard>(m, st, h, vmax2, kind, ready, c.ready, p.n0);
      ready = c.ready;
    }
  }
  if (init < p.n1) return_forces(m, X, FE, f, init, p.n1);
  for (const Index c : p.cross) {
    const Index s = c >= 0 ? c : -c - 1;
    double fx, fy, fz;
    if (!spring_force<Soft, Stiff>(S, s, X, stiff, fx, fy, fz)) continue;
    if (c >= 0) {
      const Index a = 3 * S.I[s];
      f[a] += fx;
      f[a + 1] += fy;
      f[a + 2] += fz;
    } else {
      const Index b = 3 * S.J[s];
      f[b] -= fx;
      f[b + 1] -= fy;
      f[b + 2] -= fz;
    }
  }
  if (code == kOk && ready < p.n1) code = advance_range<Guard>(m, st, h, vmax2, kind, ready, p.n1, p.n0);
  if constexpr (Stiff && !Soft) {
    double vs;
    std::memcpy(&vs, &stiff_bits, sizeof vs);
    stiff = std::max(stiff, vs);
  }
  p.stiff = stiff;
  p.code = code;
}

template <bool Guard>
void sweep_any(const Model& m, State& st, ThreadedStep& P, int t, double h, double vmax2, bool stiffening) {
  if (m.has_soft_springs)
    stiffening ? sweep<true, true, Guard>(m, st, P, t, h, vmax2)
               : sweep<true, false, Guard>(m, st, P, t, h, vmax2);
  else
    stiffening ? sweep<false, true, Guard>(m, st, P, t, h, vmax2)
               : sweep<false, false, Guard>(m, st, P, t, h, vmax2);
}

int combine(int r, int c) {
  return (c == kNonFinite || (c == kTooFast && r == kOk)) ? c : r;
}

}  // namespace

int threaded_substep(const Model& m, State& st, ThreadedStep& P, double h, double vmax2, bool guard,
                     bool stiffening) {
  auto phase1 = [&](int t) {
    guard ? sweep_any<true>(m, st, P, t, h, vmax2, stiffening)
          : sweep_any<false>(m, st, P, t, h, vmax2, stiffening);
  };
  P.pool.run(phase1);
  double stiff = 1.0;
  int r = kOk;
  for (const ThreadedStep::Part& p : P.part) {
    stiff = std::max(stiff, p.stiff);
    r = combine(r, p.code);
  }
  if (stiffening) st.stiffening = stiff;
  bool phase2 = false;
  if (r == kOk && P.has_boundary) {
    auto boundary = [&](int t) {
      ThreadedStep::Part& p = P.part[static_cast<std::size_t>(t)];
      const auto nb = static_cast<Index>(p.boundary.size());
      p.code2 = guard ? advance_nodes<true>(m, st, h, vmax2, p.boundary.data(), nb)
                      : advance_nodes<false>(m, st, h, vmax2, p.boundary.data(), nb);
    };
    P.pool.run(boundary);
    phase2 = true;
    for (const ThreadedStep::Part& p : P.part) r = combine(r, p.code2);
  }
  if (r != kOk)  // threads that finished their nodes undo them too (the others already did)
    for (const ThreadedStep::Part& p : P.part) {
      if (p.code == kOk) undo_range(m, st, h, P.kind.data(), p.n0, p.n1);
      if (phase2 && p.code2 == kOk)
        undo_symplectic(m, st, h, p.boundary.data(), static_cast<Index>(p.boundary.size()));
    }
  return r;
}

}  // namespace detail
}  // namespace medspring
