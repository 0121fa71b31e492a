// Scratch sizes of the compression terms' stable-step bound (issue 23, compression_terms.hpp): internal to
// the physics layer (State::stiff_rows is sized by them).
#pragma once

#include <cstdint>

#include "medspring/core/types.hpp"
#include "medspring/physics/compression_terms.hpp"

namespace medspring {

/// Doubles of scratch per node that the stable-step bound of add_compression_forces needs (a symmetric 3x3
/// block each).
inline constexpr Index kCompressionRowsPerNode = 6;

/// Size of State::stiff_rows for a model with `volume_terms` volume and `compression_terms` compression terms
/// on `nodes` nodes: the volume terms' local rule needs #N rows and #T increments, the compression bound
/// 6 #N after them (both are live at once: the rule's gate counts the compression bound).
inline Index stiff_rows_size(Index nodes, Index volume_terms, Index compression_terms) {
  if (volume_terms == 0 && compression_terms == 0) return 0;
  return nodes + volume_terms + (compression_terms > 0 ? kCompressionRowsPerNode * nodes : 0);
}

/// add_compression_forces in two stages, for the step (src/physics/forces.cpp): the forces and the cheap
/// bound max_i tr B_i (the blocks' traces, `rows`: #N doubles), which is at most 3x the block bound and at
/// least it ...
double add_compression_forces_trace(const CompressionTerms& T, const double* x, double* f, const double* mass,
                                    const std::uint8_t* fixed, double* rows, Index nodes);
/// ... and the block bound alone, without the forces (`rows`: kCompressionRowsPerNode #N doubles), computed
/// only where the step's sub-step count depends on where in [trace / 3, trace] it lies.
double compression_block_bound(const CompressionTerms& T, const double* x, const double* mass,
                               const std::uint8_t* fixed, double* rows, Index nodes);

}  // namespace medspring
