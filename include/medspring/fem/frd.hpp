// A small, bounds-checked reader of CalculiX's ASCII result file (.frd): the node block and the
// displacement (DISP) result blocks. Every error is an IoError naming the file and the line.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring::fem {

/// One DISP result block: the step time it belongs to and one displacement per node of the node block.
struct FrdDisplacementBlock {
  double time = 0.0;  // step time (1.0 = the full load of a static step)
  MatX3 u;            // (#nodes x 3), mm, rows in the order of FrdData::ids
};

struct FrdData {
  std::vector<Index> ids;  // node ids (positive), in file order, unique
  MatX3 X;                 // node coordinates (#nodes x 3)
  std::vector<FrdDisplacementBlock> disp;
  std::vector<FrdDisplacementBlock> forc;  // FORC blocks (reaction forces, *NODE FILE RF), N; nodes absent
                                           // from a block get zero
};

/// Parses .frd text. `name` is used in the messages ("<name>: line 12: ...").
FrdData parse_frd(std::string_view text, const std::string& name = "frd");

/// Reads a .frd file (IoError if it cannot be opened or is larger than 2 GiB).
FrdData read_frd(const std::string& path);

/// The last DISP block as displacements of nodes 1..n (row i = node id i+1). Throws IoError when there
/// is no block, a node in 1..n is missing or the last block is not at step time `expect_time` (±1e-6).
MatX3 last_displacement(const FrdData& frd, Index n, double expect_time, const std::string& name = "frd");

/// The last FORC block (reaction forces, N) as forces on nodes 1..n (row i = node id i+1; a node absent
/// from the block gets zero). Throws IoError when there is no block or it is not at `expect_time`.
MatX3 last_reaction(const FrdData& frd, Index n, double expect_time, const std::string& name = "frd");

}  // namespace medspring::fem
