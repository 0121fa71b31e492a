#include "medspring/fem/organ.hpp"

#include <cmath>
#include <limits>
#include <map>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/local/deformer.hpp"
#include "medspring/local/overlay.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/physics/static_solve.hpp"

namespace medspring::fem {

std::vector<Index> support_nodes(const MatX3& surface, const SupportRule& rule) {
  return points_near_extreme(surface, rule.direction, rule.depth);
}

SurfaceMesh subdivide_midpoint(const SurfaceMesh& surface) {
  SurfaceMesh out;
  const MatX2i E = unique_edges(surface.F);
  std::map<std::pair<Index, Index>, Index> mid;
  const Index n = surface.num_vertices();
  out.V.resize(n + static_cast<Index>(E.rows()), 3);
  out.V.topRows(n) = surface.V;
  for (Index e = 0; e < E.rows(); ++e) {
    mid[std::minmax(E(e, 0), E(e, 1))] = n + e;
    out.V.row(n + e) = 0.5 * (surface.V.row(E(e, 0)) + surface.V.row(E(e, 1)));
  }
  out.F.resize(4 * surface.num_faces(), 3);
  for (Index f = 0; f < surface.num_faces(); ++f) {
    const Index a = surface.F(f, 0), b = surface.F(f, 1), c = surface.F(f, 2);
    const Index ab = mid.at(std::minmax(a, b)), bc = mid.at(std::minmax(b, c)),
                ca = mid.at(std::minmax(c, a));
    out.F.row(4 * f) << a, ab, ca;
    out.F.row(4 * f + 1) << ab, b, bc;
    out.F.row(4 * f + 2) << ca, bc, c;
    out.F.row(4 * f + 3) << ab, bc, ca;
  }
  return out;
}

OrganReference::OrganReference(const SurfaceMesh& surface, const Material& material,
                               const SupportRule& support, const OrganMeshSettings& settings)
    : settings_(settings) {
  validate_material(material);
  require(settings.subdivisions >= 0 && settings.subdivisions <= 4,
          "organ reference: subdivisions must be 0..4");
  TetgenSettings ts;
  ts.max_volume = settings.max_volume;
  ts.radius_edge = settings.radius_edge;
  SurfaceMesh s = surface;
  require_valid_mesh(s, "organ reference: surface", {.closed = true, .manifold = true});
  for (int i = 0; i < settings.subdivisions; ++i) s = subdivide_midpoint(s);
  problem_ = FemProblem(tet_mesh_from_surface(s, ts), material);
  boundary_ = boundary_faces(problem_.mesh);
  problem_.fixed =
      points_near_extreme(problem_.mesh.X, support.direction, support.depth, boundary_nodes(problem_.mesh));
  validate_problem(problem_);  // a support region that leaves rigid motion free is refused here
  sample_ = locate_on_boundary(problem_.mesh, boundary_, surface.V);
}

MatX3 OrganReference::surface_displacement(const ContactLoad& load, double* solve_seconds,
                                           bool* from_cache) const {
  FemProblem p = problem_;
  for (const auto& [node, f] : disk_load_quadratic(p.mesh, boundary_, load.centre, load.radius, load.force))
    p.loads.push_back({node, f});
  const FemResult r = solve(p, settings_.solver);
  if (solve_seconds) *solve_seconds = r.solve_seconds;
  if (from_cache) *from_cache = r.from_cache;
  return interpolate(boundary_, sample_, r.u);
}

namespace {

MatX3 static_surface(const Body& body, const ContactLoad& load, MatX3* f_surface_out) {
  const MatX3& S = body.rest_surface();
  const MatX3 fs = disk_load_linear(S, body.faces(), load.centre, load.radius, load.force);
  const Model& m = body.model();
  MatX3 f_ext = MatX3::Zero(m.num_nodes(), 3);
  for (Index i = 0; i < fs.rows(); ++i)
    if (fs.row(i).squaredNorm() > 0) body.transfer_force(i, fs.row(i).transpose(), f_ext);
  const StaticResult r = static_equilibrium(m, f_ext);
  State st = make_state(m);
  st.x = r.x;
  MatX3 surf;
  body.map_to_surface(st, surf);
  if (f_surface_out) *f_surface_out = fs;
  return surf - S;
}

}  // namespace

MatX3 spring_displacement(const Body& body, const ContactLoad& load) {
  return static_surface(body, load, nullptr);
}

MatX3 spring_displacement_local(const Body& body, const ContactLoad& load, double k_loc) {
  MatX3 u = static_surface(body, load, nullptr);
  const MatX3& S = body.rest_surface();
  const Index contact = nearest_node(S, load.centre);
  LocalDeformationSettings ls;
  ls.patch.k_loc = k_loc > 0 ? k_loc : body.local_stiffness();
  LocalDeformer local =
      LocalDeformer::mesh(vertex_adjacency(body.num_surface_nodes(), unique_edges(body.faces())), S, ls,
                          body.fixed_surface_nodes());
  MatX3 U;
  local.compute(contact, load.force, U);
  MatX3 surf = S + u;
  apply_local_overlay(local.patch(), U, surf);
  return surf - S;
}

SurfaceError compare(const MatX3& u_model, const MatX3& u_fem, Index contact) {
  require(u_model.rows() == u_fem.rows() && u_model.rows() > 0, "compare: sizes differ");
  require(contact >= 0 && contact < u_fem.rows(), "compare: contact node out of range");
  SurfaceError e;
  e.contact_fem = u_fem.row(contact).norm();
  e.contact_model = u_model.row(contact).norm();
  e.contact_error = (u_model.row(contact) - u_fem.row(contact)).norm();
  const VecX d = (u_model - u_fem).rowwise().norm();
  e.rms = std::sqrt(d.squaredNorm() / static_cast<double>(d.size()));
  e.max = d.maxCoeff();
  return e;
}

VecX calibrate_multipliers(const Response& response, Index families,
                           const std::vector<CalibrationCase>& training, int sweeps) {
  require(families >= 1 && !training.empty(), "calibrate: need >= 1 family and >= 1 training load");
  VecX logm = VecX::Zero(families);
  auto cost = [&](const VecX& lm) {
    const VecX m = lm.array().exp().matrix();
    double c = 0;
    for (const auto& t : training) {
      MatX3 u;
      try {
        u = response(m, t.load);
      } catch (const SolverError&) {
        return std::numeric_limits<double>::infinity();
      }
      const double scale = std::max(t.u_fem.rowwise().norm().maxCoeff(), 1e-12);
      c += (u - t.u_fem).squaredNorm() / (scale * scale * static_cast<double>(u.rows()));
      c += (u.row(t.contact) - t.u_fem.row(t.contact)).squaredNorm() / (scale * scale);
    }
    return c;
  };
  const double lo0 = std::log(1e-3), hi0 = std::log(1e3), g = (std::sqrt(5.0) - 1) / 2;
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (Index f = 0; f < families; ++f) {
      // narrower bracket on later sweeps, around the current value
      double lo = sweep == 0 ? lo0 : logm(f) - std::log(10.0),
             hi = sweep == 0 ? hi0 : logm(f) + std::log(10.0);
      VecX x = logm;
      auto at = [&](double v) {
        x(f) = v;
        return cost(x);
      };
      double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
      double fa = at(a), fb = at(b);
      for (int it = 0; it < 24; ++it) {
        if (fa < fb) {
          hi = b;
          b = a;
          fb = fa;
          a = hi - g * (hi - lo);
          fa = at(a);
        } else {
          lo = a;
          a = b;
          fa = fb;
          b = lo + g * (hi - lo);
          fb = at(b);
        }
      }
      logm(f) = 0.5 * (lo + hi);
    }
  return logm.array().exp().matrix();
}

}  // namespace medspring::fem
