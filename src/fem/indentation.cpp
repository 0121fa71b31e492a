#include "medspring/fem/indentation.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/fem/matching.hpp"
#include "medspring/fem/validation.hpp"

namespace medspring::fem {

namespace {

void check_settings(const SphereIndentation& s) {
  require(std::isfinite(s.radius) && s.radius > 0, "sphere indentation: radius must be > 0 mm (got ",
          s.radius, ")");
  require(s.touch_centre.allFinite(), "sphere indentation: touch_centre must be finite");
  require(s.direction.allFinite() && s.direction.norm() > 1e-12,
          "sphere indentation: direction must be nonzero");
  require(!s.depths.empty(), "sphere indentation: no depths");
  for (std::size_t i = 0; i < s.depths.size(); ++i) {
    require(std::isfinite(s.depths[i]) && s.depths[i] > 0, "sphere indentation: depths[", i, "] must be > 0");
    require(i == 0 || s.depths[i] > s.depths[i - 1], "sphere indentation: depths must increase (depths[", i,
            "])");
  }
  require(std::isfinite(s.symmetry_factor) && s.symmetry_factor > 0,
          "sphere indentation: symmetry_factor must be > 0");
  require(s.max_iterations >= 1, "sphere indentation: max_iterations must be >= 1");
  require(std::isfinite(s.tolerance) && s.tolerance >= 0, "sphere indentation: tolerance must be >= 0");
}

}  // namespace

double hertz_force(const Material& m, double R, double depth) {
  return 4.0 / 3.0 * m.E / (1 - m.nu * m.nu) * std::sqrt(R) * std::pow(std::max(depth, 0.0), 1.5);
}

std::vector<IndentationPoint> sphere_indentation(const FemProblem& base, const SphereIndentation& s,
                                                 const FemSettings& settings) {
  check_settings(s);
  validate_problem(base);
  const Vec3 d = s.direction.normalized();
  // Frame in which the sphere moves along -z: x_r = Q x.
  const Mat3 Q = Eigen::Quaterniond::FromTwoVectors(d, Vec3(0, 0, -1)).toRotationMatrix();
  const bool identity = (Q - Mat3::Identity()).norm() < 1e-12;
  require(identity || base.constraints.empty(),
          "sphere indentation: single-component constraints of the base problem need direction (0, 0, -1)");
  FemProblem rot = base;
  if (!identity) rot.mesh.X = base.mesh.X * Q.transpose();
  const MatX3& X = rot.mesh.X;
  const Index n = static_cast<Index>(X.rows());
  const Vec3 c0 = Q * s.touch_centre;
  const double R = s.radius;

  std::vector<std::uint8_t> candidate(static_cast<std::size_t>(n), 0);
  for (Index v : boundary_nodes(rot.mesh)) candidate[static_cast<std::size_t>(v)] = 1;
  for (Index v : rot.fixed) candidate[static_cast<std::size_t>(v)] = 0;
  for (const auto& c : rot.constraints)
    if (c.dof == 2) candidate[static_cast<std::size_t>(c.node)] = 0;  // z already imposed (e.g. supports)

  FemSettings fs = settings;
  fs.reaction_forces = true;
  MatX3 u = MatX3::Zero(n, 3);  // the last solution (warm start of the next depth's active set)
  double force = 0;
  std::vector<IndentationPoint> out;
  for (double depth : s.depths) {
    const Vec3 C = c0 + depth * Vec3(0, 0, -1);
    auto inside = [&](Index i) {
      const Vec3 x = X.row(i).transpose() + u.row(i).transpose();
      return (x - C).norm() < R - s.tolerance;
    };
    std::vector<std::uint8_t> active(static_cast<std::size_t>(n), 0);
    for (Index i = 0; i < n; ++i)
      if (candidate[static_cast<std::size_t>(i)] && inside(i)) active[static_cast<std::size_t>(i)] = 1;
    IndentationPoint pt;
    pt.depth = depth;
    MatX3 rf;
    for (int it = 0; it < s.max_iterations; ++it) {
      FemProblem p = rot;
      Eigen::MatrixX2d lateral(n, 2);  // the lateral positions the imposed values were computed from
      for (Index i = 0; i < n; ++i) {
        if (!active[static_cast<std::size_t>(i)]) continue;
        const Vec3 x = X.row(i).transpose() + u.row(i).transpose();
        const double rho = std::hypot(x(0) - C(0), x(1) - C(1));
        if (rho >= R) {
          active[static_cast<std::size_t>(i)] = 0;
          continue;
        }
        lateral.row(i) << x(0), x(1);
        p.constraints.push_back({i, 2, C(2) - std::sqrt(R * R - rho * rho) - X(i, 2)});
      }
      if (s.update_boundary) s.update_boundary(p, force);
      const FemResult r = solve(p, fs);
      pt.solve_seconds += r.solve_seconds;
      pt.iterations = it + 1;
      u = r.u;
      rf = r.rf;
      const double previous = force;
      force = 0;
      Vec3 reaction = Vec3::Zero();
      pt.contact_nodes = 0;
      pt.contact_radius = 0;
      for (Index i = 0; i < n; ++i) {
        if (!active[static_cast<std::size_t>(i)]) continue;
        ++pt.contact_nodes;
        force -= rf(i, 2);
        reaction += rf.row(i).transpose();  // the sphere on the tissue; the tissue on the sphere is minus it
        const Vec3 x = X.row(i).transpose() + u.row(i).transpose();
        pt.contact_radius = std::max(pt.contact_radius, std::hypot(x(0) - C(0), x(1) - C(1)));
      }
      force *= s.symmetry_factor;
      // in the original frame (x = Q^T x_r); with symmetry planes only the component along d is summed
      pt.reaction = s.symmetry_factor == 1.0 ? Vec3(-(Q.transpose() * reaction)) : Vec3(-force * d);
      // release the nodes the sphere pulls (reaction along +z), add the free nodes inside the sphere
      bool changed = false;
      double moved = 0;
      for (Index i = 0; i < n; ++i) {
        auto& a = active[static_cast<std::size_t>(i)];
        if (a && rf(i, 2) > 0) {
          a = 0;
          changed = true;
        } else if (!a && candidate[static_cast<std::size_t>(i)] && inside(i)) {
          a = 1;
          changed = true;
        } else if (a) {
          moved = std::max(moved,
                           std::hypot(X(i, 0) + u(i, 0) - lateral(i, 0), X(i, 1) + u(i, 1) - lateral(i, 1)));
        }
      }
      const bool force_settled =
          !s.update_boundary || std::abs(force - previous) <= 1e-3 * std::max(std::abs(force), 1e-12);
      if (!changed && moved <= std::max(s.tolerance, 1e-9) && force_settled) {
        pt.converged = true;
        break;
      }
    }
    pt.force = force;
    pt.u = identity ? u : MatX3(u * Q);  // rows: u_orig = Q^T u_r
    out.push_back(std::move(pt));
  }
  return out;
}

Vec3 first_touch_centre(const MatX3& V, const MatX3i& F, double R, const Vec3& axis_point,
                        const Vec3& direction) {
  require(std::isfinite(R) && R > 0, "first_touch_centre: radius must be > 0");
  require(direction.allFinite() && direction.norm() > 1e-12, "first_touch_centre: direction must be nonzero");
  const Vec3 d = direction.normalized();
  // the centre is axis_point + t d; a surface point x touches when its lateral distance rho from the
  // axis is < R and t = (x - axis_point).d - sqrt(R^2 - rho^2); the first touch is the smallest t
  constexpr int kGrid = 24;
  double best = std::numeric_limits<double>::infinity();
  for (Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = V.row(F(f, 0)).transpose(), b = V.row(F(f, 1)).transpose(), c = V.row(F(f, 2)).transpose();
    // the face itself: the sphere touches its plane at x = centre - R n (n facing the sphere)
    Vec3 n = (b - a).cross(c - a);
    if (n.norm() > 0) {
      n.normalize();
      if (n.dot(d) > 0) n = -n;
      if (n.dot(d) < -1e-12) {
        const double t = (R - n.dot(axis_point - a)) / n.dot(d);
        const Vec3 x = axis_point + t * d - R * n;
        // barycentric test of x in the triangle
        const Vec3 v0 = b - a, v1 = c - a, v2 = x - a;
        const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
        const double den = d00 * d11 - d01 * d01;
        const double beta = (d11 * d20 - d01 * d21) / den, gamma = (d00 * d21 - d01 * d20) / den;
        if (beta >= 0 && gamma >= 0 && beta + gamma <= 1) best = std::min(best, t);
      }
    }
    // edges and corners: sampled
    for (int i = 0; i <= kGrid; ++i)
      for (int j = 0; i + j <= kGrid; ++j) {
        const double u = static_cast<double>(i) / kGrid, v = static_cast<double>(j) / kGrid;
        const Vec3 x = a + u * (b - a) + v * (c - a) - axis_point;
        const double s = x.dot(d);
        const double rho2 = (x - s * d).squaredNorm();
        if (rho2 >= R * R) continue;
        best = std::min(best, s - std::sqrt(R * R - rho2));
      }
  }
  require(std::isfinite(best), "first_touch_centre: the sphere's axis misses the surface");
  return axis_point + best * d;
}

std::pair<double, double> principal_curvatures(const MatX3& V, const Vec3& point, const Vec3& direction,
                                               double radius) {
  const Vec3 nrm = -direction.normalized();  // outward normal at the point
  Vec3 e1 = nrm.unitOrthogonal(), e2 = nrm.cross(e1);
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Vec3 b = Vec3::Zero();
  Index used = 0;
  for (Index i = 0; i < V.rows(); ++i) {
    const Vec3 x = V.row(i).transpose() - point;
    if (x.norm() > radius) continue;
    const double px = x.dot(e1), py = x.dot(e2), h = x.dot(nrm);
    const Vec3 row(0.5 * px * px, px * py, 0.5 * py * py);
    A += row * row.transpose();
    b += row * h;
    ++used;
  }
  require(used >= 6, "principal_curvatures: fewer than 6 vertices within ", radius, " mm");
  const Vec3 q = A.ldlt().solve(b);
  Eigen::Matrix2d H;
  H << q(0), q(1), q(1), q(2);
  const Eigen::Vector2d k = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(H).eigenvalues();
  // a convex surface bends away from its outward normal (h < 0 around the point): curvature -eig
  return {-k(1), -k(0)};
}

std::vector<ValidationResult> validate_hertz(int level, const FemSettings& fs) {
  require(level >= 1 && level <= 3, "validation level must be 1, 2 or 3");
  const double R = 10.0, L = 20.0;
  const Material mat = Material::from_kpa(10, 0.45);
  const int n = 4 + 2 * level;
  const auto xs = graded(0, L, n, 1.6);
  const auto zs = graded(-L, 0, n, 1.0 / 1.6);
  FemProblem p{box_mesh(xs, xs, zs), mat};
  for (Index v : nodes_on_plane(p.mesh, 0, 0.0)) p.constraints.push_back({v, 0, 0.0});
  for (Index v : nodes_on_plane(p.mesh, 1, 0.0)) p.constraints.push_back({v, 1, 0.0});
  std::vector<Index> far;
  for (int axis : {0, 1, 2})
    for (Index v : nodes_on_plane(p.mesh, axis, axis == 2 ? -L : L)) far.push_back(v);
  std::sort(far.begin(), far.end());
  far.erase(std::unique(far.begin(), far.end()), far.end());
  // the far faces carry the point-load field of the current force (they are not contact candidates:
  // their z is imposed); the base problem holds them at zero so it has no rigid motion
  for (Index v : far)
    for (int k = 0; k < 3; ++k) p.constraints.push_back({v, k, 0.0});
  const std::size_t far_begin = p.constraints.size() - 3 * far.size();
  SphereIndentation s;
  s.radius = R;
  s.touch_centre = Vec3(0, 0, R);
  s.direction = Vec3(0, 0, -1);
  s.depths = level == 1 ? std::vector<double>{0.2} : std::vector<double>{0.1, 0.2, 0.4};
  s.symmetry_factor = 4;
  s.update_boundary = [&](FemProblem& q, double force) {
    for (std::size_t j = far_begin; j < far_begin + 3 * far.size(); ++j) {
      auto& c = q.constraints[j];
      c.value = boussinesq_displacement(mat, force, q.mesh.X.row(c.node).transpose())(c.dof);
    }
  };
  std::vector<ValidationResult> out;
  for (const IndentationPoint& pt : sphere_indentation(p, s, fs)) {
    ValidationResult r{cat("hertz d = ", pt.depth, " mm"), level};
    r.nodes = p.mesh.num_nodes();
    r.elements = p.mesh.num_elements();
    r.quantity = cat("force of a rigid sphere R = ", R, " mm at depth ", pt.depth, " mm, N");
    r.fem = pt.force;
    r.analytic = hertz_force(mat, R, pt.depth);
    r.rel_error = std::abs(r.fem - r.analytic) / r.analytic;
    r.solve_seconds = pt.solve_seconds;
    out.push_back(r);
  }
  return out;
}

}  // namespace medspring::fem
