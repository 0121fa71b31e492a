#include "medspring/physics/linear_response.hpp"

#include <Eigen/SVD>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <vector>

#include "linear_static_step.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/forces.hpp"

namespace medspring {

struct LinearResponse::Impl {
  const Model* model = nullptr;
  Index n = 0;
  MatX3 x0;
  std::vector<std::uint8_t> fixed;
  std::vector<Index> dof;      // free DOF q -> flat index 3 a + d
  std::vector<Index> free_of;  // flat index -> free DOF q, -1 when fixed
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  std::size_t nnz_l = 0;
  double factor_ms = 0;
  int direct_threshold = 1;
  std::size_t cache_bytes = 0, column_bytes = 0;
  bool single = true;  // the columns in float (Precision::Float)
  // node j's response to unit forces along x, y, z (three flat 3N columns), and for the inversion count the
  // force at which each tetrahedron's displacement gradient could reach norm 1, sorted
  struct Column {
    std::unique_ptr<double[]> u;  // 9 N (Precision::Double)
    std::unique_ptr<float[]> uf;  // 9 N (Precision::Float: the default)
    std::vector<float> fstar;     // (#T) 1 / sqrt(sum_d |H_t(e_d)|_F^2), N (infinity where 0)
    std::vector<Index> by_fstar;  // tetrahedra in increasing fstar
  };
  std::unique_ptr<std::atomic<const Column*>[]> columns;
  std::vector<std::unique_ptr<Column>> storage;  // owns the columns (guarded by mutex)
  std::atomic<std::size_t> stored{0};
  std::mutex mutex;
  // the tetrahedra of the volume (else compression) terms, their rest edges' inverse E0^-1 (row-major 9)
  std::vector<Index> ta, tb, tc, td;
  std::vector<double> e0_inv;
  // the model's identity: its address, and fields that a different model at the same address would change
  Index springs = 0, terms = 0;
  const double* x0_data = nullptr;
  // Node j's columns, solved now if missing and the cache has room (nullptr otherwise).
  const Column* column(Index j) {
    const Column* c = columns[static_cast<std::size_t>(j)].load(std::memory_order_acquire);
    if (c || fixed[static_cast<std::size_t>(j)]) return c;
    std::lock_guard<std::mutex> lock(mutex);
    c = columns[static_cast<std::size_t>(j)].load(std::memory_order_relaxed);
    if (c) return c;
    if ((stored.load(std::memory_order_relaxed) + 1) * column_bytes > cache_bytes) return nullptr;
    const std::size_t N3 = 3 * static_cast<std::size_t>(n);
    auto col = std::make_unique<Column>();
    col->u = std::make_unique<double[]>(3 * N3);
    VecX e = VecX::Zero(static_cast<Index>(dof.size()));
    for (int d = 0; d < 3; ++d) {
      e.setZero();
      e[free_of[static_cast<std::size_t>(3 * j + d)]] = 1.0;
      const VecX u = ldlt.solve(e);
      double* out = col->u.get() + static_cast<std::size_t>(d) * N3;
      std::fill(out, out + N3, 0.0);
      for (std::size_t r = 0; r < dof.size(); ++r) out[dof[r]] = u[static_cast<Index>(r)];
    }
    // |H_t(f)|_F <= |f| sqrt(sum_d |H_t(e_d)|_F^2), H_t = dE E0^-1 the displacement gradient of tetrahedron t
    const std::size_t nt = ta.size();
    col->fstar.resize(nt);
    col->by_fstar.resize(nt);
    for (std::size_t t = 0; t < nt; ++t) {
      const Index q[4] = {ta[t], tb[t], tc[t], td[t]};
      double h2 = 0;
      for (int d = 0; d < 3; ++d) {
        const double* u = col->u.get() + static_cast<std::size_t>(d) * N3;
        const double* u0 = u + 3 * static_cast<std::size_t>(q[0]);
        double dE[3][3];  // dE[k][c]: edge k's displacement, component c
        for (int k = 0; k < 3; ++k)
          for (int a = 0; a < 3; ++a) dE[k][a] = u[3 * static_cast<std::size_t>(q[k + 1]) + a] - u0[a];
        const double* inv = e0_inv.data() + 9 * t;  // E0^-1 (rows r, columns = edges k)
        for (int a = 0; a < 3; ++a)
          for (int r = 0; r < 3; ++r) {
            double h = 0;  // H[a][r] = sum_k dE[k][a] inv[k][r], E0 with the edges as columns
            for (int k = 0; k < 3; ++k) h += dE[k][a] * inv[3 * k + r];
            h2 += h * h;
          }
      }
      col->fstar[t] =
          h2 > 0 ? static_cast<float>(1.0 / std::sqrt(h2)) : std::numeric_limits<float>::infinity();
      col->by_fstar[t] = static_cast<Index>(t);
    }
    std::sort(col->by_fstar.begin(), col->by_fstar.end(), [&](Index a, Index b) {
      return col->fstar[static_cast<std::size_t>(a)] < col->fstar[static_cast<std::size_t>(b)];
    });
    if (single) {  // the columns in float: half the bytes an update streams (docs/linear-response.md)
      col->uf = std::make_unique<float[]>(3 * N3);
      for (std::size_t q = 0; q < 3 * N3; ++q) col->uf[q] = static_cast<float>(col->u[q]);
      col->u.reset();
    }
    c = col.get();
    storage.push_back(std::move(col));
    stored.fetch_add(1, std::memory_order_relaxed);
    columns[static_cast<std::size_t>(j)].store(c, std::memory_order_release);
    return c;
  }
};

LinearResponse::LinearResponse(const Model& m, std::size_t cache_bytes, Precision columns)
    : p_(std::make_unique<Impl>()) {
  require(m.finalized, m.name, ": model is not finalized (call finalize or ModelBuilder::build)");
  Impl& P = *p_;
  P.model = &m;
  P.n = m.num_nodes();
  P.springs = m.num_springs();
  P.terms = m.volume.size() + m.compression.size();
  P.x0_data = m.x0.data();
  P.x0 = m.x0;
  P.fixed = m.fixed;
  P.cache_bytes = cache_bytes;
  P.single = columns == Precision::Float;
  const std::size_t N3 = 3 * static_cast<std::size_t>(P.n);
  P.free_of.assign(N3, -1);
  for (Index a : m.free_nodes)
    for (int d = 0; d < 3; ++d) {
      P.free_of[static_cast<std::size_t>(3 * a + d)] = static_cast<Index>(P.dof.size());
      P.dof.push_back(3 * a + d);
    }
  P.columns = std::make_unique<std::atomic<const Impl::Column*>[]>(static_cast<std::size_t>(P.n));
  for (Index j = 0; j < P.n; ++j) P.columns[static_cast<std::size_t>(j)].store(nullptr);
  P.storage.reserve(static_cast<std::size_t>(P.n));
  const Index nf = static_cast<Index>(P.dof.size());
  if (nf > 0) {
    const auto t0 = std::chrono::steady_clock::now();
    const Eigen::SparseMatrix<double> K =
        tangent_stiffness(m, m.x0, {.clamp_transverse = false, .include_return = true});
    std::vector<Eigen::Triplet<double>> T;
    T.reserve(static_cast<std::size_t>(K.nonZeros()));
    for (int c = 0; c < K.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator e(K, c); e; ++e) {
        const Index r = P.free_of[static_cast<std::size_t>(e.row())];
        const Index cc = P.free_of[static_cast<std::size_t>(e.col())];
        if (r >= 0 && cc >= 0) T.emplace_back(r, cc, e.value());
      }
    Eigen::SparseMatrix<double> Kff(nf, nf);
    Kff.setFromTriplets(T.begin(), T.end());
    P.ldlt.compute(Kff);
    const bool pd = P.ldlt.info() == Eigen::Success && (P.ldlt.vectorD().array() > 0).all();
    if (!pd)
      throw InvalidInput(cat(m.name,
                             ": linear_static: the tangent stiffness at rest is not positive definite "
                             "over the free nodes (rigid motion left free? support or pin nodes, or "
                             "give the nodes return springs)"));
    P.factor_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    P.nnz_l = static_cast<std::size_t>(P.ldlt.matrixL().nestedExpression().nonZeros());
    // one solve: a forward and a backward sweep over L (2 flops a nonzero each) and the permutations;
    // one cached node: 3 N x 3 multiply-adds (2 flops each)
    const double solve = 4.0 * static_cast<double>(P.nnz_l) + 8.0 * static_cast<double>(nf);
    P.direct_threshold =
        std::clamp(static_cast<int>(solve / (18.0 * static_cast<double>(P.n))), 1, kMaxColumnLoads);
  }
  // inversion candidates (volume terms, else compression terms: the same tetrahedra)
  if (m.volume.size() > 0) {
    P.ta = m.volume.a, P.tb = m.volume.b, P.tc = m.volume.c, P.td = m.volume.d;
  } else if (m.compression.size() > 0) {
    P.ta = m.compression.a, P.tb = m.compression.b, P.tc = m.compression.c, P.td = m.compression.d;
  }
  const std::size_t nt = P.ta.size();
  P.column_bytes =
      3 * N3 * (P.single ? sizeof(float) : sizeof(double)) + nt * (sizeof(float) + sizeof(Index));
  P.e0_inv.resize(9 * nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const Index q[4] = {P.ta[t], P.tb[t], P.tc[t], P.td[t]};
    Mat3 E;  // the rest edges as columns (positive volume: finalize checked it)
    for (int k = 0; k < 3; ++k) E.col(k) = (m.x0.row(q[k + 1]) - m.x0.row(q[0])).transpose();
    const Mat3 inv = E.inverse();
    for (int k = 0; k < 3; ++k)
      for (int r = 0; r < 3; ++r) P.e0_inv[9 * t + static_cast<std::size_t>(3 * k + r)] = inv(k, r);
  }
}

LinearResponse::~LinearResponse() = default;

bool LinearResponse::built_for(const Model& m) const {
  return p_->model == &m && p_->n == m.num_nodes() && p_->springs == m.num_springs() &&
         p_->terms == m.volume.size() + m.compression.size() && p_->x0_data == m.x0.data();
}
Index LinearResponse::num_nodes() const {
  return p_->n;
}
Index LinearResponse::free_dofs() const {
  return static_cast<Index>(p_->dof.size());
}
std::size_t LinearResponse::factor_nonzeros() const {
  return p_->nnz_l;
}
double LinearResponse::factor_ms() const {
  return p_->factor_ms;
}
int LinearResponse::direct_threshold() const {
  return p_->direct_threshold;
}

void LinearResponse::precompute(std::span<const Index> nodes) {
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const Index j = nodes[k];
    require(j >= 0 && j < p_->n, "linear response: precompute: nodes[", k, "] = ", j, " is out of range [0, ",
            p_->n, ")");
    if (!p_->column(j) && !p_->fixed[static_cast<std::size_t>(j)]) return;  // the cache is full
  }
}

