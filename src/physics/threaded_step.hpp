// The fused node-range step of large models (docs/threads.md, "The fused node-range step"): the
// threaded symplectic step, and the serial step of models beyond the gather pass. Thread t owns the nodes
// [node_begin[t], node_begin[t+1]). In one sweep over its inner springs (both ends among its nodes, in
// spring order, in chunks) it initialises each node's force with its load and return spring just before
// the node's first spring, scatters the springs, and advances every free node as soon as its last
// spring is in (its force is complete and no later spring reads its position), while the node's data
// are still in cache. The springs that cross to another thread's nodes follow (its own end only); their
// end nodes ("boundary" nodes) are advanced after a join. Each node's force therefore has the same terms
// in the same order as in the two-pass step (return spring, inner springs in spring order, crossing
// springs): one thread is bit-identical to the serial scatter pass + node pass, and reruns with the same
// thread count are bit-identical.
#pragma once

#include <cstdint>
#include <vector>

#include "medspring/physics/model.hpp"
#include "medspring/physics/parallel.hpp"
#include "medspring/physics/stability.hpp"
#include "medspring/physics/state.hpp"
#include "threaded_volume.hpp"

namespace medspring {

struct ThreadedStep {
  explicit ThreadedStep(int threads) : pool(threads), part(static_cast<std::size_t>(threads)) {}
  WorkerPool pool;
  const Model* model = nullptr;  // the model (and arrays) the partition was made for
  const double* x0 = nullptr;
  const Index* spring_i = nullptr;
  Index nodes = -1, springs = -1;
  /// A run of at most kChunk consecutive inner springs [s0, s1); before it the forces of nodes
  /// [.., init) are initialised, after it the free interior nodes [.., ready) are advanced.
  struct Chunk {
    Index s0, s1, init, ready;
  };
  struct alignas(64) Part {
    Index n0 = 0, n1 = 0;         // the thread's nodes
    std::vector<Chunk> chunks;    // its inner springs, in spring order
    std::vector<Index> cross;     // s: it owns end i; -(s + 1): it owns end j
    std::vector<Index> boundary;  // its free nodes on a crossing spring (advanced after the join)
    double stiff = 1.0;           // max kappa/k of its springs in the last substep
    int code = 0, code2 = 0;      // outcome of its interior (phase 1) and boundary (phase 2) nodes
  };
  std::vector<Part> part;
  /// The threaded float sub-step's partition (threaded_volume.hpp) of volumetric models, on this pool.
  VolumeSplit volume;
  /// Per node: 0 free interior node, 1 fixed, 2 free boundary node.
  std::vector<std::uint8_t> kind;
  bool has_boundary = false;
  /// Not the threaded step's: the stable step's tangent refresh of models with volume or compression terms
  /// (integrators.cpp, docs/volumetric-stable-step.md), kept here because the State
  /// holds this handle already (a copied State starts without a reference, as it starts without a partition).
  struct TangentRefresh {
    TangentScratch scratch;   // the estimate under way: its snapshot of x, Lanczos vectors, tridiagonal
    double s_ref = 0.0;       // 1.05^2 x the Lanczos omega^2 at the reference state / omega_rest^2
    double b_ref = 0.0;       // the frame's growth bound (State::stiffening) at the reference state
    std::uint64_t frame = 0;  // State::frames when its state was taken
    std::uint64_t tried = 0;  // State::frames + 1 when the last estimate was started (0: never)
    bool valid = false;       // the reference (s_ref, b_ref, frame) is in use
    bool pending = false;     // an estimate is under way on scratch.x, taken at frame_snap with bound b_snap
    double b_snap = 0.0;
    std::uint64_t frame_snap = 0;
    void drop() { valid = pending = false; }  // a rollback or a failed frame: start again
  } tangent;

  bool matches(const Model& m) const {
    return model == &m && x0 == m.x0.data() && spring_i == m.springs.i.data() && nodes == m.num_nodes() &&
           springs == m.num_springs();
  }
  void partition(const Model& m);
};

namespace detail {

/// Springs per chunk of the fused sweep (the data of a chunk's nodes stay in L1/L2 until they advance).
inline constexpr Index kChunk = 256;

/// The fused step applies to m: no bending, volume or compression terms.
inline bool fused_step_applies(const Model& m) {
  return m.bending.size() == 0 && m.volume.size() == 0 && m.compression.size() == 0 && m.thin.size() == 0;
}

/// One guarded symplectic substep (§2.1, §2.5) through the partition P, coefficients st.step_coef
/// refreshed for h by the caller. With `stiffening`, st.stiffening = max(1, max_s kappa_s / k_s). Returns
/// 0 (ok), 1 (a velocity over v_max) or 2 (non-finite), every node advanced in this substep restored.
/// st.f holds the node forces afterwards (after a failure, scratch).
int threaded_substep(const Model& m, State& st, ThreadedStep& P, double h, double vmax2, bool guard,
                     bool stiffening);

}  // namespace detail
}  // namespace medspring
