#include "medspring/local/distributed_overlay.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "medspring/core/check.hpp"

namespace medspring {

DistributedOverlay::DistributedOverlay(Adjacency adj, double k_loc, std::vector<std::uint8_t> fixed,
                                       Index capacity)
    : adj_(std::move(adj)), k_loc_(k_loc), model_fixed_(std::move(fixed)) {
  const Index n = adj_.num_nodes();
  require(std::isfinite(k_loc) && k_loc > 0, "local overlay (distributed load): k_loc must be > 0 N/mm (got ",
          k_loc, ")");
  require(model_fixed_.empty() || static_cast<Index>(model_fixed_.size()) == n,
          "local overlay (distributed load): model-fixed flags have ", model_fixed_.size(),
          " entries, the surface has ", n, " nodes");
  require(capacity >= 1, "local overlay (distributed load): capacity must be >= 1 (got ", capacity, ")");
  mark_.assign(static_cast<std::size_t>(std::max<Index>(n, 0)), -1);
  reserve(capacity);
}

void DistributedOverlay::reserve(Index nodes) {
  if (nodes <= capacity_) return;
  capacity_ = std::max(nodes, 2 * capacity_);  // at least doubled: a handful of growths per run at most
  const auto c = static_cast<std::size_t>(capacity_);
  last_.reserve(c);
  nodes_.reserve(c);
  fixed_.reserve(c);
  free_.reserve(c);
  L_.resize(c * c);
  rhs_.resize(3 * c);
  MatX3 U = MatX3::Zero(capacity_, 3);
  U.topRows(P_) = U_.topRows(P_);
  U_ = std::move(U);
}

Index DistributedOverlay::patch_size_of(const std::vector<Index>& loaded) {
  const Index n = adj_.num_nodes();
  Index P = 0;
  const auto add = [&](Index g) {
    if (mark_[static_cast<std::size_t>(g)] < 0) mark_[static_cast<std::size_t>(g)] = P++;
  };
  for (Index g : loaded)  // every node checked before any is marked: a refusal leaves the marks clean
    require(g >= 0 && g < n, "local overlay (distributed load): loaded node ", g, " out of range [0, ", n,
            ")");
  for (Index g : loaded) add(g);
  for (Index g : loaded)
    for (const Index* q = adj_.begin(g); q != adj_.end(g); ++q) add(*q);
  for (Index g : loaded) {  // unmark: the loaded nodes and their neighbours
    mark_[static_cast<std::size_t>(g)] = -1;
    for (const Index* q = adj_.begin(g); q != adj_.end(g); ++q) mark_[static_cast<std::size_t>(*q)] = -1;
  }
  return P;
}

bool DistributedOverlay::prepare(const std::vector<Index>& loaded) {
  if (prepared_ && loaded == last_) return ok_;  // the same loaded set: the factor holds (topology only)
  const Index size = patch_size_of(loaded);      // validates the nodes
  if (size > capacity_) {                        // a patch larger than any before: the one allocation
    ++growths_;
    reserve(size);
  }
  last_.assign(loaded.begin(), loaded.end());  // within the capacity: no allocation
  prepared_ = true;
  ok_ = false;
  nodes_.clear();
  const auto add = [&](Index g) {
    if (mark_[static_cast<std::size_t>(g)] >= 0) return;
    mark_[static_cast<std::size_t>(g)] = static_cast<Index>(nodes_.size());
    nodes_.push_back(g);
  };
  for (Index g : loaded) add(g);  // the loaded nodes first, as given
  const auto ring = static_cast<std::ptrdiff_t>(nodes_.size());
  for (Index g : loaded)
    for (const Index* q = adj_.begin(g); q != adj_.end(g); ++q) add(*q);
  std::sort(nodes_.begin() + ring, nodes_.end());  // the ring in index order (loaded_nodes_patch)
  P_ = static_cast<Index>(nodes_.size());
  for (Index a = 0; a < P_; ++a) mark_[static_cast<std::size_t>(nodes_[a])] = a;
  // D-15: a node with a neighbour outside the patch, or model-fixed, is fixed
  fixed_.assign(static_cast<std::size_t>(P_), 0);
  free_.clear();
  for (Index a = 0; a < P_; ++a) {
    const Index g = nodes_[a];
    bool fx = !model_fixed_.empty() && model_fixed_[static_cast<std::size_t>(g)] != 0;
    for (const Index* q = adj_.begin(g); q != adj_.end(g) && !fx; ++q)
      fx = mark_[static_cast<std::size_t>(*q)] < 0;
    fixed_[static_cast<std::size_t>(a)] = fx ? 1 : 0;
    if (!fx) free_.push_back(a);
  }
  nf_ = static_cast<Index>(free_.size());
  // L_ff (§6.2, D-16: K = L (x) I3): a free node's neighbours are all in the patch, so its diagonal is
  // k_loc x its degree; -k_loc per free-free edge. free index of local node a: mark_ reused as a scratch.
  for (Index f = 0; f < nf_; ++f) mark_[static_cast<std::size_t>(nodes_[free_[f]])] = P_ + f;
  std::fill(L_.begin(), L_.begin() + nf_ * nf_, 0.0);
  for (Index f = 0; f < nf_; ++f) {
    const Index g = nodes_[free_[f]];
    L_[static_cast<std::size_t>(f * nf_ + f)] = k_loc_ * static_cast<double>(adj_.degree(g));
    for (const Index* q = adj_.begin(g); q != adj_.end(g); ++q) {
      const Index h = mark_[static_cast<std::size_t>(*q)] - P_;
      if (h >= 0) L_[static_cast<std::size_t>(f * nf_ + h)] -= k_loc_;
    }
  }
  for (Index a = 0; a < P_; ++a) mark_[static_cast<std::size_t>(nodes_[a])] = -1;
  U_.topRows(P_).setZero();
  ok_ = nf_ > 0 && factor();
  return ok_;
}

// In-place dense Cholesky L_ff = C C^T (row-major, lower triangle), allocation-free; §6.4's singularity test
// on the pivots (the Schur complements, LDLT's D).
bool DistributedOverlay::factor() {
  const Index n = nf_;
  double* A = L_.data();
  double max_diag = 0;
  for (Index j = 0; j < n; ++j) max_diag = std::max(max_diag, A[j * n + j]);
  const double tol = 1e-12 * max_diag;
  for (Index j = 0; j < n; ++j) {
    double* Aj = A + j * n;
    double d = Aj[j];
    for (Index k = 0; k < j; ++k) d -= Aj[k] * Aj[k];
    if (!(d > tol)) return false;
    const double c = std::sqrt(d);
    Aj[j] = c;
    for (Index i = j + 1; i < n; ++i) {
      double* Ai = A + i * n;
      double s = Ai[j];
      for (Index k = 0; k < j; ++k) s -= Ai[k] * Aj[k];
      Ai[j] = s / c;
    }
  }
  return true;
}

void DistributedOverlay::solve(const MatX3& F) {
  if (!ok_) {
    U_.topRows(P_).setZero();
    return;
  }
  const Index n = nf_;
  const double* C = L_.data();
  double* y = rhs_.data();
  for (Index i = 0; i < n; ++i) {  // C y = F_f, the three axes together
    const Index g = nodes_[free_[i]];
    for (int al = 0; al < 3; ++al) {
      double s = F(g, al);
      for (Index k = 0; k < i; ++k) s -= C[i * n + k] * y[3 * k + al];
      y[3 * i + al] = s / C[i * n + i];
    }
  }
  for (Index i = n - 1; i >= 0; --i)  // C^T u = y
    for (int al = 0; al < 3; ++al) {
      double s = y[3 * i + al];
      for (Index k = i + 1; k < n; ++k) s -= C[k * n + i] * y[3 * k + al];
      y[3 * i + al] = s / C[i * n + i];
    }
  for (Index f = 0; f < n; ++f)
    for (int al = 0; al < 3; ++al) U_(free_[f], al) = y[3 * f + al];  // fixed rows stay 0
}

}  // namespace medspring
