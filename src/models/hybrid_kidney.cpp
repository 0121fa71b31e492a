#include "medspring/models/hybrid_kidney.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "medspring/core/check.hpp"
#include "medspring/core/memory.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/topology.hpp"

namespace medspring {

bool segment_inside_mask(const MaskVolume& mask, const Vec3& p, const Vec3& q) {
  const double h = std::max(1e-6, mask.spacing.minCoeff());
  const double tolerance = mask.spacing.maxCoeff();  // one voxel
  const Index n = std::max<Index>(1, static_cast<Index>(std::ceil((q - p).norm() / h)));
  for (Index s = 0; s <= n; ++s) {
    const Vec3 v = mask.to_index(p + (q - p) * (static_cast<double>(s) / static_cast<double>(n)));
    const Index ci = static_cast<Index>(std::lround(v.x())), cj = static_cast<Index>(std::lround(v.y())),
                ck = static_cast<Index>(std::lround(v.z()));
    if (mask.inside(ci, cj, ck) && mask.at(ci, cj, ck) != 0) continue;
    // the distance to the nearest object voxel (its box), searched two voxels around
    bool near = false;
    for (Index k = ck - 2; k <= ck + 2 && !near; ++k)
      for (Index j = cj - 2; j <= cj + 2 && !near; ++j)
        for (Index i = ci - 2; i <= ci + 2 && !near; ++i) {
          if (!mask.inside(i, j, k) || mask.at(i, j, k) == 0) continue;
          const Vec3 c(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
          Vec3 d;
          for (int a = 0; a < 3; ++a) d[a] = std::max(0.0, std::abs(v[a] - c[a]) - 0.5) * mask.spacing[a];
          near = d.norm() <= tolerance;
        }
    if (!near) return false;
  }
  return true;
}

MatX2i union_spokes(const MatX3& S, const MatX3& A, Index K, const MaskVolume* mask,
                    SpokeVisibility* visibility) {
  const Index ns = static_cast<Index>(S.rows()), na = static_cast<Index>(A.rows());
  require(na >= 1, "spokes: no atoms");
  require(ns >= 1, "spokes: no surface nodes");
  require(K >= 0, "spokes: spokes per atom must be >= 0 (got ", K, ")");
  if (mask)
    require(mask->dims[0] > 0 && mask->dims[1] > 0 && mask->dims[2] > 0 && mask->data.size() == mask->size(),
            "spokes: the visibility mask is empty or its data does not match its dimensions");
  SpokeVisibility vis;
  auto visible = [&](Index node, Index atom) {
    if (!mask) return true;
    const bool ok = segment_inside_mask(*mask, S.row(node).transpose(), A.row(atom).transpose());
    if (!ok) ++vis.rejected;
    return ok;
  };
  std::vector<std::pair<Index, Index>> pairs;  // (atom, node)
  // (a) every surface node to its nearest (visible) atom; ties -> lower atom index
  std::vector<Index> aorder(static_cast<std::size_t>(na));
  std::vector<double> adist(static_cast<std::size_t>(na));
  for (Index i = 0; i < ns; ++i) {
    for (Index a = 0; a < na; ++a) adist[a] = (S.row(i) - A.row(a)).squaredNorm();
    std::iota(aorder.begin(), aorder.end(), 0);
    std::stable_sort(aorder.begin(), aorder.end(), [&](Index x, Index y) { return adist[x] < adist[y]; });
    Index best = -1;
    for (Index a : aorder)
      if (visible(i, a)) {
        best = a;
        break;
      }
    if (best < 0) {
      best = aorder.front();
      ++vis.fallbacks;
    }
    pairs.emplace_back(best, i);
  }
  // (b) every atom to its K nearest (visible) surface nodes (ties -> lower node index)
  std::vector<Index> order(static_cast<std::size_t>(ns));
  std::vector<double> dist(static_cast<std::size_t>(ns));
  const Index kk = std::min(K, ns);
  for (Index a = 0; a < na; ++a) {
    for (Index i = 0; i < ns; ++i) dist[i] = (S.row(i) - A.row(a)).squaredNorm();
    std::iota(order.begin(), order.end(), 0);
    auto closer = [&](Index x, Index y) { return dist[x] < dist[y] || (dist[x] == dist[y] && x < y); };
    if (!mask) {
      std::partial_sort(order.begin(), order.begin() + kk, order.end(), closer);
      for (Index q = 0; q < kk; ++q) pairs.emplace_back(a, order[q]);
      continue;
    }
    std::sort(order.begin(), order.end(), closer);
    Index taken = 0;
    for (Index q = 0; q < ns && taken < kk; ++q)
      if (visible(order[q], a)) {
        pairs.emplace_back(a, order[q]);
        ++taken;
      }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  MatX2i out(static_cast<Index>(pairs.size()), 2);
  for (std::size_t r = 0; r < pairs.size(); ++r) {
    out(static_cast<Index>(r), 0) = pairs[r].second;
    out(static_cast<Index>(r), 1) = pairs[r].first;
  }
  if (visibility) *visibility = vis;
  return out;
}

HybridKidney::HybridKidney(const SurfaceMesh& surface, const MatX3& atoms, const HybridSettings& st,
                           std::string name, const MaskVolume* mask, Index locality_min_nodes)
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
  for (std::size_t q = 0; q < st.fixed.size(); ++q) require_index(st.fixed[q], ns, name, ": fixed[", q, "]");
  // Locality (issue 15): a large, badly numbered surface is simulated in its RCM order (DOF d = surface
  // node order[d]); everything else below is in the user's numbering and mapped by dof().
  std::vector<Index> order;  // order[dof] = surface node (empty: identity)
  MatX2i E;                  // surface springs, in DOF numbering
  if (ns >= locality_min_nodes) {
    order = locality_order(surface);
    SurfaceMesh ordered = permute_vertices(surface, order);
    if (2 * mesh_bandwidth(ordered) < mesh_bandwidth(surface)) {
      dof_of_surface_ = inverse_permutation(order);
      E = unique_edges(ordered.F);  // sorted by DOF: springs in locality order too
    } else {
      order.clear();
    }
  }
  if (order.empty()) E = unique_edges(surface.F);
  const DuffingSettings duff = st.nonlinear ? st.duffing : DuffingSettings{.mode = DuffingMode::Linear};
  ModelBuilder b(name);
  for (Index d = 0; d < ns; ++d)
    b.add_node(surface.V.row(order.empty() ? d : order[static_cast<std::size_t>(d)]).transpose(),
               st.surface_node);
  for (Index a = 0; a < num_atoms_; ++a) b.add_node(atoms.row(a).transpose(), st.atom_node);
  const MaskVolume* filter = st.visibility_filter ? mask : nullptr;
  spokes_ = union_spokes(surface.V, atoms, st.spokes_per_atom, filter, &stats_.visibility);
  stats_.visibility_filtered = filter != nullptr;
  b.reserve_springs(static_cast<Index>(E.rows() + spokes_.rows()) + num_atoms_);
  for (Index s = 0; s < E.rows(); ++s) b.add_spring(E(s, 0), E(s, 1), st.k_surf, duff);  // §4.3 surface
  for (Index a = 0; a + 1 < num_atoms_; ++a) b.add_spring(ns + a, ns + a + 1, st.k_cl, duff);  // centerline
  spoke_length_ = VecX::Zero(ns);
  std::vector<Index> per_atom(static_cast<std::size_t>(num_atoms_), 0);
  std::vector<std::pair<Index, Index>> spoke_springs;  // (atom, DOF): by atom, then DOF
  spoke_springs.reserve(static_cast<std::size_t>(spokes_.rows()));
  for (Index s = 0; s < spokes_.rows(); ++s) {
    const Index i = spokes_(s, 0), a = spokes_(s, 1);
    const double L = (surface.V.row(i) - atoms.row(a)).norm();
    require(L >= 1e-9, name, ": surface node ", i, " coincides with atom ", a);
    spoke_springs.emplace_back(a, dof_of(i));
    spoke_length_[i] = spoke_length_[i] > 0 ? std::min(spoke_length_[i], L) : L;
    ++per_atom[a];
  }
  if (!order.empty()) std::sort(spoke_springs.begin(), spoke_springs.end());  // identity: already sorted
  for (const auto& [a, d] : spoke_springs) b.add_spring(d, ns + a, st.k_spoke, duff);  // spokes (D-9)
  for (const Index f : st.fixed) b.set_fixed(dof_of(f));
  for (std::size_t q = 0; q < st.fixed_atoms.size(); ++q) {
    require_index(st.fixed_atoms[q], num_atoms_, name, ": fixed_atoms[", q, "]");
    b.set_fixed(ns + st.fixed_atoms[q]);
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
  if (dof_of_surface_.empty()) {
    surface = state.x.topRows(num_surface_nodes());
    return;
  }
  const Index n = num_surface_nodes();
  surface.resize(n, 3);
  for (Index s = 0; s < n; ++s) surface.row(s) = state.x.row(dof_of_surface_[static_cast<std::size_t>(s)]);
}

void HybridKidney::transfer_force(Index node, const Vec3& F, MatX3& f_dof) const {
  f_dof.row(dof_of(node)) += F.transpose();
}

std::vector<std::uint8_t> HybridKidney::fixed_surface_nodes() const {
  if (dof_of_surface_.empty()) return {model_.fixed.begin(), model_.fixed.begin() + num_surface_nodes()};
  std::vector<std::uint8_t> out(dof_of_surface_.size());
  for (std::size_t s = 0; s < out.size(); ++s)
    out[s] = model_.fixed[static_cast<std::size_t>(dof_of_surface_[s])];
  return out;
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
