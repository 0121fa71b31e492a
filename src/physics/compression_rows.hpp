// Scratch sizes of the compression terms' stable-step bound (issue 23, compression_terms.hpp): internal to
// the physics layer (State::stiff_rows is sized by them).
#pragma once

#include <cstdint>

#include "medspring/core/types.hpp"
#include "medspring/physics/compression_terms.hpp"
#include "medspring/physics/volume_terms.hpp"

namespace medspring {

/// Doubles of scratch per node that the stable-step bound of add_compression_forces needs (a symmetric 3x3
/// block each).
inline constexpr Index kCompressionRowsPerNode = 6;

/// Size of State::stiff_rows for a model with `volume_terms` volume and `compression_terms` compression terms
/// on `nodes` nodes: the volume terms' local rule needs #N rows and #T increments, the compression bound
/// 6 #N for its blocks, #N for their traces and #N for m_i^-1/2 after them (all live at once: the rule's gate
/// counts the compression bound).
inline Index stiff_rows_size(Index nodes, Index volume_terms, Index compression_terms) {
  if (volume_terms == 0 && compression_terms == 0) return 0;
  return nodes + volume_terms + (compression_terms > 0 ? (kCompressionRowsPerNode + 2) * nodes : 0);
}

/// The compression bound of the step's last sub-step (src/physics/forces.cpp) in two stages: the forces
/// (added to f; none when f is null, the volume pass having fused them) and the cheap bound max_i tr B_i (the
/// blocks' traces, `rows`: #N doubles), which is at most 3x the block bound and at least it ...
double add_compression_forces_trace(const CompressionTerms& T, const double* x, double* f, const double* mass,
                                    const std::uint8_t* fixed, double* rows, Index nodes);
/// ... and the block bound alone, without the forces (`rows`: kCompressionRowsPerNode #N doubles), computed
/// only where the step's sub-step count depends on where in [trace / 3, trace] it lies.
double compression_block_bound(const CompressionTerms& T, const double* x, const double* mass,
                               const std::uint8_t* fixed, double* rows, Index nodes);
/// add_volume_forces_inc (volume_terms.hpp) with the fused compression terms (VolumeTerms::kc not empty,
/// fuse_compression_terms) in the same pass: their forces, as add_volume_and_compression_forces adds them,
/// and the traces of their bound's 3x3 blocks into trows (#N, zeroed first; `s`: m_i^-1/2 per node, 0 on a
/// fixed node), the numbers add_compression_forces_trace accumulates, to rounding. The step's last sub-step
/// then needs a pass over the compression terms only where the blocks themselves decide its sub-step count.
double add_volume_and_compression_forces_inc(const VolumeTerms& T, const double* x, double* f, double* inc,
                                             const double* s, double* trows, Index nodes);
namespace detail {
/// The volume passes (add_volume_forces, add_volume_and_compression_forces, add_volume_forces_inc,
/// add_volume_and_compression_forces_inc; volume_passes.cpp) run kTetLanes records at a time where the target
/// has AVX2 (tet_simd.hpp, volume_simd_compiled) unless this switch is off (on by default): the same numbers
/// bit for bit either way. For the tests and the benchmark's A/B in one binary; not to be flipped while a
/// pass runs. Returns the former setting.
bool set_volume_simd(bool on);
/// Whether the vector path was compiled (a target with AVX2 and GCC or Clang).
bool volume_simd_compiled();
}  // namespace detail

/// compression_block_bound of the fused compression terms over the volume records (the step's last sub-step,
/// where the blocks decide its sub-step count): the same bound to rounding, from `s` (m_i^-1/2, 0 on a fixed
/// node) instead of the masses; `brows`: kCompressionRowsPerNode #N doubles (overwritten).
double fused_compression_blocks(const VolumeTerms& T, const double* x, const double* s, double* brows,
                                Index nodes);
/// The bound max_i tr B_i / 3 + sqrt(2/3 |dev B_i|_F^2) >= lambda_max(B_i) of the 3x3 blocks in `rows`.
double compression_block_max(const double* rows, Index nodes);

}  // namespace medspring
