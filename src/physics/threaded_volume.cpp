// The threaded float sub-step of volumetric models (threaded_volume.hpp).
#include "threaded_volume.hpp"

#include <algorithm>
#include <cstring>

#include "medspring/core/check.hpp"
#include "medspring/physics/parallel.hpp"
#include "spring_f32.hpp"
#include "spring_gather.hpp"
#include "threaded_step.hpp"
#include "volume_f32.hpp"

namespace medspring {

bool VolumeSplit::matches(const Model& m, int threads_) const {
  return model == &m && f32 == static_cast<const void*>(m.volume_f32.get()) && node_count == m.num_nodes() &&
         threads() == threads_;
}

void VolumeSplit::partition(const Model& m, WorkerPool& pool) {
  const int threads_ = pool.size();
  require(
      m.volume_f32 != nullptr && m.volume_f32->springs.size() == static_cast<std::size_t>(m.num_springs()),
      m.name, ": the threaded float sub-step needs the float volume pass and float springs");
  const auto T = static_cast<std::size_t>(threads_);
  const std::size_t nr = m.volume_f32->rec.size(), ns = m.volume_f32->springs.size();
  // thread 0 also computes the slots: its share of tetrahedra is what is left of an equal share of the work
  const std::size_t work = kRecordCost * nr + kSpringCost * ns, share = work / T;
  const std::size_t first =
      share > kSpringCost * ns ? std::min(nr, (share - kSpringCost * ns) / kRecordCost) : 0;
  rec_begin.assign(T + 1, nr);
  rec_begin[0] = 0;
  for (std::size_t t = 1; t < T; ++t) {  // the rest in equal shares, multiples of eight (a vector's records)
    const std::size_t b = first + (nr - first) * (t - 1) / (T - 1);
    rec_begin[t] = std::min(nr, (b + 4) / 8 * 8);
  }
  rec_even.assign(T + 1, nr);
  for (std::size_t t = 0; t < T; ++t) rec_even[t] = std::min(nr, (nr * t / T + 4) / 8 * 8);
  mirrors.assign(4 * static_cast<std::size_t>(m.num_nodes()) * (T - 1), 0.0f);
  mirror_at.assign(T, nullptr);
  for (std::size_t t = 1; t < T; ++t)
    mirror_at[t] = mirrors.data() + 4 * static_cast<std::size_t>(m.num_nodes()) * (t - 1);
  model = &m;
  f32 = m.volume_f32.get();
  node_count = m.num_nodes();
  par = ParallelRecords{&pool, rec_even.data(), mirror_at.data(), threads_};
}

const ParallelRecords* VolumeSplit::records_for(State& st) {
  mirror_at[0] = st.volume_f32.data() + 4 * static_cast<std::size_t>(node_count);
  return &par;
}

int volume_threads(const Model& m, const StepSettings& s) {
  if (!threads_supported() || s.threads <= 1 || s.integrator != Integrator::SymplecticEuler || !m.volume_f32)
    return 1;
  const Index by_size = m.volume.size() / kMinVolumeRecordsPerThread;
  return static_cast<int>(std::max<Index>(1, std::min<Index>(std::min(s.threads, kMaxThreads), by_size)));
}

namespace detail {

int threaded_volume_substep(const Model& m, State& st, ThreadedStep& P, double h, double vmax2, bool guard) {
  const VolumeTermsF32& F = *m.volume_f32;
  VolumeSplit& S = P.volume;
  const Index n = m.num_nodes();
  const auto mirror_floats = 4 * static_cast<std::size_t>(n);
  float* u = st.volume_f32.data();
  S.records_for(st);
  auto mirror = [&](int t) { return S.mirror_at[static_cast<std::size_t>(t)]; };
  fill_displacements_f32(F, st.x.data(), u);
  auto forces = [&](int t) {
    float* g = mirror(t);
    std::memset(g, 0, sizeof(float) * mirror_floats);
    if (t == 0) spring_slots_f32(F.springs, u, reinterpret_cast<float*>(st.spring_force.data()), false);
    add_records_f32(F, u, g, S.rec_begin[static_cast<std::size_t>(t)],
                    S.rec_begin[static_cast<std::size_t>(t) + 1]);
  };
  P.pool.run(forces);
  // the node pass, each node's volume force the sum of its rows of the mirrors in thread order
  return node_pass_f32(m, st, h, vmax2, guard, S.mirror_at.data(), S.threads());
}

}  // namespace detail
}  // namespace medspring
