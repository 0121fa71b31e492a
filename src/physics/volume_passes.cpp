// The volume terms' force passes (volume_terms.hpp, compression_rows.hpp; issue 23,
// docs/volumetric-speed.md): the records through tet_record (tet_kernel.hpp) one at a time, or kTetLanes at a
// time through tet_records_simd (tet_simd.hpp) on a target with AVX2, the rest one at a time. Compiled with
// -ffp-contract=off (src/physics/CMakeLists.txt): GCC contracts a*b+c into FMAs differently in the scalar and
// the vector kernel, and without contraction the two are the same operations, so a pass gives the same
// numbers bit for bit with or without the vector path (on any target, and with volume_simd off).
#include <algorithm>
#include <atomic>
#include <cstddef>

#include "compression_rows.hpp"
#include "medspring/core/check.hpp"
#include "medspring/physics/volume_terms.hpp"
#include "tet_kernel.hpp"
#include "tet_simd.hpp"

namespace medspring {

namespace {

std::atomic<bool> g_volume_simd{true};

// The records of T through tet_record<0, false, Stiff, Local, Comp, Trace>: with the vector path (and a
// target with AVX2), kTetLanes records at a time through tet_records_simd (the same numbers bit for bit), the
// rest one by one.
template <bool Stiff, bool Local, bool Comp, bool Trace>
double volume_records(const VolumeTerms& T, const double* x, double* f, double* inc = nullptr,
                      const detail::CompTrace* tr = nullptr) {
  require(static_cast<Index>(T.packed.size()) == T.size(), "volume terms: not finalized");
  const detail::SpringParams none{nullptr, nullptr, nullptr, nullptr};
  const VolumeTerms::Packed* p = T.packed.data();
  const std::size_t nr = T.packed.size();
  double ss = 1.0, sv = 1.0;
  std::size_t i = 0;
#if defined(MEDSPRING_TET_SIMD)
  if (g_volume_simd.load(std::memory_order_relaxed)) {
    constexpr int W = detail::kTetLanes;
    using V = detail::TetVec<W>::V;
    V vsv = V{} + 1.0;
    for (; i + W <= nr; i += W)
      detail::tet_records_simd<W, Stiff, Local, Comp, Trace>(p + i, x, f, vsv, Local ? inc + i : nullptr, tr);
    for (int l = 0; l < W; ++l) sv = vsv[l] > sv ? vsv[l] : sv;  // as the scalar kernel's max
  }
#endif
  for (; i < nr; ++i)
    detail::tet_record<0, false, Stiff, Local, Comp, Trace>(p[i], none, x, f, ss, sv,
                                                            Local ? inc + i : nullptr, tr);
  return sv;
}

}  // namespace

double add_volume_forces(const VolumeTerms& T, const double* x, double* f, bool stiffening) {
  return stiffening ? volume_records<true, false, false, false>(T, x, f)
                    : volume_records<false, false, false, false>(T, x, f);
}

void add_volume_and_compression_forces(const VolumeTerms& T, const double* x, double* f) {
  if (T.kc.empty())
    volume_records<false, false, false, false>(T, x, f);
  else
    volume_records<false, false, true, false>(T, x, f);
}

double add_volume_forces_inc(const VolumeTerms& T, const double* x, double* f, double* inc) {
  return volume_records<true, true, false, false>(T, x, f, inc);
}

double add_volume_and_compression_forces_inc(const VolumeTerms& T, const double* x, double* f, double* inc,
                                             const double* s, double* trows, Index nodes) {
  require(static_cast<Index>(T.packed.size()) == T.size() && T.kc.size() == T.packed.size(),
          "volume terms: not finalized or no fused compression terms");
  std::fill(trows, trows + nodes, 0.0);
  const detail::CompTrace tr{s, trows};
  return volume_records<true, true, true, true>(T, x, f, inc, &tr);
}

namespace detail {

bool set_volume_simd(bool on) {
  return g_volume_simd.exchange(on);
}

bool volume_simd_compiled() {
#if defined(MEDSPRING_TET_SIMD)
  return true;
#else
  return false;
#endif
}

}  // namespace detail

}  // namespace medspring
