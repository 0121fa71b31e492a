#include "medspring/models/hybrid_kidney.hpp"

#include <algorithm>
#include <numeric>

#include "medspring/core/check.hpp"
#include "medspring/core/memory.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/topology.hpp"

namespace medspring {

MatX2i union_spokes(const MatX3& S, const MatX3& A, Index K) {
  const Index ns = static_cast<Index>(S.rows()), na = static_cast<Index>(A.rows());
  require(na >= 1, "spokes: no atoms");
  require(ns >= 1, "spokes: no surface nodes");
  require(K >= 0, "spokes: spokes per atom must be >= 0 (got ", K, ")");
  std::vector<std::pair<Index, Index>> pairs;  // (atom, node)
  // (a) every surface node to its nearest atom; ties -> lower atom index (strict <)
  for (Index i = 0; i < ns; ++i) {
    Index best = 0;
    double bd = (S.row(i) - A.row(0)).squaredNorm();
    for (Index a = 1; a < na; ++a) {
      const double d = (S.row(i) - A.row(a)).squaredNorm();
      if (d < bd) {
        bd = d;
        best = a;
      }
    }
    pairs.emplace_back(best, i);
  }
  // (b) every atom to its K nearest surface nodes (ties -> lower node index)
  std::vector<Index> order(static_cast<std::size_t>(ns));
  std::vector<double> dist(static_cast<std::size_t>(ns));
  const Index kk = std::min(K, ns);
  for (Index a = 0; a < na; ++a) {
    for (Index i = 0; i < ns; ++i) dist[i] = (S.row(i) - A.row(a)).squaredNorm();
    std::iota(order.begin(), order.end(), 0);
    std::partial_sort(order.begin(), order.begin() + kk, order.end(),
                      [&](Index x, Index y) { return dist[x] < dist[y] || (dist[x] == dist[y] && x < y); });
    for (Index q = 0; q < kk; ++q) pairs.emplace_back(a, order[q]);
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  MatX2i out(static_cast<Index>(pairs.size()), 2);
  for (std::size_t r = 0; r < pairs.size(); ++r) {
    out(static_cast<Index>(r), 0) = pairs[r].second;
    out(static_cast<Index>(r), 1) = pairs[r].first;
  }
  return out;
}

HybridKidney::HybridKidney(const SurfaceMesh& surface, const MatX3& atoms, const HybridSettings& st,
                           std::string name)
    : F_(surface.F), rest_surface_(surface.V), settings_(st) {
  require_memory(kModelBuildBytesPerNode * static_cast<double>(surface.num_vertices()),
                 cat(name, ": a hybrid model of ", surface.num_vertices(), " surface nodes"));
  require_valid_mesh(surface, name, {.closed = false, .manifold = true});
  require(atoms.rows() >= 2, name, ": a hybrid model needs at least 2 centerline atoms (got ", atoms.rows(),
          ")");
  require_finite_points(atoms, name, ": atoms");
  require_positive(st.k_surf, name, ": k_surf");
  require_nonnegative(st.k_spoke, name, ": k_spoke");
  require_nonnegative(st.k_cl, name, ": k_cl");
  for (Index a = 1; a < atoms.rows(); ++a)
    require((atoms.row(a) - atoms.row(a - 1)).norm() >= 1e-9, name, ": atoms ", a - 1, " and ", a,
            " coincide (a centerline spring needs a non-zero rest length)");
  const Index ns = surface.num_vertices();
  num_atoms_ = static_cast<Index>(atoms.rows());
  const DuffingSettings duff = st.nonlinear ? st.duffing : DuffingSettings{.mode = DuffingMode::Linear};
  ModelBuilder b(name);
  for (Index i = 0; i < ns; ++i) b.add_node(surface.V.row(i).transpose(), st.surface_node);
  for (Index a = 0; a < num_atoms_; ++a) b.add_node(atoms.row(a).transpose(), st.atom_node);
  const MatX2i E = unique_edges(surface.F);
  spokes_ = union_spokes(surface.V, atoms, st.spokes_per_atom);
  b.reserve_springs(static_cast<Index>(E.rows() + spokes_.rows()) + num_atoms_);
  for (Index s = 0; s < E.rows(); ++s) b.add_spring(E(s, 0), E(s, 1), st.k_surf, duff);  // §4.3 surface
  for (Index a = 0; a + 1 < num_atoms_; ++a) b.add_spring(ns + a, ns + a + 1, st.k_cl, duff);  // centerline
  spoke_length_ = VecX::Zero(ns);
  std::vector<Index> per_atom(static_cast<std::size_t>(num_atoms_), 0);
  for (Index s = 0; s < spokes_.rows(); ++s) {
    const Index i = spokes_(s, 0), a = spokes_(s, 1);
    const double L = (surface.V.row(i) - atoms.row(a)).norm();
    require(L >= 1e-9, name, ": surface node ", i, " coincides with atom ", a);
    b.add_spring(i, ns + a, st.k_spoke, duff);  // spokes (D-9)
    spoke_length_[i] = spoke_length_[i] > 0 ? std::min(spoke_length_[i], L) : L;
    ++per_atom[a];
  }
  for (std::size_t q = 0; q < st.fixed.size(); ++q) {
    require_index(st.fixed[q], ns, name, ": fixed[", q, "]");
    b.set_fixed(st.fixed[q]);
  }
  model_ = b.build();
  stats_.surface_nodes = ns;
  stats_.atoms = num_atoms_;
  stats_.surface_springs = static_cast<Index>(E.rows());
  stats_.centerline_springs = num_atoms_ - 1;
  stats_.spokes = static_cast<Index>(spokes_.rows());
  stats_.min_spokes_per_atom = *std::min_element(per_atom.begin(), per_atom.end());
  stats_.max_spokes_per_atom = *std::max_element(per_atom.begin(), per_atom.end());
  for (Index i = 0; i < ns; ++i) stats_.surface_nodes_without_spoke += spoke_length_[i] > 0 ? 0 : 1;
}

void HybridKidney::map_to_surface(const State& state, MatX3& surface) const {
  surface = state.x.topRows(num_surface_nodes());
}

void HybridKidney::transfer_force(Index node, const Vec3& F, MatX3& f_dof) const {
  f_dof.row(node) += F.transpose();
}

std::vector<std::uint8_t> HybridKidney::fixed_surface_nodes() const {
  return {model_.fixed.begin(), model_.fixed.begin() + num_surface_nodes()};
}

MatX3 kidney_phantom_atoms(Index count) {
  require(count >= 2, "kidney phantom atoms: count must be >= 2 (got ", count, ")");
  const KidneyPhantomShape s;
  MatX3 A(count, 3);
  for (Index k = 0; k < count; ++k) {
    const double x = -0.85 * s.a + 1.7 * s.a * static_cast<double>(k) / static_cast<double>(count - 1);
    A.row(k) = kidney_bend(Vec3(x, 0, 0), s.bend_radius).transpose();
  }
  return A;
}

HybridKidney hybrid_kidney_phantom(const HybridSettings& settings) {
  return HybridKidney(kidney_phantom(), kidney_phantom_atoms(42), settings, "kidney_phantom");
}

}  // namespace medspring