bool LinearResponse::cached(Index node) const {
  return node >= 0 && node < p_->n &&
         p_->columns[static_cast<std::size_t>(node)].load(std::memory_order_acquire) != nullptr;
}
std::size_t LinearResponse::cached_nodes() const {
  return p_->stored.load();
}
std::size_t LinearResponse::cached_bytes() const {
  return p_->stored.load() * p_->column_bytes;
}

Mat3 LinearResponse::block(Index i, Index j) {
  require(i >= 0 && i < p_->n && j >= 0 && j < p_->n, "linear response: block(", i, ", ", j,
          "): a node is out of range [0, ", p_->n, ")");
  Mat3 C = Mat3::Zero();
  if (p_->fixed[static_cast<std::size_t>(i)] || p_->fixed[static_cast<std::size_t>(j)]) return C;
  const Impl::Column* col = p_->column(j);
  if (col) {
    const std::size_t N3 = 3 * static_cast<std::size_t>(p_->n);
    for (int e = 0; e < 3; ++e)
      for (int d = 0; d < 3; ++d) {
        const std::size_t q =
            static_cast<std::size_t>(d) * N3 + 3 * static_cast<std::size_t>(i) + static_cast<std::size_t>(e);
        C(e, d) = col->uf ? static_cast<double>(col->uf[q]) : col->u[q];
      }
    return C;
  }
  VecX b = VecX::Zero(free_dofs());  // the cache is full: solve j's columns without keeping them
  for (int d = 0; d < 3; ++d) {
    b.setZero();
    b[p_->free_of[static_cast<std::size_t>(3 * j + d)]] = 1.0;
    const VecX u = p_->ldlt.solve(b);
    for (int e = 0; e < 3; ++e) C(e, d) = u[p_->free_of[static_cast<std::size_t>(3 * i + e)]];
  }
  return C;
}

