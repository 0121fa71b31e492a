// Axis-aligned bounding box tree over the triangles of a surface whose topology is fixed: built once
// on the rest positions, refitted to the deformed positions every update (no allocation).
#pragma once

#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

class SurfaceBvh {
 public:
  SurfaceBvh() = default;
  /// Builds the tree for faces F (#F x 3) on positions X (leaves of up to 4 triangles).
  SurfaceBvh(const MatX3i& F, const MatX3& X);
  /// Recomputes every box for new positions X (same topology).
  void refit(const MatX3& X);
  /// Appends to `out` the triangles whose box overlaps [lo, hi]. out keeps its capacity.
  void query(const Vec3& lo, const Vec3& hi, std::vector<Index>& out) const;
  Index num_nodes() const { return static_cast<Index>(nodes_.size()); }

 private:
  struct Node {
    Vec3 lo, hi;
    Index left = -1, right = -1;  // children (internal)
    Index first = 0, count = 0;   // triangles order_[first, first + count) (leaf)
  };
  Index build(Index first, Index count, const MatX3& centroids);
  MatX3i faces_;
  std::vector<Node> nodes_;
  std::vector<Index> order_;
};

}  // namespace medspring
