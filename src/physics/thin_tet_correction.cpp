// The correction term for thin tetrahedra (thin_tet_correction.hpp; docs/volumetric-mesh.md).
#include "medspring/physics/thin_tet_correction.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "medspring/core/check.hpp"

namespace medspring {
namespace {

constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
const double kSqrt2 = std::sqrt(2.0);

/// The symmetric tensor of a Mandel vector.
Mat3 unmandel(const Vec6& v) {
  Mat3 s;
  s << v[0], v[5] / kSqrt2, v[4] / kSqrt2, v[5] / kSqrt2, v[1], v[3] / kSqrt2, v[4] / kSqrt2, v[3] / kSqrt2,
      v[2];
  return s;
}

Mat3 edge_matrix(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  Mat3 D;
  D.col(0) = p1 - p0;
  D.col(1) = p2 - p0;
  D.col(2) = p3 - p0;
  return D;
}

struct Lame {
  double mu, la;
};
Lame lame(double E, double nu) {
  return {E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))};
}

/// Energy density and, optionally, P = dPsi/dF of Psi = 1/2 e(U - I)^T C e(U - I).
double biot_energy(const Mat6& Cc, const Mat3& F, Mat3* P) {
  Eigen::SelfAdjointEigenSolver<Mat3> es(F.transpose() * F);
  const Mat3& Q = es.eigenvectors();
  Vec3 lam;
  for (int i = 0; i < 3; ++i) lam[i] = std::sqrt(std::max(es.eigenvalues()[i], 0.0));
  const Mat3 U = Q * lam.asDiagonal() * Q.transpose();
  const Vec6 e = mandel(U - Mat3::Identity());
  const Vec6 sigma = Cc * e;
  const double psi = 0.5 * e.dot(sigma);
  if (P) {
    Mat3 Tq = Q.transpose() * unmandel(sigma) * Q;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) Tq(i, j) /= std::max(lam[i] + lam[j], 1e-12);
    *P = 2.0 * F * (Q * Tq * Q.transpose());
  }
  return psi;
}

// The stable step's growth factor of one term at F (header, add_thin_tet_forces).
double growth(const Mat6& Cc, double c_max, const Mat3& F) {
  const Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullV);
  const Vec3 sg = svd.singularValues();
  double rho = 0.5;
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) {
      const double d = sg[i] + sg[j];
      rho = std::max(rho, d > 0 ? (sg[i] * sg[i] + sg[j] * sg[j]) / (d * d) : 1.0);
    }
  const Mat3& V = svd.matrixV();
  const Mat3 U = V * sg.asDiagonal() * V.transpose();
  const double T = (Cc * mandel(U - Mat3::Identity())).norm();  // |T|_F (Mandel keeps the norm)
  const double smin = std::max(sg.minCoeff(), 1e-12);
  return 2.0 * rho + 3.0 * T / (smin * c_max);
}

// The deformation gradient of term u at positions x (its rest edge matrix inverted in C.DmInv).
Mat3 deformation_gradient(const ThinTetCorrections& C, const MatX3& x, std::size_t u) {
  const auto& n = C.n[u];
  return edge_matrix(x.row(n[0]).transpose(), x.row(n[1]).transpose(), x.row(n[2]).transpose(),
                     x.row(n[3]).transpose()) *
         C.DmInv[u];
}

}  // namespace

Vec6 mandel(const Mat3& s) {
  Vec6 v;
  v << s(0, 0), s(1, 1), s(2, 2), kSqrt2 * 0.5 * (s(1, 2) + s(2, 1)), kSqrt2 * 0.5 * (s(0, 2) + s(2, 0)),
      kSqrt2 * 0.5 * (s(0, 1) + s(1, 0));
  return v;
}

double tet_quality(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  const Vec3 p[4] = {p0, p1, p2, p3};
  const double V = std::abs((p1 - p0).dot((p2 - p0).cross(p3 - p0))) / 6.0;
  double amax = 0, lmax = 0;
  for (int k = 0; k < 4; ++k) {
    const Vec3& a = p[(k + 1) % 4];
    const Vec3& b = p[(k + 2) % 4];
    const Vec3& c = p[(k + 3) % 4];
    amax = std::max(amax, 0.5 * (b - a).cross(c - a).norm());
  }
  for (const auto& e : kEdges) lmax = std::max(lmax, (p[e[1]] - p[e[0]]).norm());
  if (amax <= 0 || lmax <= 0) return 0;
  return 3.0 * V / amax / lmax;
}

