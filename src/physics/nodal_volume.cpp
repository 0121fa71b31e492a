#include "medspring/physics/nodal_volume.hpp"

#include <algorithm>
#include <cmath>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

// Volume (mm^3) and dV/dx of the four corners of tetrahedron e at x.
inline double tet_gradient(const MatX4i& T, const MatX3& x, Index e, Vec3 g[4]) {
  const Vec3 xa = x.row(T(e, 0)).transpose();
  const Vec3 e1 = x.row(T(e, 1)).transpose() - xa, e2 = x.row(T(e, 2)).transpose() - xa,
             e3 = x.row(T(e, 3)).transpose() - xa;
  g[1] = e2.cross(e3) / 6.0;
  g[2] = e3.cross(e1) / 6.0;
  g[3] = e1.cross(e2) / 6.0;
  g[0] = -(g[1] + g[2] + g[3]);
  return e1.dot(e2.cross(e3)) / 6.0;
}

}  // namespace

NodalVolumeTerms make_nodal_volume_terms(const MatX3& x0, const MatX4i& T, const std::vector<double>& kv,
                                         const std::string& what) {
  const Index n = static_cast<Index>(x0.rows());
  require(static_cast<Index>(kv.size()) == T.rows(), what, ": nodal volume terms: ", kv.size(),
          " moduli for ", T.rows(), " tetrahedra");
  NodalVolumeTerms N;
  N.T = T;
  N.V0.resize(static_cast<std::size_t>(T.rows()));
  N.k = VecX::Zero(n);
  N.W0 = VecX::Zero(n);
  Vec3 g[4];
  for (Index e = 0; e < T.rows(); ++e) {
    for (int c = 0; c < 4; ++c)
      require(T(e, c) >= 0 && T(e, c) < n, what, ": nodal volume terms: tetrahedron ", e, " corner ", c, " (",
              T(e, c), ") is not a node (", n, " nodes)");
    require(std::isfinite(kv[static_cast<std::size_t>(e)]) && kv[static_cast<std::size_t>(e)] >= 0, what,
            ": nodal volume terms: tetrahedron ", e, ": modulus must be >= 0 and finite (got ",
            kv[static_cast<std::size_t>(e)], ")");
    double V = tet_gradient(N.T, x0, e, g);
    if (V < 0) {  // orient positively at rest
      std::swap(N.T(e, 2), N.T(e, 3));
      V = -V;
    }
    double L = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) L = std::max(L, (x0.row(T(e, a)) - x0.row(T(e, b))).norm());
    require(V > 1e-12 * L * L * L, what, ": nodal volume terms: tetrahedron ", e,
            " is degenerate at rest (volume ", V, " mm^3)");
    N.V0[static_cast<std::size_t>(e)] = V;
    for (int c = 0; c < 4; ++c) {
      N.W0[N.T(e, c)] += V;
      N.k[N.T(e, c)] += kv[static_cast<std::size_t>(e)] * V;
    }
  }
  for (Index a = 0; a < n; ++a)
    if (N.W0[a] > 0) N.k[a] /= N.W0[a];
  return N;
}

double nodal_volume_energy(const NodalVolumeTerms& N, const MatX3& x) {
  VecX W = VecX::Zero(N.W0.size());
  Vec3 g[4];
  for (Index e = 0; e < N.T.rows(); ++e) {
    const double V = tet_gradient(N.T, x, e, g);
    for (int c = 0; c < 4; ++c) W[N.T(e, c)] += V;
  }
  double E = 0;
  for (Index a = 0; a < W.size(); ++a)
    if (N.W0[a] > 0) E += N.k[a] * (W[a] - N.W0[a]) * (W[a] - N.W0[a]) / (8.0 * N.W0[a]);
  return E;
}

void add_nodal_volume_forces(const NodalVolumeTerms& N, const MatX3& x, MatX3& f, VecX& W) {
  W.setZero(N.W0.size());
  Vec3 g[4];
  for (Index e = 0; e < N.T.rows(); ++e) {
    const double V = tet_gradient(N.T, x, e, g);
    for (int c = 0; c < 4; ++c) W[N.T(e, c)] += V;
  }
  for (Index a = 0; a < W.size(); ++a)  // W becomes the nodal p_a = k_a (W_a - W0_a) / (4 W0_a)
    W[a] = N.W0[a] > 0 ? N.k[a] * (W[a] - N.W0[a]) / (4.0 * N.W0[a]) : 0.0;
  for (Index e = 0; e < N.T.rows(); ++e) {
    tet_gradient(N.T, x, e, g);
    const double p = W[N.T(e, 0)] + W[N.T(e, 1)] + W[N.T(e, 2)] + W[N.T(e, 3)];
    for (int c = 0; c < 4; ++c) f.row(N.T(e, c)) -= p * g[c].transpose();
  }
}

void add_nodal_volume_stiffness_triplets(const NodalVolumeTerms& N, const MatX3& x,
                                         std::vector<Eigen::Triplet<double>>& out) {
  const Index n = static_cast<Index>(N.W0.size());
  // the tetrahedra at each node (CSR)
  std::vector<Index> start(static_cast<std::size_t>(n) + 1, 0), at(static_cast<std::size_t>(4 * N.T.rows()));
  for (Index e = 0; e < N.T.rows(); ++e)
    for (int c = 0; c < 4; ++c) ++start[static_cast<std::size_t>(N.T(e, c)) + 1];
  for (Index a = 0; a < n; ++a) start[static_cast<std::size_t>(a) + 1] += start[static_cast<std::size_t>(a)];
  std::vector<Index> fill(start.begin(), start.end() - 1);
  for (Index e = 0; e < N.T.rows(); ++e)
    for (int c = 0; c < 4; ++c) at[static_cast<std::size_t>(fill[static_cast<std::size_t>(N.T(e, c))]++)] = e;
  // per node: G_a = sum over its tetrahedra of dV_e/dx, gathered on the nodes it touches
  std::vector<Index> nodes;
  std::vector<Vec3> G;
  Vec3 g[4];
  for (Index a = 0; a < n; ++a) {
    if (!(N.W0[a] > 0) || N.k[a] == 0) continue;
    nodes.clear();
    G.clear();
    for (Index q = start[static_cast<std::size_t>(a)]; q < start[static_cast<std::size_t>(a) + 1]; ++q) {
      const Index e = at[static_cast<std::size_t>(q)];
      tet_gradient(N.T, x, e, g);
      for (int c = 0; c < 4; ++c) {
        const auto it = std::find(nodes.begin(), nodes.end(), N.T(e, c));
        if (it == nodes.end()) {
          nodes.push_back(N.T(e, c));
          G.push_back(g[c]);
        } else
          G[static_cast<std::size_t>(it - nodes.begin())] += g[c];
      }
    }
    const double s = N.k[a] / (4.0 * N.W0[a]);
    for (std::size_t i = 0; i < nodes.size(); ++i)
      for (std::size_t j = 0; j < nodes.size(); ++j) {
        const Mat3 B = s * G[i] * G[j].transpose();
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) out.emplace_back(3 * nodes[i] + r, 3 * nodes[j] + c, B(r, c));
      }
  }
}

}  // namespace medspring
