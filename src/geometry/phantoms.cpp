#include "medspring/geometry/phantoms.hpp"

#include <cmath>
#include <map>
#include <numbers>

#include "medspring/core/check.hpp"
#include "medspring/core/memory.hpp"

namespace medspring {

MatX3i tube_grid_faces(Index rings, Index spokes) {
  require(rings >= 2, "tube: rings must be >= 2 (got ", rings, ")");
  require(spokes >= 3, "tube: spokes must be >= 3 (got ", spokes, ")");
  const double nodes = static_cast<double>(rings) * static_cast<double>(spokes);
  require_index_count(2.0 * nodes, cat("tube: ", rings, " x ", spokes, " nodes: the face count"));
  require_memory(48.0 * nodes, cat("tube: ", rings, " x ", spokes, " nodes"));  // V and F
  MatX3i F(2 * spokes * (rings - 1), 3);
  Index f = 0;
  for (Index i = 0; i + 1 < rings; ++i)
    for (Index j = 0; j < spokes; ++j) {
      const Index a = i * spokes + j, b = i * spokes + (j + 1) % spokes;
      const Index c = (i + 1) * spokes + (j + 1) % spokes, d = (i + 1) * spokes + j;
      F.row(f++) << a, b, c;
      F.row(f++) << a, c, d;
    }
  return F;
}

SurfaceMesh tube(Index rings, Index spokes, double spacing, double radius) {
  require_positive(spacing, "tube: spacing");
  require_positive(radius, "tube: radius");
  SurfaceMesh m;
  m.F = tube_grid_faces(rings, spokes);
  m.V.resize(rings * spokes, 3);
  for (Index i = 0; i < rings; ++i)
    for (Index j = 0; j < spokes; ++j) {
      // frame u = e_z x t = +y, v = t x u = +z (ALGORITHMS.md §5.5 rest start for t = +x)
      const double th = 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(spokes);
      m.V.row(i * spokes + j) << spacing * static_cast<double>(i), radius * std::cos(th),
          radius * std::sin(th);
    }
  return m;
}

Vec3 kidney_bend(const Vec3& q, double Rb) {
  return {(Rb - q.y()) * std::sin(q.x() / Rb), Rb - (Rb - q.y()) * std::cos(q.x() / Rb), q.z()};
}

SurfaceMesh kidney_phantom() {
  const KidneyPhantomShape s;
  constexpr Index rings = 19, per = 24;
  const double pi = std::numbers::pi;
  SurfaceMesh m;
  m.V.resize(2 + rings * per, 3);
  m.V.row(0) = kidney_bend(Vec3(-s.a, 0, 0), s.bend_radius);
  for (Index k = 0; k < rings; ++k) {
    const double psi = pi * static_cast<double>(k + 1) / 20.0;
    for (Index j = 0; j < per; ++j) {
      const double phi = 2.0 * pi * static_cast<double>(j) / static_cast<double>(per);
      const Vec3 q(-s.a * std::cos(psi), s.b * std::sin(psi) * std::cos(phi),
                   s.c * std::sin(psi) * std::sin(phi));
      m.V.row(1 + per * k + j) = kidney_bend(q, s.bend_radius);
    }
  }
  m.V.row(1 + rings * per) = kidney_bend(Vec3(s.a, 0, 0), s.bend_radius);
  const Index last = 1 + rings * per;
  m.F.resize(2 * per + 2 * per * (rings - 1), 3);
  Index f = 0;
  auto node = [&](Index k, Index j) { return 1 + per * k + (j % per); };
  for (Index j = 0; j < per; ++j) m.F.row(f++) << 0, node(0, j + 1), node(0, j);
  for (Index k = 0; k + 1 < rings; ++k)
    for (Index j = 0; j < per; ++j) {
      m.F.row(f++) << node(k, j), node(k, j + 1), node(k + 1, j + 1);
      m.F.row(f++) << node(k, j), node(k + 1, j + 1), node(k + 1, j);
    }
  for (Index j = 0; j < per; ++j) m.F.row(f++) << last, node(rings - 1, j), node(rings - 1, j + 1);
  if (signed_volume(m.V, m.F) < 0) m.F.col(1).swap(m.F.col(2));
  return m;
}

SurfaceMesh icosphere(int subdivisions, double radius) {
  require(subdivisions >= 0 && subdivisions <= 8, "icosphere: subdivisions must be in [0, 8] (got ",
          subdivisions, ")");
  require_positive(radius, "icosphere: radius");
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> V = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<Index, 3>> F = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                         {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                         {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                         {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& v : V) v.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<Index, Index>, Index> mid;
    auto midpoint = [&](Index a, Index b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      V.push_back((V[a] + V[b]).normalized());
      const Index id = static_cast<Index>(V.size()) - 1;
      mid.emplace(key, id);
      return id;
    };
    std::vector<std::array<Index, 3>> G;
    G.reserve(F.size() * 4);
    for (const auto& f : F) {
      const Index ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      G.push_back({f[0], ab, ca});
      G.push_back({f[1], bc, ab});
      G.push_back({f[2], ca, bc});
      G.push_back({ab, bc, ca});
    }
    F.swap(G);
  }
  SurfaceMesh m;
  m.V.resize(static_cast<Index>(V.size()), 3);
  for (std::size_t i = 0; i < V.size(); ++i) m.V.row(static_cast<Index>(i)) = radius * V[i];
  m.F.resize(static_cast<Index>(F.size()), 3);
  for (std::size_t f = 0; f < F.size(); ++f)
    for (int k = 0; k < 3; ++k) m.F(static_cast<Index>(f), k) = F[f][k];
  if (signed_volume(m.V, m.F) < 0) m.F.col(1).swap(m.F.col(2));
  return m;
}

}  // namespace medspring