Mat6 p1_mandel_stiffness(double E, double nu) {
  const Lame l = lame(E, nu);
  Vec6 d;
  d << 1, 1, 1, 0, 0, 0;
  return l.la * d * d.transpose() + 2 * l.mu * Mat6::Identity();
}

Mat6 rule_mandel_stiffness(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3,
                           const ThinTetSettings& s, double spring_factor) {
  const Lame l = lame(s.E, s.nu);
  const Vec3 p[4] = {p0, p1, p2, p3};
  Mat6 C = Mat6::Zero();
  for (const auto& e : kEdges) {
    const Vec3 n = (p[e[1]] - p[e[0]]).normalized();
    const Vec6 m = mandel(n * n.transpose());
    C += (spring_factor * s.spring_scale * 2.5 * l.mu) * m * m.transpose();  // (1/V) k_e L_e^2 m m^T
  }
  Vec6 d;
  d << 1, 1, 1, 0, 0, 0;
  C += s.volume_scale * std::max(l.la - l.mu, 0.0) * d * d.transpose();
  return C;
}

ThinTetCorrections build_thin_tet_corrections(const MatX3& x0, const std::vector<std::array<Index, 4>>& tets,
                                              const ThinTetSettings& s, const std::string& what) {
  require_positive(s.E, what, ": E");
  require(std::isfinite(s.nu) && s.nu >= 0 && s.nu < 0.5, what, ": nu must be in [0, 0.5) (got ", s.nu, ")");
  require(std::isfinite(s.q_max) && s.q_max > 0, what, ": q_max must be > 0 (got ", s.q_max, ")");
  require(std::isfinite(s.spring_scale) && s.spring_scale >= 0 && std::isfinite(s.volume_scale) &&
              s.volume_scale >= 0,
          what, ": spring_scale and volume_scale must be finite and >= 0");
  const Mat6 Cp1 = p1_mandel_stiffness(s.E, s.nu);
  const double two_mu = 2 * lame(s.E, s.nu).mu;
  ThinTetCorrections C;
  const Index N = static_cast<Index>(x0.rows());
  for (std::size_t t = 0; t < tets.size(); ++t) {
    const auto& n = tets[t];
    for (int k = 0; k < 4; ++k)
      require(n[static_cast<std::size_t>(k)] >= 0 && n[static_cast<std::size_t>(k)] < N, what,
              ": tetrahedron ", t, " corner ", k, " = ", n[static_cast<std::size_t>(k)],
              " is out of range [0, ", N, ")");
    const Vec3 p0 = x0.row(n[0]).transpose(), p1 = x0.row(n[1]).transpose(), p2 = x0.row(n[2]).transpose(),
               p3 = x0.row(n[3]).transpose();
    const Mat3 D = edge_matrix(p0, p1, p2, p3);
    const double V = D.determinant() / 6.0;
    double lmax = 0;
    const Vec3 p[4] = {p0, p1, p2, p3};
    for (const auto& e : kEdges) lmax = std::max(lmax, (p[e[1]] - p[e[0]]).norm());
    require(std::isfinite(V) && V > 1e-12 * lmax * lmax * lmax, what, ": tetrahedron ", t,
            " is inverted or degenerate at rest (volume ", V, " mm^3)");
    if (tet_quality(p0, p1, p2, p3) >= s.q_max) continue;
    double factor = 1.0;
    Mat6 Dc = Cp1 - rule_mandel_stiffness(p0, p1, p2, p3, s);
    if (s.projection == ThinTetProjection::ScaleSprings) {
      // the largest s <= 1 with A - s B PSD, A = C_P1 - C_vol, B = C_spr: s = 1 / lambda_max(L^-1 B L^-T)
      const Mat6 Cvol = rule_mandel_stiffness(p0, p1, p2, p3, s, 0.0);
      const Mat6 A = Cp1 - Cvol, Bs = rule_mandel_stiffness(p0, p1, p2, p3, s) - Cvol;
      const Eigen::LLT<Mat6> llt(A);
      if (llt.info() == Eigen::Success) {
        const Mat6 Linv = llt.matrixL().solve(Mat6::Identity());
        const Mat6 M = Linv * Bs * Linv.transpose();
        const double emax =
            Eigen::SelfAdjointEigenSolver<Mat6>(0.5 * (M + M.transpose())).eigenvalues().maxCoeff();
        if (emax > 1.0) factor = 1.0 / emax;
        Dc = A - factor * Bs;
      }  // else (a volume term stiffer than P1 in some mode): the clip
    }
    Eigen::SelfAdjointEigenSolver<Mat6> es(0.5 * (Dc + Dc.transpose()));
    const Vec6 ev = es.eigenvalues().cwiseMax(0.0);
    C.n.push_back(n);
    C.tet.push_back(static_cast<Index>(t));
    C.DmInv.push_back(D.inverse());
    C.V0.push_back(V);
    C.C.push_back(es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose());
    C.clipped.push_back(std::max(-es.eigenvalues().minCoeff(), 0.0) / two_mu);
    C.spring_factor.push_back(factor);
    C.c_max.push_back(ev.maxCoeff());
  }
  return C;
}

