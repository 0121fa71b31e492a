// A model's springs and nodes as flat arrays for a node-parallel gather (no atomics): the layout the
// CUDA backend copies to the device (src/gpu, docs/gpu.md), and that a CPU loop can run through the
// same hd:: functions (physics/kernels.hpp) to check them against the engine's step.
#pragma once

#include <cstdint>
#include <vector>

#include "medspring/physics/kernels.hpp"
#include "medspring/physics/kernels_split.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/physics/model.hpp"

namespace medspring {

/// hd::SpringTable's arrays (sliced ELL, slices of hd::kSlice nodes; see kernels.hpp).
template <class R>
struct SpringTableArrays {
  int nodes = 0;
  std::vector<int> row_node;  // node of each row; empty: row r is node r
  std::vector<int> slice_begin, slice_width, other;
  std::vector<R> L0, k, kp, ik;
  std::vector<unsigned short> cls;  // compact_spring_params: class of each entry (then k, kp, ik are empty)
  std::vector<R> ck, ckp, cik;      // the classes' k, k', 1/k
  // pack_spring_table: each entry one word (other end's offset, class), classes of (L0, k, k', 1/k) in
  // cL0, ck, ckp, cik; other, L0, k, kp, ik, cls then empty.
  std::vector<unsigned> packed;
  int class_bits = 0;
  std::vector<R> cL0;
  std::size_t entries() const { return packed.empty() ? other.size() : packed.size(); }
  hd::SpringTable<R> view() const {
    hd::SpringTable<R> T;
    T.nodes = nodes;
    T.row_node = row_node.empty() ? nullptr : row_node.data();
    T.slice_begin = slice_begin.data();
    T.slice_width = slice_width.data();
    T.other = other.data();
    T.L0 = L0.data();
    if (!packed.empty()) {
      T.other = nullptr;
      T.L0 = nullptr;
      T.packed = packed.data();
      T.class_bits = class_bits;
      T.cL0 = cL0.data();
      T.ck = ck.data();
      T.ckp = ckp.data();
      T.cik = cik.data();
    } else if (cls.empty()) {
      T.k = k.data();
      T.kp = kp.data();
      T.ik = ik.data();
    } else {
      T.cls = cls.data();
      T.ck = ck.data();
      T.ckp = ckp.data();
      T.cik = cik.data();
    }
    return T;
  }
};

/// Order of the table's rows (load balance, docs/gpu.md). A node's terms and their order are the same
/// in every order; only which thread (and warp) gathers which node changes.
enum class RowOrder {
  Nodes,      // row r = node r
  HeavyLast,  // node order, except rows of more than kHeavyDegree springs (and more than twice the
              // median degree: the kidney's atoms), moved to the end by decreasing degree, so that they
              // fill warps of their own and light nodes are not padded to their width; locality of
              // the other nodes kept (the grid kernel of large models)
  Balanced,   // by decreasing degree, dealt to `threads` threads in snake order (round j runs forward
              // for even j, backward for odd j): in the one-block-per-model kernel thread t takes rows
              // t, t + threads, ... so every thread gets a heavy and a light row in turn, and each warp's
              // rows have similar degrees
};
inline constexpr int kHeavyDegree = 16;

/// The sliced ELL table of a finalized model: each node's springs in increasing spring index (the order
/// of the CPU's serial spring pass), rows in `order` (`threads`: the block size, for Balanced). Throws
/// InvalidInput for a model with bending terms (not a spring network: the gather has no three-node
/// terms).
template <class R>
SpringTableArrays<R> make_spring_table(const Model& model, RowOrder order = RowOrder::Nodes, int threads = 0);

/// The one-block-per-model kernel's table with heavy rows split (hd::SplitRows, kernels_split.hpp): a node
/// of more than `chunk` springs becomes ceil(degree / chunk) rows of consecutive springs (in spring
/// order); all rows are dealt by size to `threads` threads in snake order as RowOrder::Balanced.
/// chunk <= 0: ceil(2 springs / threads), at least 8 (the mean work of a thread).
template <class R>
struct SplitTableArrays {
  SpringTableArrays<R> table;  // table.row_node: the node of each row (rows = table.row_node.size())
  std::vector<int> part, heavy_node, part_begin;
  int chunk = 0;
  int parts() const { return part_begin.empty() ? 0 : part_begin.back(); }
  hd::SplitRows view() const {
    return {static_cast<int>(part.size()), part.data(), static_cast<int>(heavy_node.size()),
            heavy_node.data(), part_begin.data()};
  }
};
template <class R>
SplitTableArrays<R> make_split_table(const Model& model, int threads, int chunk = 0);

/// The grid kernel's table with heavy nodes split (hd::GridSplit, kernels_split.hpp): nodes of at most
/// `chunk` springs (default as HeavyLast: max(kHeavyDegree, twice the median degree)) are whole rows in
/// node order; then, from a warp boundary, each
/// heavier node by decreasing degree as consecutive rows of at most max(chunk, ceil(degree / 32)) springs
/// in spring order, all in one warp (padding rows, part -2, where a node's chunks would straddle two), its
/// first row the lead that sums them.
template <class R>
struct GridSplitArrays {
  SpringTableArrays<R> table;  // table.row_node: the node of each row (rows = part.size())
  std::vector<int> part, lead, part_begin, heavy_node, lead_row;
  int chunk = 0;
  int parts() const { return part_begin.empty() ? 0 : part_begin.back(); }
  int rows() const { return static_cast<int>(part.size()); }
  hd::GridSplit view() const {
    return {static_cast<int>(part.size()), part.data(), lead.data(), part_begin.data(), heavy_node.data()};
  }
};
template <class R>
GridSplitArrays<R> make_grid_split_table(const Model& model, int chunk = 0);

/// The row order alone (node of each row; empty for RowOrder::Nodes) from the node degrees.
std::vector<int> table_row_order(const std::vector<int>& degree, RowOrder order, int threads);

/// hd::NodeArrays' arrays. load_slot is -1 everywhere until set_load_slots.
template <class R>
struct NodeArrayData {
  int nodes = 0;
  std::vector<R> x0, mass, damping, kr;
  std::vector<unsigned char> fixed;
  std::vector<int> load_slot;
  std::vector<unsigned short> cls;  // compact_node_params: class of each node (then mass, damping, kr empty)
  std::vector<R> cmass, cdamping, ckr;
  hd::NodeArrays<R> view() const {
    hd::NodeArrays<R> N{nodes,     x0.data(),    mass.data(),     damping.data(),
                        kr.data(), fixed.data(), load_slot.data()};
    if (!cls.empty()) {
      N.mass = N.damping = N.kr = nullptr;
      N.cls = cls.data();
      N.cmass = cmass.data();
      N.cdamping = cdamping.data();
      N.ckr = ckr.data();
    }
    return N;
  }
};
template <class R>
NodeArrayData<R> make_node_arrays(const Model& model);

/// Default cap on the classes of a compact table: 1,024 classes of three reals stay in a GPU's L1.
inline constexpr int kCompactClasses = 1024;

/// Compact parameters (docs/gpu.md): where the table's (k, k', 1/k) triples take at most `max_classes`
/// distinct values (bit for bit; max_classes <= 65,536), replaces the per-entry arrays by a 2-byte class
/// per entry and the classes' values, and returns true; otherwise leaves the table as it is and returns
/// false. The gather then reads the same values, so its results are bit-identical.
template <class R>
bool compact_spring_params(SpringTableArrays<R>& table, int max_classes = kCompactClasses);

/// Packed entries (docs/gpu.md, "Packed table"): each entry of row r (node a) becomes one 32-bit word,
/// its other end's offset b - a in the high 32 - class_bits bits (signed) and its class in the low
/// class_bits bits, a class being a distinct (L0, k, k', 1/k) bit for bit (from the per-entry arrays or
/// the compact classes). class_bits: the fewest bits that number the classes. Packs and returns fits =
/// true when there are at most 2^max_class_bits classes and every offset fits in the remaining bits;
/// otherwise leaves the table as it is and returns fits = false with the figures that did not fit (the
/// caller keeps the unpacked table: say so). The gather then reads the same values: the same results.
struct PackReport {
  bool fits = false;
  long long classes = 0;       // distinct (L0, k, k', 1/k)
  int class_bits = 0;          // bits for the classes
  long long max_offset = 0;    // largest |b - a| over the entries
  long long offset_limit = 0;  // largest |b - a| the remaining bits hold: 2^(31 - class_bits) - 1
};
template <class R>
PackReport pack_spring_table(SpringTableArrays<R>& table, int max_class_bits = 16);

/// The same for the nodes' (mass, damping, k_r).
template <class R>
bool compact_node_params(NodeArrayData<R>& nodes, int max_classes = kCompactClasses);

/// The distinct loaded nodes of a load list, in order of first appearance: node -> row of the load table.
struct LoadSlots {
  std::vector<int> nodes;  // row r is node nodes[r]
  std::vector<int> slot;   // (model nodes) row of the node, -1 = unloaded
};
/// Validates the loads against n nodes (validate_loads) and assigns rows.
LoadSlots make_load_slots(const std::vector<PointLoad>& loads, Index n);

/// The load table at time t: row r = sum of the loads on node nodes[r] (accumulate_loads' arithmetic,
/// in load order): rows has 3 x slots.nodes.size() entries.
void load_rows(const std::vector<PointLoad>& loads, const LoadSlots& slots, double t, double* rows);

}  // namespace medspring
