// Private to the meshing layer: the CGAL types and helpers that cgal_meshing.cpp (distances, hole
// filling) and cgal_balloon.cpp (the balloon surface) share; the mesh conversions are in cgal_mesh.hpp.
// CMake compiles the two files as ONE unity translation unit (UNITY_GROUP cgal): a CGAL translation unit
// takes ~25 s and ~1.6 GB to compile (../shared/TOOLCHAIN.md).
#pragma once

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/tangential_relaxation.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/Euler_operations.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>
#include <vector>

#include "cgal_mesh.hpp"
#include "medspring/core/check.hpp"
#include "medspring/geometry/locality.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/meshing/balloon.hpp"
#include "medspring/meshing/mesh_repair.hpp"
#include "medspring/meshing/surface_distance.hpp"

namespace medspring::cgal_detail {

namespace PMP = CGAL::Polygon_mesh_processing;
using Vector = K::Vector_3;
using Triangle = K::Triangle_3;
using HD = Mesh::Halfedge_index;
using ED = Mesh::Edge_index;
using Triangles = std::vector<Triangle>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

inline constexpr double kPi = 3.14159265358979323846;

inline Triangles to_triangles(const SurfaceMesh& s) {
  Triangles t;
  t.reserve(static_cast<std::size_t>(s.num_faces()));
  for (Index f = 0; f < s.num_faces(); ++f)
    t.emplace_back(to_point(s.V, s.F(f, 0)), to_point(s.V, s.F(f, 1)), to_point(s.V, s.F(f, 2)));
  return t;
}

/// Closest-point queries on a triangle set (the organ surface): the projection of the balloon.
class SurfaceQuery {
 public:
  explicit SurfaceQuery(Triangles triangles) : triangles_(std::move(triangles)) {
    tree_.insert(triangles_.cbegin(), triangles_.cend());
    tree_.build();
    tree_.accelerate_distance_queries();
  }
  Point closest(const Point& p) const { return tree_.closest_point(p); }
  double distance(const Point& p) const { return std::sqrt(tree_.squared_distance(p)); }

 private:
  Triangles triangles_;
  Tree tree_;
};

inline int sq(int x) {
  return x * x;
}
inline int valence(const Mesh& m, VD v) {
  return static_cast<int>(m.degree(v));
}

inline Vector normal_of(const Point& a, const Point& b, const Point& c) {
  return CGAL::cross_product(b - a, c - a);
}
inline double norm(const Vector& v) {
  return std::sqrt(v.squared_length());
}
inline double cos_between(const Vector& u, const Vector& v) {
  const double d = norm(u) * norm(v);
  return d > 0.0 ? (u * v) / d : -1.0;
}

/// Smallest interior angle of triangle abc, radians (0 for a degenerate triangle).
inline double min_angle(const Point& a, const Point& b, const Point& c) {
  const Point p[3] = {a, b, c};
  double best = kPi;
  for (int i = 0; i < 3; ++i) {
    const Vector u = p[(i + 1) % 3] - p[i], v = p[(i + 2) % 3] - p[i];
    const double nu = norm(u), nv = norm(v);
    if (nu <= 0.0 || nv <= 0.0) return 0.0;
    best = std::min(best, std::acos(std::clamp((u * v) / (nu * nv), -1.0, 1.0)));
  }
  return best;
}

}  // namespace medspring::cgal_detail