double thin_tet_energy(const ThinTetCorrections& C, const MatX3& x) {
  double E = 0;
  for (Index t = 0; t < C.size(); ++t) {
    const auto u = static_cast<std::size_t>(t);
    E += C.V0[u] * biot_energy(C.C[u], deformation_gradient(C, x, u), nullptr);
  }
  return E;
}

void add_thin_tet_forces(const ThinTetCorrections& C, const MatX3& x, MatX3& f) {
  add_thin_tet_forces(C, x, f, false);
}

double add_thin_tet_forces(const ThinTetCorrections& C, const MatX3& x, MatX3& f, bool stiffening) {
  double grow = 1.0;
  for (Index t = 0; t < C.size(); ++t) {
    const auto u = static_cast<std::size_t>(t);
    const auto& n = C.n[u];
    const Mat3 F = deformation_gradient(C, x, u);
    Mat3 P;
    biot_energy(C.C[u], F, &P);
    const Mat3 H = -C.V0[u] * P * C.DmInv[u].transpose();  // columns: forces on corners 1..3
    for (int k = 0; k < 3; ++k) f.row(n[static_cast<std::size_t>(k + 1)]) += H.col(k).transpose();
    f.row(n[0]) -= (H.col(0) + H.col(1) + H.col(2)).transpose();
    if (stiffening && C.c_max[u] > 0) grow = std::max(grow, growth(C.C[u], C.c_max[u], F));
  }
  return grow;
}

namespace {

// The polar rotation of F (U V^T of its SVD; a reflection where F is inverted: still orthogonal, so the
// co-rotated stiffness stays positive semi-definite).
Mat3 polar_rotation(const Mat3& F) {
  const Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

}  // namespace

void add_thin_tet_stiffness_product(const ThinTetCorrections& C, const MatX3& x, const VecX& p, VecX& y) {
  for (Index t = 0; t < C.size(); ++t) {
    const auto u = static_cast<std::size_t>(t);
    const auto& n = C.n[u];
    const Mat3 F = deformation_gradient(C, x, u);
    const Mat3 R = polar_rotation(F);
    Vec3 q[4];
    for (int k = 0; k < 4; ++k) q[k] = R.transpose() * p.segment<3>(3 * n[static_cast<std::size_t>(k)]);
    Mat3 Dq;
    for (int k = 0; k < 3; ++k) Dq.col(k) = q[k + 1] - q[0];
    const Mat3 G = Dq * C.DmInv[u];
    const Mat3 S = unmandel(C.C[u] * mandel(0.5 * (G + G.transpose())));
    const Mat3 H = R * (C.V0[u] * S * C.DmInv[u].transpose());  // columns: K p on corners 1..3
    for (int k = 0; k < 3; ++k) y.segment<3>(3 * n[static_cast<std::size_t>(k + 1)]) += H.col(k);
    y.segment<3>(3 * n[0]) -= H.col(0) + H.col(1) + H.col(2);
  }
}

void add_thin_tet_stiffness_triplets(const ThinTetCorrections& C, const MatX3& x,
                                     std::vector<Eigen::Triplet<double>>& T) {
  for (Index t = 0; t < C.size(); ++t) {
    const auto u = static_cast<std::size_t>(t);
    const auto& n = C.n[u];
    const Mat3 F = deformation_gradient(C, x, u);
    const Mat3 R = polar_rotation(F);
    const Mat12 K = thin_tet_rest_stiffness(C, t);
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const Mat3 B = R * K.block<3, 3>(3 * a, 3 * b) * R.transpose();
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            T.emplace_back(3 * n[static_cast<std::size_t>(a)] + i, 3 * n[static_cast<std::size_t>(b)] + j,
                           B(i, j));
      }
  }
}