namespace {
// The loaded free nodes of f (rows not all zero): their count, the first kMaxColumnLoads of them in idx; -1
// where a loaded row is not finite.
int loaded_nodes(const double* F, const std::vector<std::uint8_t>& fixed, Index n, Index* idx) {
  int k = 0;
  for (Index j = 0; j < n; ++j) {
    const double* fj = F + 3 * static_cast<std::size_t>(j);
    if ((fj[0] == 0.0 && fj[1] == 0.0 && fj[2] == 0.0) || fixed[static_cast<std::size_t>(j)]) continue;
    if (!std::isfinite(fj[0] + fj[1] + fj[2])) return -1;
    if (k < LinearResponse::kMaxColumnLoads) idx[k] = j;
    ++k;
  }
  return k;
}
}  // namespace

Index LinearResponse::positions(const MatX3& f, MatX3& x, VecX& b, VecX& u) {
  Impl& P = *p_;
  require(f.rows() == P.n && x.rows() == P.n, "linear response: f and x must have ", P.n, " rows");
  const std::size_t N3 = 3 * static_cast<std::size_t>(P.n);
  const double* F = f.data();
  Index idx[kMaxColumnLoads];
  const int k = loaded_nodes(F, P.fixed, P.n, idx);
  if (k < 0) return -1;
  x = P.x0;
  if (k == 0) return 0;
  double* X = x.data();
  // the cached columns where they can take every loaded node (solved now where missing and the cache has
  // room)
  bool columns = k <= P.direct_threshold;
  const Impl::Column* c[kMaxColumnLoads];
  for (int a = 0; a < k && columns; ++a) {
    c[a] = P.column(idx[a]);
    columns = c[a] != nullptr;
  }
  if (columns) {
    // in blocks of X that stay in the L1 cache while every loaded node's columns stream through
    constexpr std::size_t kBlock = 768;
    auto sum = [&](auto column_of) {
      for (std::size_t k0 = 0; k0 < N3; k0 += kBlock) {
        const std::size_t k1 = std::min(N3, k0 + kBlock);
        for (int a = 0; a < k; ++a) {
          const double* fj = F + 3 * static_cast<std::size_t>(idx[a]);
          const double fx = fj[0], fy = fj[1], fz = fj[2];
          const auto* cx = column_of(*c[a]);
          const auto* cy = cx + N3;
          const auto* cz = cy + N3;
          for (std::size_t q = k0; q < k1; ++q) X[q] += fx * cx[q] + fy * cy[q] + fz * cz[q];
        }
      }
    };
    if (P.single)
      sum([](const Impl::Column& col) { return static_cast<const float*>(col.uf.get()); });
    else
      sum([](const Impl::Column& col) { return static_cast<const double*>(col.u.get()); });
    return k;
  }
  const Index nf = free_dofs();
  if (b.size() != nf) b.resize(nf);
  if (u.size() != nf) u.resize(nf);
  for (Index q = 0; q < nf; ++q) b[q] = F[P.dof[static_cast<std::size_t>(q)]];
  u = P.ldlt.solve(b);
  for (Index q = 0; q < nf; ++q) X[P.dof[static_cast<std::size_t>(q)]] += u[q];
  return k;
}

