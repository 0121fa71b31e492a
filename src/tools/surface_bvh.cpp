#include "medspring/tools/surface_bvh.hpp"

#include <algorithm>

#include "medspring/core/check.hpp"

namespace medspring {

SurfaceBvh::SurfaceBvh(const MatX3i& F, const MatX3& X) : faces_(F) {
  require(F.rows() > 0, "surface bvh: no triangles");
  const Index n = static_cast<Index>(F.rows());
  MatX3 centroids(n, 3);
  for (Index t = 0; t < n; ++t) {
    for (int k = 0; k < 3; ++k)
      require_index(F(t, k), static_cast<Index>(X.rows()), "surface bvh: faces[", t, "]");
    centroids.row(t) = (X.row(F(t, 0)) + X.row(F(t, 1)) + X.row(F(t, 2))) / 3.0;
  }
  order_.resize(static_cast<std::size_t>(n));
  for (Index t = 0; t < n; ++t) order_[static_cast<std::size_t>(t)] = t;
  nodes_.reserve(static_cast<std::size_t>(2 * n));
  build(0, n, centroids);
  refit(X);
}

Index SurfaceBvh::build(Index first, Index count, const MatX3& centroids) {
  const Index id = static_cast<Index>(nodes_.size());
  nodes_.push_back({});
  if (count <= 4) {
    nodes_[static_cast<std::size_t>(id)].first = first;
    nodes_[static_cast<std::size_t>(id)].count = count;
    return id;
  }
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (Index i = first; i < first + count; ++i) {
    const Vec3 c = centroids.row(order_[static_cast<std::size_t>(i)]).transpose();
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const auto begin = order_.begin() + first, mid = begin + count / 2, end = begin + count;
  std::nth_element(begin, mid, end,
                   [&](Index a, Index b) { return centroids(a, axis) < centroids(b, axis); });
  const Index left = build(first, count / 2, centroids);
  const Index right = build(first + count / 2, count - count / 2, centroids);
  nodes_[static_cast<std::size_t>(id)].left = left;
  nodes_[static_cast<std::size_t>(id)].right = right;
  return id;
}

void SurfaceBvh::refit(const MatX3& X) {
  // children always have larger indices than their parent (pre-order build): sweep backwards
  for (std::size_t k = nodes_.size(); k-- > 0;) {
    Node& n = nodes_[k];
    if (n.left < 0) {
      n.lo = Vec3::Constant(1e300);
      n.hi = Vec3::Constant(-1e300);
      for (Index i = n.first; i < n.first + n.count; ++i) {
        const Index t = order_[static_cast<std::size_t>(i)];
        for (int c = 0; c < 3; ++c) {
          const Vec3 p = X.row(faces_(t, c)).transpose();
          n.lo = n.lo.cwiseMin(p);
          n.hi = n.hi.cwiseMax(p);
        }
      }
    } else {
      const Node& a = nodes_[static_cast<std::size_t>(n.left)];
      const Node& b = nodes_[static_cast<std::size_t>(n.right)];
      n.lo = a.lo.cwiseMin(b.lo);
      n.hi = a.hi.cwiseMax(b.hi);
    }
  }
}

void SurfaceBvh::query(const Vec3& lo, const Vec3& hi, std::vector<Index>& out) const {
  if (nodes_.empty()) return;
  Index stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[static_cast<std::size_t>(stack[--top])];
    if ((n.lo.array() > hi.array()).any() || (n.hi.array() < lo.array()).any()) continue;
    if (n.left < 0) {
      for (Index i = n.first; i < n.first + n.count; ++i) out.push_back(order_[static_cast<std::size_t>(i)]);
    } else if (top + 2 <= 128) {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
}

}  // namespace medspring
