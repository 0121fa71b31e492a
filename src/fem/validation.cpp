#include "medspring/fem/validation.hpp"

#include <cmath>
#include <numbers>

#include "medspring/core/check.hpp"
#include "medspring/fem/matching.hpp"

namespace medspring::fem {

namespace {

// Lateral stretch l2 with zero lateral Cauchy stress for axial stretch l1, and the nominal stress.
// sigma = 2 C10 / J^(5/3) dev(B) + 2 / D1 (J - 1) I, B = diag(l1^2, l2^2, l2^2).
double lateral_stress(const Material& m, double l1, double l2) {
  const double J = l1 * l2 * l2;
  return 2 * m.c10() / std::pow(J, 5.0 / 3.0) * (-(l1 * l1 - l2 * l2) / 3.0) + 2.0 / m.d1() * (J - 1);
}

double lateral_stretch(const Material& m, double l1) {
  double lo = 0.2, hi = 2.0;  // lateral_stress increases with l2
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (lateral_stress(m, l1, mid) > 0 ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

double nominal_stress(const Material& m, double l1) {
  const double l2 = lateral_stretch(m, l1), J = l1 * l2 * l2;
  const double s11 = 2 * m.c10() / std::pow(J, 5.0 / 3.0) * (l1 * l1 - l2 * l2);
  return s11 * l2 * l2;
}

ValidationResult finish(ValidationResult r, const FemProblem& p, const FemResult& res) {
  r.nodes = p.mesh.num_nodes();
  r.elements = p.mesh.num_elements();
  r.rel_error = std::abs(r.fem - r.analytic) / std::abs(r.analytic);
  r.solve_seconds = res.solve_seconds;
  return r;
}

}  // namespace

std::vector<Index> nodes_on_plane(const TetMesh& m, int axis, double value) {
  std::vector<Index> out;
  for (Index i = 0; i < m.num_nodes(); ++i)
    if (std::abs(m.X(i, axis) - value) < 1e-9) out.push_back(i);
  return out;
}

Vec3 boussinesq_displacement(const Material& m, double F, const Vec3& x) {
  const double G = m.mu(), nu = m.nu;
  const double rho = std::hypot(x(0), x(1)), zeta = -x(2), R = x.norm();
  const double c = F / (4 * std::numbers::pi * G);
  const double ur = c * (rho * zeta / (R * R * R) - (1 - 2 * nu) * rho / (R * (R + zeta)));
  const double uz = c * (zeta * zeta / (R * R * R) + 2 * (1 - nu) / R);
  Vec3 u(0, 0, -uz);
  if (rho > 0) {
    u(0) = ur * x(0) / rho;
    u(1) = ur * x(1) / rho;
  }
  return u;
}

double uniaxial_stretch(const Material& m, double P) {
  validate_material(m);
  double lo = 0.3, hi = 3.0;  // nominal stress increases with the stretch over this range
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (nominal_stress(m, mid) > P ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

ValidationResult validate_uniaxial(int level, const FemSettings& s) {
  require(level >= 1 && level <= 3, "validation level must be 1, 2 or 3");
  const double L = 10.0, P = 0.002;  // mm, MPa
  const int n = level + 1;
  FemProblem p{box_mesh(graded(0, L, n), graded(0, L, n), graded(0, L, n)), Material::from_kpa(10, 0.45)};
  for (int axis = 0; axis < 3; ++axis)
    for (Index v : nodes_on_plane(p.mesh, axis, 0.0)) p.constraints.push_back({v, axis, 0.0});
  const MatX6i B = boundary_faces(p.mesh);
  for (const auto& [node, f] :
       uniform_traction(p.mesh, faces_on_plane(p.mesh, B, 0, L), Vec3(P * L * L, 0, 0)))
    p.loads.push_back({node, f});
  const FemResult res = solve(p, s);
  ValidationResult r{"uniaxial", level};
  r.quantity = "stretch lambda under 2 kPa";
  const auto tip = nodes_on_plane(p.mesh, 0, L);
  double mean = 0;
  for (Index v : tip) mean += res.u(v, 0);
  r.fem = 1.0 + mean / static_cast<double>(tip.size()) / L;
  r.analytic = uniaxial_stretch(p.material, P);
  return finish(r, p, res);
}

ValidationResult validate_cantilever(int level, const FemSettings& s) {
  require(level >= 1 && level <= 3, "validation level must be 1, 2 or 3");
  const double L = 40, b = 4, h = 4;
  const int nx = 10 * level, nyz = level + 1;
  const Material mat{1.0, 0.3};
  const double I = b * h * h * h / 12.0, A = b * h;
  const double target = 0.01 * L;
  const double compliance = L * L * L / (3 * mat.E * I) + L / (5.0 / 6.0 * mat.mu() * A);
  const double F = target / compliance;
  FemProblem p{box_mesh(graded(0, L, nx), graded(0, b, nyz), graded(0, h, nyz)), mat};
  p.fixed = nodes_on_plane(p.mesh, 0, 0.0);
  const MatX6i B = boundary_faces(p.mesh);
  for (const auto& [node, f] : uniform_traction(p.mesh, faces_on_plane(p.mesh, B, 0, L), Vec3(0, 0, -F)))
    p.loads.push_back({node, f});
  const FemResult res = solve(p, s);
  ValidationResult r{"cantilever", level};
  r.quantity = "mean tip deflection, mm";
  const auto tip = nodes_on_plane(p.mesh, 0, L);
  double mean = 0;
  for (Index v : tip) mean += -res.u(v, 2);
  r.fem = mean / static_cast<double>(tip.size());
  r.analytic = F * compliance;
  return finish(r, p, res);
}

std::vector<ValidationResult> validate_boussinesq(int level, const FemSettings& s) {
  require(level >= 1 && level <= 3, "validation level must be 1, 2 or 3");
  const double a = 1.0, R = 10.0, F = 0.01;
  const Material mat{1.0, 0.4};
  const int n = 4 + 2 * level;
  const auto xs = graded(0, R, n, 1.35);
  auto zs = graded(-R, 0, n, 1.0 / 1.35);
  FemProblem p{box_mesh(xs, xs, zs), mat};
  for (Index v : nodes_on_plane(p.mesh, 0, 0.0)) p.constraints.push_back({v, 0, 0.0});
  for (Index v : nodes_on_plane(p.mesh, 1, 0.0)) p.constraints.push_back({v, 1, 0.0});
  for (int axis : {0, 1, 2}) {
    const double value = axis == 2 ? -R : R;
    for (Index v : nodes_on_plane(p.mesh, axis, value)) {
      const Vec3 u = boussinesq_displacement(mat, F, p.mesh.X.row(v));
      for (int d = 0; d < 3; ++d) p.constraints.push_back({v, d, u(d)});
    }
  }
  const MatX6i top = faces_on_plane(p.mesh, boundary_faces(p.mesh), 2, 0.0);
  for (const auto& [node, f] : disk_load_quadratic(p.mesh, top, Vec3::Zero(), a, Vec3(0, 0, -F / 4)))
    p.loads.push_back({node, f});
  const FemResult res = solve(p, s);
  const double pressure = F / (std::numbers::pi * a * a);
  std::vector<ValidationResult> out;
  {
    ValidationResult r{"boussinesq centre", level};
    r.quantity = "indentation under the disk centre, mm";
    const auto centre = points_near_extreme(p.mesh.X, Vec3(0, 0, 1), 1e-9);
    Index c = -1;
    for (Index v : centre)
      if (p.mesh.X.row(v).head<2>().norm() < 1e-9) c = v;
    r.fem = -res.u(c, 2);
    r.analytic = 2 * (1 - mat.nu * mat.nu) * pressure * a / mat.E;
    out.push_back(finish(r, p, res));
  }
  {
    ValidationResult r{"boussinesq r = 3a", level};
    r.quantity = "surface displacement at r = 3 a, mm";
    const MatX3 pt = (MatX3(1, 3) << 3 * a, 0, 0).finished();
    const BoundarySample smp = locate_on_boundary(p.mesh, top, pt);
    r.fem = -interpolate(top, smp, res.u)(0, 2);
    const double k = a / (3 * a);
    r.analytic = 4 * (1 - mat.nu * mat.nu) * pressure * (3 * a) / (std::numbers::pi * mat.E) *
                 (std::comp_ellint_2(k) - (1 - k * k) * std::comp_ellint_1(k));
    out.push_back(finish(r, p, res));
  }
  return out;
}

}  // namespace medspring::fem