namespace {
bool inverted_at(const double* X, const Index q[4]) {  // count_inverted's test
  const double* a = X + 3 * static_cast<std::ptrdiff_t>(q[0]);
  double e[3][3];
  for (int r = 0; r < 3; ++r) {
    const double* p = X + 3 * static_cast<std::ptrdiff_t>(q[r + 1]);
    for (int d = 0; d < 3; ++d) e[r][d] = p[d] - a[d];
  }
  const double v6 = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) +
                    e[0][1] * (e[1][2] * e[2][0] - e[1][0] * e[2][2]) +
                    e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
  return !(v6 > 0);
}
}  // namespace

std::uint64_t LinearResponse::count_inverted(const MatX3& f, const MatX3& x) const {
  const Impl& P = *p_;
  require(f.rows() == P.n && x.rows() == P.n, "linear response: f and x must have ", P.n, " rows");
  const std::size_t nt = P.ta.size();
  if (nt == 0) return 0;
  const double* X = x.data();
  const double* F = f.data();
  // the loaded free nodes and their columns; without them all, every tetrahedron is tested
  Index idx[kMaxColumnLoads];
  const Impl::Column* c[kMaxColumnLoads];
  double reach[kMaxColumnLoads];
  const int k = loaded_nodes(F, P.fixed, P.n, idx);
  bool columns = k >= 0 && k <= kMaxColumnLoads;
  for (int a = 0; a < k && columns; ++a) {
    c[a] = P.columns[static_cast<std::size_t>(idx[a])].load(std::memory_order_acquire);
    columns = c[a] != nullptr;
  }
  std::uint64_t inverted = 0;
  if (!columns) {
    for (std::size_t t = 0; t < nt; ++t) {
      const Index q[4] = {P.ta[t], P.tb[t], P.tc[t], P.td[t]};
      inverted += inverted_at(X, q);
    }
    return inverted;
  }
  // |H_t|_F <= sum_j |f_j| / fstar_tj: below 1 (with a margin for rounding) no corner motion along the load
  // path s f, s in [0, 1], makes det(I + s H_t) vanish. Some term of a sum of k terms that reaches it is at
  // least 1 / k: tetrahedron t is tested where |f_j| k / fstar_tj >= 1 - 1e-3 for some j, from the first such
  // j.
  const double scale = static_cast<double>(k) / (1.0 - 1e-3);
  for (int a = 0; a < k; ++a) {
    const double* fj = F + 3 * static_cast<std::size_t>(idx[a]);
    reach[a] = scale * std::sqrt(fj[0] * fj[0] + fj[1] * fj[1] + fj[2] * fj[2]);
  }
  for (int a = 0; a < k; ++a) {
    for (Index t : c[a]->by_fstar) {
      const auto v = static_cast<std::size_t>(t);
      if (static_cast<double>(c[a]->fstar[v]) > reach[a]) break;
      bool earlier = false;  // tested from an earlier loaded node already
      for (int e = 0; e < a && !earlier; ++e) earlier = static_cast<double>(c[e]->fstar[v]) <= reach[e];
      if (earlier) continue;
      const Index q[4] = {P.ta[v], P.tb[v], P.tc[v], P.td[v]};
      inverted += inverted_at(X, q);
    }
  }
  return inverted;
}

