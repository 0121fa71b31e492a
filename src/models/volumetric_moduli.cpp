#include "medspring/models/volumetric_moduli.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/physics/forces.hpp"

namespace medspring {

namespace {

// The Mandel basis of symmetric strains, each with eps:eps = 1: five deviatoric, then the hydrostatic one.
std::array<Mat3, 6> unit_strains() {
  std::array<Mat3, 6> e;
  for (Mat3& m : e) m.setZero();
  const double r2 = std::sqrt(0.5), r6 = 1.0 / std::sqrt(6.0), r3 = 1.0 / std::sqrt(3.0);
  e[0](0, 0) = r2, e[0](1, 1) = -r2;
  e[1](0, 0) = r6, e[1](1, 1) = r6, e[1](2, 2) = -2 * r6;
  e[2](0, 1) = e[2](1, 0) = r2;
  e[3](0, 2) = e[3](2, 0) = r2;
  e[4](1, 2) = e[4](2, 1) = r2;
  e[5] = r3 * Mat3::Identity();
  return e;
}

}  // namespace

MeshModuli mesh_moduli(const Model& model, Index boundary_nodes, double volume, const MatX3i* faces) {
  if (volume <= 0)
    for (double v : model.volume.V0) volume += v;
  return mesh_moduli(tangent_stiffness(model, model.x0, {.include_return = false}), model.x0, boundary_nodes,
                     volume, faces, model.name);
}

MeshModuli mesh_moduli(const Eigen::SparseMatrix<double>& K, const MatX3& X, Index boundary_nodes,
                       double volume, const MatX3i* faces, const std::string& name) {
  const Index n = static_cast<Index>(X.rows()), nb = boundary_nodes, ni = n - nb;
  require(nb >= 1 && ni >= 0, "mesh_moduli: ", name, ": boundary nodes ", nb, " must be in [1, ", n, "]");
  require(K.rows() == 3 * n && K.cols() == 3 * n, "mesh_moduli: ", name, ": the stiffness is ", K.rows(),
          " x ", K.cols(), " for ", n, " nodes");
  require(std::isfinite(volume) && volume > 0, "mesh_moduli: ", name,
          ": no volume (give it, or a model with volume terms)");
  MeshModuli out;
  out.volume = volume;
  const Index db = 3 * nb, di = 3 * ni;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  Eigen::SparseMatrix<double> Kib;
  if (ni > 0) {
    const Eigen::SparseMatrix<double> Kii = K.bottomRightCorner(di, di);
    Kib = K.bottomLeftCorner(di, db);
    ldlt.compute(Kii);
    if (ldlt.info() != Eigen::Success)
      throw SolverError(cat("mesh_moduli: ", name, ": the interior stiffness could not be factorised"));
  }
  const auto eps = unit_strains();
  std::array<VecX, 6> u, ua;
  for (int a = 0; a < 6; ++a) {
    ua[static_cast<std::size_t>(a)].resize(3 * n);
    for (Index i = 0; i < n; ++i)
      ua[static_cast<std::size_t>(a)].segment<3>(3 * i) =
          eps[static_cast<std::size_t>(a)] * X.row(i).transpose();
    VecX& v = u[static_cast<std::size_t>(a)];
    v = ua[static_cast<std::size_t>(a)];
    if (ni > 0) v.tail(di) = -ldlt.solve(Kib * v.head(db));
    if (!v.allFinite())
      throw SolverError(cat("mesh_moduli: ", name, ": the interior is not held (singular stiffness)"));
  }
  auto energy = [&](const VecX& v) { return 0.5 * v.dot(K * v) / volume; };  // per unit volume
  out.mu_min = 1e300;
  out.mu_max = -1e300;
  for (int a = 0; a < 5; ++a) {
    const double m = energy(u[static_cast<std::size_t>(a)]);  // W/V = mu eps:eps for a deviatoric unit strain
    out.mu += m / 5;
    out.mu_min = std::min(out.mu_min, m);
    out.mu_max = std::max(out.mu_max, m);
    out.mu_affine += energy(ua[static_cast<std::size_t>(a)]) / 5;
  }
  // hydrostatic unit strain: W/V = mu + 3 lambda / 2 = 3 K / 2
  out.K = 2.0 / 3.0 * energy(u[5]);
  out.K_affine = 2.0 / 3.0 * energy(ua[5]);
  if (faces) {
    // free body under uniform tractions: (K + delta I) u = f; f is self-equilibrated (no net force or
    // moment for a closed surface and a symmetric sigma), so the tiny shift only fixes the rigid motion
    Eigen::SparseMatrix<double> Ks = K;
    const double delta = 1e-9 * K.diagonal().cwiseAbs().maxCoeff();
    for (Index r = 0; r < 3 * n; ++r) Ks.coeffRef(r, r) += delta;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> full(Ks);
    if (full.info() != Eigen::Success)
      throw SolverError(cat("mesh_moduli: ", name, ": the stiffness could not be factorised"));
    for (int a = 0; a < 6; ++a) {
      VecX f = VecX::Zero(3 * n);
      const Mat3& s = eps[static_cast<std::size_t>(a)];  // unit stress
      for (Index t = 0; t < faces->rows(); ++t) {
        const Index i = (*faces)(t, 0), j = (*faces)(t, 1), k = (*faces)(t, 2);
        require(i >= 0 && i < nb && j >= 0 && j < nb && k >= 0 && k < nb, "mesh_moduli: ", name, ": face ", t,
                " is not over the boundary nodes");
        const Vec3 an =
            0.5 * (X.row(j) - X.row(i)).transpose().cross((X.row(k) - X.row(i)).transpose());  // n A
        const Vec3 fk = s * an / 3.0;
        for (Index v : {i, j, k}) f.segment<3>(3 * v) += fk;
      }
      const VecX uf = full.solve(f);
      const double W = 0.5 * f.dot(uf) / volume;  // complementary energy per volume
      if (a < 5)
        out.mu_traction += 1.0 / (4.0 * W) / 5;  // deviatoric: W/V = sigma:sigma / (4 mu)
      else
        out.K_traction = 1.0 / (6.0 * W);  // sigma = I / sqrt 3: W/V = 1 / (6 K)
    }
  }
  return out;
}

Eigen::SparseMatrix<double> p1_stiffness(const MatX3& X, const MatX4i& T, double mu, double lambda) {
  const Index n = static_cast<Index>(X.rows());
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<std::size_t>(T.rows()) * 144);
  for (Index t = 0; t < T.rows(); ++t) {
    const Vec3 x0 = X.row(T(t, 0)).transpose(), e1 = X.row(T(t, 1)).transpose() - x0,
               e2 = X.row(T(t, 2)).transpose() - x0, e3 = X.row(T(t, 3)).transpose() - x0;
    const double V6 = e1.dot(e2.cross(e3));
    require(std::abs(V6) > 0, "p1_stiffness: tetrahedron ", t, " is degenerate");
    Vec3 g[4];  // shape function gradients
    g[1] = e2.cross(e3) / V6;
    g[2] = e3.cross(e1) / V6;
    g[3] = e1.cross(e2) / V6;
    g[0] = -(g[1] + g[2] + g[3]);
    const double V = std::abs(V6) / 6.0;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const Mat3 Kab = V * (lambda * g[a] * g[b].transpose() + mu * g[b] * g[a].transpose() +
                              mu * g[a].dot(g[b]) * Mat3::Identity());
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) trip.emplace_back(3 * T(t, a) + i, 3 * T(t, b) + j, Kab(i, j));
      }
  }
  Eigen::SparseMatrix<double> K(3 * n, 3 * n);
  K.setFromTriplets(trip.begin(), trip.end());
  return K;
}