void validate_thin_tet_corrections(const ThinTetCorrections& C, Index nodes, const std::string& what) {
  const auto nt = static_cast<std::size_t>(C.size());
  require(C.tet.size() == nt && C.DmInv.size() == nt && C.V0.size() == nt && C.C.size() == nt &&
              C.clipped.size() == nt && C.spring_factor.size() == nt && C.c_max.size() == nt,
          what, ": thin-tetrahedron terms: arrays have inconsistent sizes");
  for (std::size_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k)
      require(C.n[t][static_cast<std::size_t>(k)] >= 0 && C.n[t][static_cast<std::size_t>(k)] < nodes, what,
              ": thin-tetrahedron term ", t, ": corner ", k, " = ", C.n[t][static_cast<std::size_t>(k)],
              " out of range [0, ", nodes, ")");
    require(std::isfinite(C.V0[t]) && C.V0[t] > 0, what, ": thin-tetrahedron term ", t,
            ": rest volume must be > 0 (got ", C.V0[t], ")");
    require(C.DmInv[t].allFinite() && C.C[t].allFinite() && std::isfinite(C.c_max[t]) && C.c_max[t] >= 0,
            what, ": thin-tetrahedron term ", t, ": non-finite rest data");
  }
}

namespace {
Mat12 rest_stiffness(const Mat3& Di, double V, const Mat6& C) {
  Eigen::Matrix<double, 6, 12> B;
  for (int k = 0; k < 4; ++k) {
    const Vec3 g =
        k == 0 ? Vec3(-(Di.row(0) + Di.row(1) + Di.row(2)).transpose()) : Vec3(Di.row(k - 1).transpose());
    for (int a = 0; a < 3; ++a) {
      const Mat3 H = Vec3::Unit(a) * g.transpose();  // displacement gradient of a unit displacement
      B.col(3 * k + a) = mandel(0.5 * (H + H.transpose()));
    }
  }
  return V * B.transpose() * C * B;
}
}  // namespace

Mat12 thin_tet_rest_stiffness(const ThinTetCorrections& C, Index t) {
  const auto u = static_cast<std::size_t>(t);
  return rest_stiffness(C.DmInv[u], C.V0[u], C.C[u]);
}

Mat12 tet_mandel_rest_stiffness(const MatX3& x0, const std::array<Index, 4>& tet, const Mat6& C) {
  const Mat3 D = edge_matrix(x0.row(tet[0]).transpose(), x0.row(tet[1]).transpose(),
                             x0.row(tet[2]).transpose(), x0.row(tet[3]).transpose());
  return rest_stiffness(D.inverse(), D.determinant() / 6.0, C);
}

Eigen::SparseMatrix<double> thin_tet_rest_stiffness_change(const ThinTetCorrections& C, const MatX3& x0,
                                                           const ThinTetSettings& s) {
  std::vector<Eigen::Triplet<double>> trip;
  for (Index t = 0; t < C.size(); ++t) {
    const auto u = static_cast<std::size_t>(t);
    const auto& n = C.n[u];
    Mat12 K = thin_tet_rest_stiffness(C, t);
    if (C.spring_factor[u] != 1.0) {
      const Vec3 p0 = x0.row(n[0]), p1 = x0.row(n[1]), p2 = x0.row(n[2]), p3 = x0.row(n[3]);
      const Mat6 Cspr =
          rule_mandel_stiffness(p0, p1, p2, p3, s) - rule_mandel_stiffness(p0, p1, p2, p3, s, 0.0);
      K += (C.spring_factor[u] - 1.0) * rest_stiffness(C.DmInv[u], C.V0[u], Cspr);
    }
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            trip.emplace_back(3 * n[static_cast<std::size_t>(a)] + i, 3 * n[static_cast<std::size_t>(b)] + j,
                              K(3 * a + i, 3 * b + j));
  }
  const Index N = static_cast<Index>(x0.rows());
  Eigen::SparseMatrix<double> out(3 * N, 3 * N);
  out.setFromTriplets(trip.begin(), trip.end());
  return out;
}

void add_thin_tet_gershgorin(const ThinTetCorrections& C, const VecX& mass,
                             const std::vector<std::uint8_t>& fixed, VecX& diag, VecX& off) {
  for (Index t = 0; t < C.size(); ++t) {
    const Mat12 K = thin_tet_rest_stiffness(C, t);
    const auto& n = C.n[static_cast<std::size_t>(t)];
    for (int k = 0; k < 4; ++k) {
      const Index i = n[static_cast<std::size_t>(k)];
      diag[i] += K.block<3, 3>(3 * k, 3 * k).norm();
      for (int l = 0; l < 4; ++l) {
        const Index j = n[static_cast<std::size_t>(l)];
        if (l == k || fixed[static_cast<std::size_t>(j)]) continue;
        off[i] += K.block<3, 3>(3 * k, 3 * l).norm() / std::sqrt(mass[i] * mass[j]);
      }
    }
  }
}

}  // namespace medspring