namespace detail {

void prepare_linear_static(const Model& m, State& st) {
  if (!st.linear || !st.linear->built_for(m)) st.linear = std::make_shared<LinearResponse>(m);
  const Index nf = st.linear->free_dofs();
  if (st.linear_b.size() != nf) st.linear_b.setZero(nf);
  if (st.linear_u.size() != nf) st.linear_u.setZero(nf);
}

StepStatus linear_static_step(const Model& m, State& st, const StepSettings& s,
                              const std::vector<PointLoad>* loads, const SubstepForce* per_substep) {
  StepStatus status;
  if (!st.linear || !st.linear->built_for(m) || st.linear_b.size() != st.linear->free_dofs())
    prepare_linear_static(m, st);  // a state not prepared for this integrator: once
  const double t0 = st.t;
  if (loads) accumulate_loads(*loads, t0, st.f_ext);
  if (per_substep) per_substep->fn(per_substep->ctx, st, t0);
  st.t = t0 + s.dt;
  ++st.frames;
  st.v = st.x;  // the frame's start, for its mean velocity
  if (st.linear->positions(st.f_ext, st.x, st.linear_b, st.linear_u) < 0) {
    // a non-finite force: the positions stay where they are; the frame is reported failed
    ++st.warnings.nonfinite;
    ++st.warnings.failed;
    st.v.setZero();
    status.code = StepCode::Failed;
    return status;
  }
  const double rate = 1.0 / s.dt;
  st.v = (st.x - st.v) * rate;
  st.stiffening = 1.0;
  status.substeps = 1;
  ++st.substeps;
  if (m.volume.size() > 0 || m.compression.size() > 0)
    st.warnings.inverted_elements += st.linear->count_inverted(st.f_ext, st.x);
  return status;
}

}  // namespace detail

}  // namespace medspring
