// The linear static response of a model at rest (issue 23, docs/linear-response.md): u = K0^-1 f over the
// free degrees of freedom, with K0 the tangent stiffness at the rest shape. This is the precomputed-response
// model of real-time surgery simulators (Bro-Nielsen & Cotin 1996; Cotin, Delingette & Ayache 1999): K0 is
// factored once; the response to a force on one node (three columns of K0^-1) is solved the first time that
// node is loaded and kept, so an update that loads k nodes costs 9 k N multiply-adds: no sub-steps, no
// iteration. It is quasi-static and linear: no inertia, no geometric or Duffing stiffening; step() uses it
// for Integrator::LinearStatic.
#pragma once

#include <cstddef>
#include <memory>
#include <span>

#include "medspring/core/types.hpp"
#include "medspring/physics/model.hpp"

namespace medspring {

class LinearResponse {
 public:
  /// Memory for cached response columns unless set otherwise (bytes); beyond it, updates that load an
  /// uncached node use one solve with the factor.
  static constexpr std::size_t kDefaultCacheBytes = std::size_t{256} << 20;
  /// Most loaded nodes an update sums from cached columns (more: one direct solve).
  static constexpr int kMaxColumnLoads = 256;

  /// Precision of the cached columns: float (the default) halves what an update streams; the sums, x and the
  /// direct solve stay double. Float columns are K0^-1's to a relative 6e-8 (docs/linear-response.md).
  enum class Precision { Float, Double };

  /// Factors the model's tangent stiffness at rest over its free nodes (return springs, volume and bending
  /// terms included). Throws InvalidInput naming the model when that tangent is not positive definite (rigid
  /// motion left free: support or pin nodes, or give return springs) and when the model is not finalized.
  explicit LinearResponse(const Model& model, std::size_t cache_bytes = kDefaultCacheBytes,
                          Precision columns = Precision::Float);
  ~LinearResponse();
  LinearResponse(const LinearResponse&) = delete;
  LinearResponse& operator=(const LinearResponse&) = delete;

  /// The model it was built for (identity: the address and the node count when built).
  bool built_for(const Model& model) const;
  Index num_nodes() const;
  Index free_dofs() const;
  /// Nonzeros of the factor's L (the cost of one direct solve is about 4 of these).
  std::size_t factor_nonzeros() const;
  double factor_ms() const;  // wall time of the factorisation
  /// Loaded free nodes above which an update uses one direct solve instead of the cached columns.
  int direct_threshold() const;

  /// Solves and caches the response columns of these nodes now (allocates), so that updates loading them do
  /// not. Fixed nodes have none (a force on a fixed node goes to the support). Throws InvalidInput naming an
  /// index out of range; stops caching where the cache is full.
  void precompute(std::span<const Index> nodes);
  bool cached(Index node) const;
  std::size_t cached_nodes() const;
  std::size_t cached_bytes() const;

  /// The compliance block C_ij = du_i / df_j (mm/N) of free nodes i and j (zero where one is fixed); solves
  /// and caches j's columns if needed. Symmetric: block(i, j) = block(j, i)^T.
  Mat3 block(Index i, Index j);

  /// x = x0 + K0^-1 f over the free nodes (fixed ones stay at x0; f's rows on them are ignored). Loaded free
  /// nodes up to direct_threshold() are summed from their columns (solved and cached on first use, unless the
  /// cache is full); more, or uncached ones with a full cache, take one solve with the factor into the
  /// caller's scratch `b` and `u` (sized free_dofs(); resized if not). Returns the loaded free nodes, or -1
  /// with x unchanged where a loaded row of f is not finite. No allocation once the loaded nodes are cached
  /// and the scratch is sized. Safe to call from several threads with distinct scratch.
  Index positions(const MatX3& f, MatX3& x, VecX& b, VecX& u);

  /// Inverted (or flat) tetrahedra of the model's volume (else compression) terms at x = positions(f): the
  /// count is count_inverted's exactly. Where every loaded node is cached, only the tetrahedra whose
  /// displacement gradient H_t could reach norm 1 under f are tested (a bound kept with each node's columns:
  /// |H_t|_F <= sum_j |f_j| h_tj; below 1, det(I + s H_t) > 0 along the whole load path); otherwise all of
  /// them.
  std::uint64_t count_inverted(const MatX3& f, const MatX3& x) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> p_;
};

}  // namespace medspring
