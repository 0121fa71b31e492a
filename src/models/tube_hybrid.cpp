#include "medspring/models/tube_hybrid.hpp"

#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/topology.hpp"

namespace medspring {

TubeHybridBody::TubeHybridBody(const TubeHybridSettings& st) : settings_(st) {
  require(st.rings >= 2, "tube hybrid: rings must be >= 2 (got ", st.rings, ")");
  require(st.spokes >= 3, "tube hybrid: spokes must be >= 3 (got ", st.spokes, ")");
  require_positive(st.spacing, "tube hybrid: spacing");
  require_positive(st.radius, "tube hybrid: radius");
  const SurfaceMesh t = tube(st.rings, st.spokes, st.spacing, st.radius);
  const Index S = t.num_vertices();
  const HybridSettings& h = st.hybrid;
  DuffingSettings d = h.duffing;
  if (!st.nonlinear) d.mode = DuffingMode::Linear;
  ModelBuilder b("vessel hybrid MS (D-18)");
  for (Index r = 0; r < S; ++r) b.add_node(t.V.row(r).transpose(), h.surface_node);
  for (Index i = 0; i < st.rings; ++i)
    b.add_node(Vec3(st.spacing * static_cast<double>(i), 0, 0), h.atom_node);
  const MatX2i edges = unique_edges(t.F);
  for (Index e = 0; e < edges.rows(); ++e) b.add_spring(edges(e, 0), edges(e, 1), h.k_surf, d);
  for (Index i = 0; i + 1 < st.rings; ++i) b.add_spring(S + i, S + i + 1, h.k_cl, d);
  for (Index i = 0; i < st.rings; ++i)
    for (Index j = 0; j < st.spokes; ++j) b.add_spring(i * st.spokes + j, S + i, h.k_spoke, d);
  fixed_surface_.assign(static_cast<std::size_t>(S), 0);
  for (Index j = 0; j < st.spokes; ++j)
    for (const Index r : {j, (st.rings - 1) * st.spokes + j}) {
      b.set_fixed(r);
      fixed_surface_[static_cast<std::size_t>(r)] = 1;
    }
  b.set_fixed(S);
  b.set_fixed(S + st.rings - 1);
  model_ = b.build();
  F_ = t.F;
  rest_ = t.V;
}

void TubeHybridBody::map_to_surface(const State& state, MatX3& surface) const {
  surface = state.x.topRows(rest_.rows());
}

void TubeHybridBody::transfer_force(Index node, const Vec3& F, MatX3& f_dof) const {
  f_dof.row(node) += F.transpose();
}

}  // namespace medspring
