// The threaded float sub-step of volumetric models (issue 23; docs/threads.md, "Volumetric models"): the
// sub-steps without the stable step's bound (all but the frame's last) of a model with the float volume pass
// and float springs (gather_substep_f32), on StepSettings::threads threads.
//
// The calling thread fills the displacement mirror, then one join: it computes every spring's float slot and
// the first share of the tetrahedra, each other thread the next share, each tetrahedron's forces into its
// thread's own force mirror (4 floats a node). The shares are static, sized so that each thread has about
// the same work (VolumeSplit::kRecordCost, kSpringCost). After the join the calling thread sums the
// mirrors into each node's volume force (in thread order) within the node pass (slots, load, return spring,
// symplectic update), as the serial sub-step adds its one mirror.
//
// The frame's last sub-step (with the stable step's bound) and the inversion count at the frame's end share
// their tetrahedra in equal parts the same way (ParallelRecords, volume_f32.hpp); the rest of that sub-step
// (slots, local rows, node pass) stays on the calling thread.
//
// Why this split, and not one by nodes (measured, docs/threads.md): the node pass stays on one thread, so no
// cache line of positions, velocities, forces or slots is written by two cores; the other threads only read
// the displacements and write their own mirror. A split of nodes, tetrahedra and springs into spatial slabs
// made each thread's node pass 2x slower per node than the serial one on the 2,012-node kidney, because the
// kidney's node order is not spatial (the surface nodes come first) and nearly every line was shared.
//
// The shares are fixed: reruns with the same thread count are bit-identical; another thread count sums
// each node's volume force in another order (float rounding, about 1e-7 of the force).
#pragma once

#include <cstddef>
#include <vector>

#include "medspring/physics/integrators.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/physics/state.hpp"
#include "volume_f32.hpp"

namespace medspring {

struct ThreadedStep;

/// Volume records (tetrahedra) per thread below which the threaded float sub-step is not worth its join:
/// a model with fewer than threads x this many runs on fewer threads.
inline constexpr Index kMinVolumeRecordsPerThread = 2000;

/// The static shares of the threaded float sub-step (threaded_volume.hpp), held by ThreadedStep.
struct VolumeSplit {
  /// Work of one tetrahedron and of one spring slot, in common units: 5 : 2 balanced the two threads' times
  /// of the pass on the 2,012-node kidney (measured: 3 : 1, the serial passes' per-item times of about 21 and
  /// 7 cycles, left the thread with the slots about 10 % behind).
  static constexpr std::size_t kRecordCost = 5, kSpringCost = 2;
  const Model* model = nullptr;  // the model the shares were made for
  const void* f32 = nullptr;     // its float terms (Model::volume_f32)
  Index node_count = -1;
  std::vector<std::size_t> rec_begin;  // thread t's tetrahedra: [rec_begin[t], rec_begin[t + 1])
  std::vector<std::size_t> rec_even;   // the same in equal shares (the passes without the slots)
  std::vector<float> mirrors;          // the force mirrors of threads 1 .. T-1 (4 #N floats each)
  std::vector<float*> mirror_at;       // every thread's mirror in the step under way (0: the state's)
  ParallelRecords par;                 // the equal shares, for the frame's last pass and the count

  /// Points the shares at st's float scratch (its mirror is thread 0's) and returns them.
  const ParallelRecords* records_for(State& st);

  int threads() const { return static_cast<int>(rec_begin.size()) - 1; }
  bool matches(const Model& m, int threads) const;
  void partition(const Model& m, WorkerPool& pool);  // shares for pool.size() threads
};

/// Threads the float sub-step of m uses under s: 1 unless s asks for more, the build has threads, the
/// integrator is symplectic and m has the float volume pass; then s.threads, reduced so that every thread
/// gets at least kMinVolumeRecordsPerThread records. Deterministic.
int volume_threads(const Model& m, const StepSettings& s);

namespace detail {

/// One guarded symplectic sub-step of the float path (gather_substep_f32 without the stiffening) through the
/// pool and shares of P (P.volume matches m), coefficients st.step_coef refreshed for h by the caller,
/// st.volume_f32 the float scratch (prepare_step). Returns 0, or 1 (a velocity over v_max) / 2 (non-finite)
/// with the nodes already advanced restored, as gather_substep; st.f holds the node forces afterwards.
int threaded_volume_substep(const Model& m, State& st, ThreadedStep& P, double h, double vmax2, bool guard);

}  // namespace detail
}  // namespace medspring
