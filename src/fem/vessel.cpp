#include "medspring/fem/vessel.hpp"

#include <array>
#include <cmath>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/physics/static_solve.hpp"

namespace medspring::fem {

namespace {

// C3D10 mid-edge slots 4..9 and the corners they join (tet_mesh.hpp).
constexpr std::array<std::array<int, 2>, 6> kEdges = {{{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}};
constexpr double kTol = 1e-9;

}  // namespace

TubeMesh tube_mesh(const MatX3& C, const MatX3& P, Index spokes, double thickness_ratio,
                   int axial_subdivisions, int layers) {
  const Index n = static_cast<Index>(C.rows()), M = spokes;
  require(n >= 2, "tube mesh: need >= 2 rings (got ", n, ")");
  require(M >= 3, "tube mesh: need >= 3 spokes per ring (got ", M, ")");
  require(P.rows() == n * M, "tube mesh: ", P.rows(), " ring points for ", n, " rings x ", M, " spokes");
  require(C.allFinite() && P.allFinite(), "tube mesh: coordinates must be finite");
  require(std::isfinite(thickness_ratio) && thickness_ratio > 0,
          "tube mesh: thickness ratio must be > 0 (got ", thickness_ratio, ")");
  require(axial_subdivisions >= 1 && axial_subdivisions <= 16, "tube mesh: axial subdivisions must be 1..16");
  require(layers >= 1 && layers <= 8, "tube mesh: layers must be 1..8");
  const Index sub = axial_subdivisions, L = layers, R = (n - 1) * sub + 1;
  auto id = [&](Index r, Index j, Index l) { return (r * M + ((j % M + M) % M)) * (L + 1) + l; };
  MatX3 X(R * M * (L + 1), 3);
  VecX axial0(X.rows()), radial0(X.rows());
  for (Index r = 0; r < R; ++r) {
    const Index i = std::min(r / sub, n - 2);
    const double t = static_cast<double>(r - i * sub) / static_cast<double>(sub);
    const Vec3 c = (1 - t) * C.row(i).transpose() + t * C.row(i + 1).transpose();
    for (Index j = 0; j < M; ++j) {
      const Vec3 p = (1 - t) * P.row(i * M + j).transpose() + t * P.row((i + 1) * M + j).transpose();
      require((p - c).norm() > 0, "tube mesh: ring ", i, ", spoke ", j, " has zero radius");
      for (Index l = 0; l <= L; ++l) {
        const double w = static_cast<double>(l) / static_cast<double>(L);
        X.row(id(r, j, l)) = (c + (1 + thickness_ratio * w) * (p - c)).transpose();
        axial0(id(r, j, l)) = static_cast<double>(i) + t;
        radial0(id(r, j, l)) = w;
      }
    }
  }
  // Kuhn split of every (ring, spoke, layer) cell; the parametric volume of permutation p has the sign of
  // p, so sign(volume) * parity is the sign of the map's Jacobian, which must not change.
  const std::array<std::array<int, 3>, 6> perms = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  const std::array<int, 6> parity = {1, -1, -1, 1, 1, -1};
  MatX4i T((R - 1) * M * L * 6, 4);
  Index e = 0;
  int jac = 0;
  for (Index r = 0; r + 1 < R; ++r)
    for (Index j = 0; j < M; ++j)
      for (Index l = 0; l < L; ++l)
        for (std::size_t q = 0; q < perms.size(); ++q) {
          std::array<Index, 3> o{0, 0, 0};
          T(e, 0) = id(r, j, l);
          for (int s = 0; s < 3; ++s) {
            o[static_cast<std::size_t>(perms[q][static_cast<std::size_t>(s)])] = 1;
            T(e, s + 1) = id(r + o[0], j + o[1], l + o[2]);
          }
          const Vec3 a = X.row(T(e, 0)), b = X.row(T(e, 1)), c = X.row(T(e, 2)), d = X.row(T(e, 3));
          const double v = (b - a).cross(c - a).dot(d - a) * parity[q];
          const int sg = v > 0 ? 1 : (v < 0 ? -1 : 0);
          if (jac == 0) jac = sg;
          if (sg == 0 || sg != jac)
            throw InvalidInput(cat("tube mesh: the wall turns inside out between rings ", r / sub, " and ",
                                   r / sub + 1, " (spoke ", j,
                                   "): the bend is sharper than the wall is thick there (rho kappa >= 1)"));
          ++e;
        }
  TubeMesh out;
  out.mesh = make_quadratic(X, T);
  out.rings = n;
  out.spokes = M;
  const Index N = out.mesh.num_nodes(), nc = static_cast<Index>(X.rows());
  out.axial = VecX::Zero(N);
  out.radial = VecX::Zero(N);
  out.axial.head(nc) = axial0;
  out.radial.head(nc) = radial0;
  for (Index k = 0; k < out.mesh.num_elements(); ++k)
    for (int s = 0; s < 6; ++s) {
      const Index m = out.mesh.T(k, 4 + s), a = out.mesh.T(k, kEdges[s][0]), b = out.mesh.T(k, kEdges[s][1]);
      out.axial(m) = 0.5 * (out.axial(a) + out.axial(b));
      out.radial(m) = 0.5 * (out.radial(a) + out.radial(b));
    }
  return out;
}

VesselReference::VesselReference(const SmrmVessel& vessel, const Material& material,
                                 const VesselMeshSettings& settings)
    : settings_(settings) {
  validate_material(material);
  const GridLayout g = vessel.grid();
  require(g.valid(), "vessel reference: '", vessel.name(), "' is not a structured tube (rings x spokes)");
  require(settings.spoke_stride >= 1 && g.spokes % settings.spoke_stride == 0,
          "vessel reference: spoke stride ", settings.spoke_stride, " must divide the ", g.spokes, " spokes");
  require(settings.layers == 1 || settings.layers == 2, "vessel reference: layers must be 1 or 2");
  const Index M = g.spokes / settings.spoke_stride;
  require(M >= 6, "vessel reference: need >= 6 FEM spokes per ring (got ", M, ")");
  atoms_ = vessel.num_atoms();
  require(g.rings == atoms_, "vessel reference: ", g.rings, " rings for ", atoms_, " atoms");
  const MatX3& S = vessel.rest_surface();
  MatX3 P(atoms_ * M, 3);
  for (Index i = 0; i < atoms_; ++i)
    for (Index j = 0; j < M; ++j) P.row(i * M + j) = S.row(i * g.spokes + j * settings.spoke_stride);
  sub_ = settings.axial_subdivisions;
  tube_ = tube_mesh(vessel.rest_atoms(), P, M, settings.thickness_ratio, settings.axial_subdivisions,
                    settings.layers);
  problem_ = FemProblem(tube_.mesh, material);
  for (Index k = 0; k < tube_.mesh.num_nodes(); ++k)
    if (tube_.axial(k) < kTol || tube_.axial(k) > static_cast<double>(atoms_ - 1) - kTol)
      problem_.fixed.push_back(k);  // both end rings clamped (the SMRM fixes both end atoms)
  validate_problem(problem_);
  boundary_ = boundary_faces(problem_.mesh);
  lumen_ = locate_on_boundary(problem_.mesh, boundary_, S);
}

VesselFemResult VesselReference::solve(Index atom, const Vec3& force) const {
  require(atom > 0 && atom + 1 < atoms_, "vessel reference: the loaded atom must be interior (1..",
          atoms_ - 2, ", got ", atom, ")");
  require(force.allFinite() && force.norm() > 0, "vessel reference: the force must be finite and non-zero");
  const double h = std::max(0.5, 1.0 / static_cast<double>(sub_)) + kTol;
  std::vector<Index> rows;
  for (Index t = 0; t < boundary_.rows(); ++t) {
    bool in = true;
    for (int k = 0; k < 3; ++k) {
      const Index v = boundary_(t, k);
      in = in && tube_.radial(v) > 1 - kTol && std::abs(tube_.axial(v) - static_cast<double>(atom)) <= h;
    }
    if (in) rows.push_back(t);
  }
  require(!rows.empty(), "vessel reference: no outer wall around atom ", atom);
  MatX6i band(static_cast<Index>(rows.size()), 6);
  for (std::size_t i = 0; i < rows.size(); ++i) band.row(static_cast<Index>(i)) = boundary_.row(rows[i]);
  FemProblem p = problem_;
  for (const auto& [node, f] : uniform_traction(p.mesh, band, force)) p.loads.push_back({node, f});
  const FemResult r = fem::solve(p, settings_.solver);
  VesselFemResult out;
  out.solve_seconds = r.solve_seconds;
  out.from_cache = r.from_cache;
  out.centerline = MatX3::Zero(atoms_, 3);
  VecX count = VecX::Zero(atoms_);
  for (Index k = 0; k < p.mesh.num_nodes(); ++k) {
    const double a = tube_.axial(k);
    const Index i = static_cast<Index>(std::lround(a));
    if (std::abs(a - static_cast<double>(i)) > kTol || std::abs(tube_.radial(k) - 0.5) > kTol) continue;
    out.centerline.row(i) += r.u.row(k);  // the mid-surface nodes of ring i, evenly spread around
    count(i) += 1;
  }
  for (Index i = 0; i < atoms_; ++i) {
    if (!(count(i) > 0)) throw Error(cat("vessel reference: no mid-surface node on ring ", i));
    out.centerline.row(i) /= count(i);
  }
  out.lumen = interpolate(boundary_, lumen_, r.u);
  return out;
}

MatX3 smrm_centerline_displacement(const Model& chain, Index atom, const Vec3& force) {
  require(atom >= 0 && atom < chain.num_nodes(), "smrm centerline: atom ", atom, " out of range");
  MatX3 f = MatX3::Zero(chain.num_nodes(), 3);
  f.row(atom) = force.transpose();
  const StaticResult r = static_equilibrium(chain, f);
  return r.x - chain.x0;
}

CenterlineError compare_centerline(const MatX3& u_model, const MatX3& u_fem, Index atom) {
  require(u_model.rows() == u_fem.rows() && u_model.rows() > 0, "compare centerline: sizes differ");
  require(atom >= 0 && atom < u_fem.rows(), "compare centerline: atom out of range");
  CenterlineError e;
  e.loaded_fem = u_fem.row(atom).norm();
  e.loaded_model = u_model.row(atom).norm();
  e.loaded_error = (u_model.row(atom) - u_fem.row(atom)).norm();
  const VecX d = (u_model - u_fem).rowwise().norm();
  e.rms = std::sqrt(d.squaredNorm() / static_cast<double>(d.size()));
  e.max = d.maxCoeff();
  return e;
}

}  // namespace medspring::fem