ModuliCorrection moduli_correction(const VolumetricMesh& mesh, double mu, double lambda) {
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  const Index n = static_cast<Index>(mesh.X.rows());
  const double kv = std::max(lambda - mu, 0.0), K = lambda + 2.0 * mu / 3.0;
  // rest stiffness of the rule's springs (Ks) and volume terms (Kv), assembled separately
  std::vector<Eigen::Triplet<double>> ts, tv;
  double volume = 0;
  for (Index t = 0; t < mesh.T.rows(); ++t) {
    Vec3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = mesh.X.row(mesh.T(t, k)).transpose();
    const Vec3 e1 = p[1] - p[0], e2 = p[2] - p[0], e3 = p[3] - p[0];
    const double V = std::abs(e1.dot(e2.cross(e3))) / 6.0;
    require(V > 0, "moduli_correction: tetrahedron ", t, " is degenerate");
    volume += V;
    for (const auto& e : kEdges) {
      const Vec3 d = p[e[1]] - p[e[0]];
      const double L2 = d.squaredNorm();
      const Mat3 B = 2.5 * mu * V / L2 * (d * d.transpose()) / L2;
      const Index a = mesh.T(t, e[0]), b = mesh.T(t, e[1]);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          ts.emplace_back(3 * a + i, 3 * a + j, B(i, j));
          ts.emplace_back(3 * b + i, 3 * b + j, B(i, j));
          ts.emplace_back(3 * a + i, 3 * b + j, -B(i, j));
          ts.emplace_back(3 * b + i, 3 * a + j, -B(i, j));
        }
    }
    if (kv > 0) {
      Vec3 g[4];
      g[1] = e2.cross(e3) / 6.0;
      g[2] = e3.cross(e1) / 6.0;
      g[3] = e1.cross(e2) / 6.0;
      g[0] = -(g[1] + g[2] + g[3]);
      const double sgn = e1.dot(e2.cross(e3)) > 0 ? 1.0 : -1.0;  // g up to the orientation (gg^T is even)
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
          const Mat3 B = kv / V * (sgn * g[a]) * (sgn * g[b]).transpose();
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) tv.emplace_back(3 * mesh.T(t, a) + i, 3 * mesh.T(t, b) + j, B(i, j));
        }
    }
  }
  Eigen::SparseMatrix<double> Ks(3 * n, 3 * n), Kv(3 * n, 3 * n);
  Ks.setFromTriplets(ts.begin(), ts.end());
  Kv.setFromTriplets(tv.begin(), tv.end());
  auto measure = [&](double s, double v) {
    const Eigen::SparseMatrix<double> Kt = s * Ks + v * Kv;
    const MeshModuli m = mesh_moduli(Kt, mesh.X, mesh.surface_nodes, volume, &mesh.F, "moduli_correction");
    return std::pair<double, double>{0.5 * (m.mu + m.mu_traction), 0.5 * (m.K + m.K_traction)};
  };
  ModuliCorrection c;
  auto [mu_e, K_e] = measure(1, 1);
  c.mu_before = mu_e / mu;
  c.K_before = K_e / K;
  for (int round = 0; round < 3; ++round) {
    // bulk: the affine value is s 5 mu / 3 + v kv (springs: lambda_s = mu); the relaxation scales it by r
    const double r = K_e / (c.spring * 5.0 * mu / 3.0 + c.volume * kv);
    c.spring *= mu / mu_e;  // shear: the springs (the volume terms add none under affine shear)
    if (kv > 0) c.volume = std::max(0.0, (K / r - c.spring * 5.0 * mu / 3.0) / kv);
    std::tie(mu_e, K_e) = measure(c.spring, c.volume);
  }
  c.mu_after = mu_e / mu;
  c.K_after = K_e / K;
  return c;
}

}  // namespace medspring
