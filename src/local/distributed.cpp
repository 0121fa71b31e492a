#include "medspring/local/distributed.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "medspring/core/check.hpp"

namespace medspring {

LocalPatch loaded_nodes_patch(const Adjacency& adj, const std::vector<Index>& loaded, Index contact,
                              double k_loc, const std::vector<std::uint8_t>& fixed, int rings) {
  const Index n = adj.num_nodes();
  require(!loaded.empty(), "local patch (distributed load): no loaded node");
  require(rings >= 0, "local patch (distributed load): rings must be >= 0 (got ", rings, ")");
  require(std::find(loaded.begin(), loaded.end(), contact) != loaded.end(),
          "local patch (distributed load): contact node ", contact, " is not a loaded node");
  std::vector<int> hops(static_cast<std::size_t>(std::max<Index>(n, 0)), -1);
  std::vector<Index> frontier;
  for (Index g : loaded) {
    require(g >= 0 && g < n, "local patch (distributed load): loaded node ", g, " out of range [0, ", n, ")");
    hops[static_cast<std::size_t>(g)] = 0;
    frontier.push_back(g);
  }
  std::vector<Index> nodes = loaded;  // the loaded nodes first, then each ring in index order
  for (int r = 1; r <= rings; ++r) {
    std::vector<Index> next;
    for (Index g : frontier)
      for (const Index* q = adj.begin(g); q != adj.end(g); ++q)
        if (hops[static_cast<std::size_t>(*q)] < 0) {
          hops[static_cast<std::size_t>(*q)] = r;
          next.push_back(*q);
        }
    std::sort(next.begin(), next.end());
    nodes.insert(nodes.end(), next.begin(), next.end());
    frontier = std::move(next);
  }
  return make_local_patch(adj, nodes, contact, k_loc, fixed);
}

Vec3 solve_local_distributed(const LocalPatch& patch, const MatX3& F, MatX3& U, const MatX3& X,
                             const LocalSettings& settings) {
  require(settings.stiffness != LocalStiffness::PaperLiteral,
          "local deformation (distributed load): PaperLiteral is not symmetric; use Isotropic, Linearized or "
          "AxisProjected");
  const Index P = patch.size();
  require(F.rows() == P, "local deformation (distributed load): force has ", F.rows(),
          " rows, the patch has ", P, " nodes");
  require(F.allFinite(), "local deformation (distributed load): the force is not finite");
  const Eigen::MatrixXd K = local_stiffness_matrix(patch, X, settings);  // validates patch and settings
  U = MatX3::Zero(P, 3);
  Vec3 dropped = Vec3::Zero();
  for (Index a = 0; a < P; ++a)
    if (patch.fixed[a] != 0) dropped += F.row(a).transpose();
  const Index nf = patch.num_free();
  if (nf == 0) return dropped;
  Eigen::MatrixXd Kff(3 * nf, 3 * nf);
  VecX rhs(3 * nf);
  for (Index i = 0; i < nf; ++i) {
    const Index a = patch.free_nodes[i];
    rhs.segment<3>(3 * i) = F.row(a).transpose();
    for (Index j = 0; j < nf; ++j)
      Kff.block<3, 3>(3 * i, 3 * j) = K.block<3, 3>(3 * a, 3 * patch.free_nodes[j]);
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(Kff);
  const double tol = settings.pivot_tolerance * K.cwiseAbs().maxCoeff();
  const VecX d = ldlt.vectorD();
  for (Index i = 0; i < d.size(); ++i)
    if (!(d(i) > tol))
      throw SolverError(cat("local deformation (distributed load, ", to_string(settings.stiffness),
                            "): singular patch stiffness (pivot ", d(i), " <= ", tol,
                            ") - some free nodes are not connected to a fixed node"));
  const VecX u = ldlt.solve(rhs);
  for (Index i = 0; i < nf; ++i) U.row(patch.free_nodes[i]) = u.segment<3>(3 * i).transpose();
  return dropped;
}

}  // namespace medspring
