#include "medspring/fem/organ.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>
#include <numbers>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/local/deformer.hpp"
#include "medspring/local/overlay.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/linear_response.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/physics/static_solve.hpp"

namespace medspring::fem {

std::vector<Index> apply_support_rule(const MatX3& P, const MatX3& N, const SupportRule& rule,
                                      const std::vector<Index>& candidates) {
  require(std::isfinite(rule.facing_deg) && rule.facing_deg >= 0 && rule.facing_deg <= 90,
          "support rule: facing_deg must be in [0, 90] degrees (got ", rule.facing_deg, ")");
  std::vector<Index> out = points_near_extreme(P, rule.direction, rule.depth, candidates);
  if (rule.facing_deg > 0) {
    require(N.rows() == P.rows(), "support rule: facing_deg > 0 needs a normal per point (", N.rows(),
            " normals for ", P.rows(), " points)");
    const Vec3 d = rule.direction.normalized();
    const double c = std::cos(rule.facing_deg * std::numbers::pi / 180.0);
    auto facing = [&](Index i) {
      if (N.row(i).dot(d) >= c) out.push_back(i);
    };
    if (candidates.empty())
      for (Index i = 0; i < P.rows(); ++i) facing(i);
    else
      for (Index i : candidates) facing(i);
  }
  for (const auto& [dir, depth] : rule.caps)
    for (Index i : points_near_extreme(P, dir, depth, candidates)) out.push_back(i);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<Index> support_nodes(const MatX3& surface, const SupportRule& rule) {
  require(rule.facing_deg == 0,
          "support rule: facing_deg > 0 needs the surface's normals (pass the surface mesh)");
  return apply_support_rule(surface, MatX3(), rule);
}

std::vector<Index> support_nodes(const SurfaceMesh& surface, const SupportRule& rule) {
  MatX3 N;
  vertex_normals(surface.V, surface.F, N);
  return apply_support_rule(surface.V, N, rule);
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
  MatX3 normals;  // area-weighted outward normals of the boundary nodes (corner triangles), for facing_deg
  if (support.facing_deg > 0) {
    normals = MatX3::Zero(problem_.mesh.num_nodes(), 3);
    for (Index f = 0; f < boundary_.rows(); ++f) {
      const Vec3 a = problem_.mesh.X.row(boundary_(f, 0)), b = problem_.mesh.X.row(boundary_(f, 1)),
                 c = problem_.mesh.X.row(boundary_(f, 2));
      const Vec3 n = (b - a).cross(c - a);  // twice the area times the unit normal
      for (int k = 0; k < 6; ++k) normals.row(boundary_(f, k)) += n.transpose();
    }
    for (Index i = 0; i < normals.rows(); ++i)
      if (normals.row(i).norm() > 0) normals.row(i).normalize();
  }
  problem_.fixed = apply_support_rule(problem_.mesh.X, normals, support, boundary_nodes(problem_.mesh));
  validate_problem(problem_);  // a support region that leaves rigid motion free is refused here
  sample_ = locate_on_boundary(problem_.mesh, boundary_, surface.V);
}

MatX3 OrganReference::surface_displacement(const ContactLoad& load, double* solve_seconds, bool* from_cache,
                                           Vec3* disk_mean, MatX3* nodal) const {
  FemProblem p = problem_;
  for (const auto& [node, f] : disk_load_quadratic(p.mesh, boundary_, load.centre, load.radius, load.force))
    p.loads.push_back({node, f});
  const FemResult r = solve(p, settings_.solver);
  if (solve_seconds) *solve_seconds = r.solve_seconds;
  if (from_cache) *from_cache = r.from_cache;
  if (disk_mean) {
    const double F2 = load.force.squaredNorm();
    *disk_mean = Vec3::Zero();
    for (const auto& l : p.loads) *disk_mean += (l.force.dot(load.force) / F2) * r.u.row(l.node).transpose();
  }
  if (nodal) *nodal = r.u;
  return interpolate(boundary_, sample_, r.u);
}

Vec3 disk_mean_linear(const MatX3& V, const MatX3i& F, const ContactLoad& load, const MatX3& u) {
  require(u.rows() == V.rows(), "disk mean: ", u.rows(), " displacements for ", V.rows(), " vertices");
  const VecX w = disk_load_linear(V, F, load.centre, load.radius, Vec3(1, 0, 0)).col(0);
  return (u.transpose() * w);
}

std::vector<std::pair<Index, double>> disk_mean_weights(const MatX3& V, const MatX3i& F,
                                                        const ContactLoad& load) {
  const VecX w = disk_load_linear(V, F, load.centre, load.radius, Vec3(1, 0, 0)).col(0);
  std::vector<std::pair<Index, double>> out;
  for (Index i = 0; i < w.size(); ++i)
    if (w[i] != 0) out.emplace_back(i, w[i]);
  require(!out.empty(), "disk mean: the disk of radius ", load.radius, " mm at (", load.centre.transpose(),
          ") covers no surface triangle");
  return out;
}

Vec3 site_readout(const CalibrationCase& c, const MatX3& u) {
  if (c.mean_weights.empty()) {
    require(c.contact >= 0 && c.contact < u.rows(), "calibrate: contact node ", c.contact,
            " is not among the ", u.rows(), " rows of the response");
    return u.row(c.contact).transpose();
  }
  Vec3 m = Vec3::Zero();
  for (const auto& [i, w] : c.mean_weights) {
    require(i >= 0 && i < u.rows(), "calibrate: disk-mean weight on row ", i, ", the response has ",
            u.rows());
    m += w * u.row(i).transpose();
  }
  return m;
}

Vec3 fem_site_readout(const CalibrationCase& c) {
  return c.mean_weights.empty() ? Vec3(c.u_fem.row(c.contact).transpose()) : c.fem_mean;
}

std::string_view to_string(SiteReadout r) {
  return r == SiteReadout::DiskMean ? "disk-mean" : "node";
}

SiteReadout parse_enum(const std::string& text, SiteReadout*) {
  if (text == "node") return SiteReadout::Node;
  if (text == "disk-mean") return SiteReadout::DiskMean;
  throw InvalidInput(cat("must be node or disk-mean (got '", text, "')"));
}

std::vector<double> checked_train_forces(const std::vector<double>& forces) {
  if (forces.empty()) throw InvalidInput("must list at least one force");
  for (double f : forces)
    if (!(std::isfinite(f) && f > 0))
      throw InvalidInput(cat("must be > 0 N or a list of such (got '", f, "')"));
  return forces;
}

std::vector<double> parse_train_forces(const std::string& text) {
  std::vector<double> out;
  if (text.empty()) return checked_train_forces(out);
  std::size_t begin = 0;
  while (true) {  // every comma separates two items: "0.5," and ",0.5" hold an empty one
    const std::size_t comma = text.find(',', begin);
    const std::string item =
        text.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin);
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || !(end && end != item.c_str() && *end == '\0'))
      throw InvalidInput(cat("must be > 0 N or a list of such (got '", item, "')"));
    out.push_back(v);
    if (comma == std::string::npos) break;
    begin = comma + 1;
  }
  return checked_train_forces(out);
}

double checked_site_weight(double w) {
  if (!(std::isfinite(w) && w >= 0)) throw InvalidInput(cat("must be a number >= 0 (got '", w, "')"));
  return w;
}

double parse_site_weight(const std::string& text) {
  char* end = nullptr;
  const double w = std::strtod(text.c_str(), &end);
  if (text.empty() || !(end && *end == '\0'))
    throw InvalidInput(cat("must be a number >= 0 (got '", text, "')"));
  return checked_site_weight(w);
}

namespace {

// The disk load as nodal forces on the model's degrees of freedom (through the body's force map).
MatX3 model_load(const Body& body, const ContactLoad& load) {
  const MatX3& S = body.rest_surface();
  const MatX3 fs = disk_load_linear(S, body.faces(), load.centre, load.radius, load.force);
  MatX3 f_ext = MatX3::Zero(body.model().num_nodes(), 3);
  for (Index i = 0; i < fs.rows(); ++i)
    if (fs.row(i).squaredNorm() > 0) body.transfer_force(i, fs.row(i).transpose(), f_ext);
  return f_ext;
}

MatX3 surface_of(const Body& body, const MatX3& x) {
  State st = make_state(body.model());
  st.x = x;
  MatX3 surf;
  body.map_to_surface(st, surf);
  return surf - body.rest_surface();
}

// The residual tolerance is relative to the load: 1e-7 of the largest nodal force (at least 1e-10 N). An
// absolute 1e-10 N sits at the round-off floor of the volumetric kind's forces, where Newton stagnates
// (5e-10 N after 10 iterations, then up to 200 factorisations per solve); 1e-7 of the load changes a
// displacement by about 1e-7 of itself. A model with volume terms (thousands of nodes, a tangent whose
// factorisation is most of the solve) also keeps its factorised tangent across Newton steps (modified
// Newton); the others factor at every step as before.
MatX3 static_surface(const Body& body, const ContactLoad& load) {
  const MatX3 f = model_load(body, load);
  StaticSettings ss;
  ss.tolerance = std::max(ss.tolerance, 1e-7 * f.rowwise().norm().maxCoeff());
  ss.reuse_tangent = body.model().volume.size() > 0;
  return surface_of(body, static_equilibrium(body.model(), f, ss).x);
}

// Golden-section search for the minimum of f over [lo, hi]: two probes and `iterations` more; returns the
// final bracket.
template <class F>
std::pair<double, double> golden_section(F&& f, double lo, double hi, int iterations) {
  const double g = (std::sqrt(5.0) - 1) / 2;
  double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
  double fa = f(a), fb = f(b);
  for (int it = 0; it < iterations; ++it) {
    if (fa < fb) {
      hi = b;
      b = a;
      fb = fa;
      a = hi - g * (hi - lo);
      fa = f(a);
    } else {
      lo = a;
      a = b;
      fa = fb;
      b = lo + g * (hi - lo);
      fb = f(b);
    }
  }
  return {lo, hi};
}

}  // namespace

MatX3 spring_displacement(const Body& body, const ContactLoad& load) {
  return static_surface(body, load);
}

std::vector<Index> free_dof_map(const Model& m, Index& free) {
  std::vector<Index> map(static_cast<std::size_t>(3 * m.num_nodes()), -1);
  free = 0;
  for (Index a : m.free_nodes)
    for (int d = 0; d < 3; ++d) map[static_cast<std::size_t>(3 * a + d)] = free++;
  return map;
}

Eigen::SparseMatrix<double> restrict_to_free(const Eigen::SparseMatrix<double>& K,
                                             const std::vector<Index>& map, Index free) {
  std::vector<Eigen::Triplet<double>> T;
  T.reserve(static_cast<std::size_t>(K.nonZeros()));
  for (int c = 0; c < K.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator e(K, c); e; ++e) {
      const Index r = map[static_cast<std::size_t>(e.row())], q = map[static_cast<std::size_t>(e.col())];
      if (r >= 0 && q >= 0) T.emplace_back(r, q, e.value());
    }
  Eigen::SparseMatrix<double> Kff(free, free);
  Kff.setFromTriplets(T.begin(), T.end());
  return Kff;
}

std::vector<MatX3> spring_displacement_linear(const Body& body, const std::vector<ContactLoad>& loads) {
  const Model& m = body.model();
  std::vector<MatX3> out;
  if (m.free_nodes.empty()) {
    for (std::size_t i = 0; i < loads.size(); ++i) out.push_back(MatX3::Zero(body.num_surface_nodes(), 3));
    return out;
  }
  // the quasi-static linear response of the simulator (Integrator::LinearStatic), without its column cache
  std::unique_ptr<LinearResponse> R;
  try {
    R = std::make_unique<LinearResponse>(m, 0);
  } catch (const InvalidInput& e) {
    throw SolverError(e.what());
  }
  MatX3 x(m.num_nodes(), 3);
  VecX b, u;
  for (const auto& load : loads) {
    if (R->positions(model_load(body, load), x, b, u) < 0 || !x.allFinite())
      throw SolverError(cat(m.name, ": linear response: the solve is not finite"));
    out.push_back(surface_of(body, x));
  }
  return out;
}

MatX3 spring_displacement_local(const Body& body, const ContactLoad& load, double k_loc) {
  MatX3 u = static_surface(body, load);
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

double calibration_cost(const Response& response, const VecX& m,
                        const std::vector<CalibrationCase>& training) {
  double c = 0;
  for (const auto& t : training) {
    MatX3 u;
    try {
      u = response(m, t.load);
    } catch (const SolverError&) {
      return std::numeric_limits<double>::infinity();
    }
    require(u.rows() >= t.u_fem.rows(), "calibrate: the response has ", u.rows(), " surface nodes, the FEM ",
            t.u_fem.rows());
    const double scale = std::max(t.u_fem.rowwise().norm().maxCoeff(), 1e-12);
    const Eigen::Index n = t.u_fem.rows();
    c += (u.topRows(n) - t.u_fem).squaredNorm() / (scale * scale * static_cast<double>(n));
    c += t.site_weight * (site_readout(t, u) - fem_site_readout(t)).squaredNorm() / (scale * scale);
  }
  return c;
}

VecX calibrate_multipliers(const Response& response, Index families,
                           const std::vector<CalibrationCase>& training, int sweeps) {
  require(families >= 1 && !training.empty(), "calibrate: need >= 1 family and >= 1 training load");
  VecX logm = VecX::Zero(families);
  auto cost = [&](const VecX& lm) { return calibration_cost(response, lm.array().exp().matrix(), training); };
  const double lo0 = std::log(1e-3), hi0 = std::log(1e3);
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (Index f = 0; f < families; ++f) {
      // narrower bracket on later sweeps, around the current value
      const double lo = sweep == 0 ? lo0 : logm(f) - std::log(10.0),
                   hi = sweep == 0 ? hi0 : logm(f) + std::log(10.0);
      VecX x = logm;
      const auto [l, h] = golden_section(
          [&](double v) {
            x(f) = v;
            return cost(x);
          },
          lo, hi, 24);
      logm(f) = 0.5 * (l + h);
    }
  return logm.array().exp().matrix();
}

VecX calibrate_scale_and_ratio(const BatchResponse& response, const std::vector<CalibrationCase>& training,
                               int evaluations) {
  require(!training.empty() && evaluations >= 3, "calibrate: need >= 1 training load and >= 3 evaluations");
  std::vector<ContactLoad> loads;
  for (const auto& t : training) loads.push_back(t.load);
  double best_cost = std::numeric_limits<double>::infinity(), best_logr = 0, best_c = 1;
  auto cost = [&](double logr) {
    VecX m(2);
    m << 1.0, std::exp(logr);
    std::vector<MatX3> us;
    try {
      us = response(m, loads);
    } catch (const SolverError&) {
      return std::numeric_limits<double>::infinity();
    }
    require(us.size() == training.size(), "calibrate: the response returned ", us.size(), " fields for ",
            training.size(), " loads");
    // the cost of a / c times u is quadratic in a: minimised in closed form
    // the site read-out (node or disk mean) is linear in u, so it scales with a too
    double uu = 0, uU = 0;
    for (std::size_t i = 0; i < training.size(); ++i) {
      const auto& t = training[i];
      const Eigen::Index n = t.u_fem.rows();
      require(us[i].rows() >= n, "calibrate: the response has ", us[i].rows(), " surface nodes, the FEM ", n);
      const auto u = us[i].topRows(n);
      const Vec3 site = site_readout(t, us[i]), site_fem = fem_site_readout(t);
      const double s = std::max(t.u_fem.rowwise().norm().maxCoeff(), 1e-12);
      const double wn = 1.0 / (s * s * static_cast<double>(n)), wc = t.site_weight / (s * s);
      uu += wn * u.squaredNorm() + wc * site.squaredNorm();
      uU += wn * (u.array() * t.u_fem.array()).sum() + wc * site.dot(site_fem);
    }
    const double a = uU > 0 && uu > 0 ? uU / uu : 1.0;  // a = 1 / c
    double cst = 0;
    for (std::size_t i = 0; i < training.size(); ++i) {
      const auto& t = training[i];
      const Eigen::Index n = t.u_fem.rows();
      const double s = std::max(t.u_fem.rowwise().norm().maxCoeff(), 1e-12);
      cst += (a * us[i].topRows(n) - t.u_fem).squaredNorm() / (s * s * static_cast<double>(n));
      cst += t.site_weight * (a * site_readout(t, us[i]) - fem_site_readout(t)).squaredNorm() / (s * s);
    }
    if (cst < best_cost) {
      best_cost = cst;
      best_logr = logr;
      best_c = 1.0 / a;
    }
    return cst;
  };
  golden_section(cost, std::log(1e-2), std::log(1e2), evaluations - 2);
  if (!std::isfinite(best_cost)) throw SolverError("calibrate: no ratio in [1e-2, 1e2] has a response");
  VecX m(2);
  m << best_c, best_c * std::exp(best_logr);
  return m;
}

RefineResult refine_multipliers(const Response& response, const VecX& start, const std::vector<double>& spans,
                                const std::vector<CalibrationCase>& training, int probes, int sweeps) {
  const Index n = static_cast<Index>(spans.size());
  require(n >= 1 && start.size() <= n && !training.empty() && probes >= 2 && sweeps >= 1,
          "refine_multipliers: need >= 1 span, a start of at most as many families, >= 1 training load, "
          ">= 2 probes and >= 1 sweep");
  VecX logm = VecX::Zero(n);
  for (Index f = 0; f < start.size(); ++f) {
    require(std::isfinite(start(f)) && start(f) > 0, "refine_multipliers: start[", f, "] must be > 0 (got ",
            start(f), ")");
    logm(f) = std::log(start(f));
  }
  RefineResult r;
  auto cost = [&](const VecX& lm) {
    ++r.evaluations;
    return calibration_cost(response, lm.array().exp().matrix(), training);
  };
  r.start_cost = r.cost = cost(logm);
  std::vector<Index> order(static_cast<std::size_t>(n));  // widest span first
  for (Index f = 0; f < n; ++f) order[static_cast<std::size_t>(f)] = f;
  std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) {
    return spans[static_cast<std::size_t>(a)] > spans[static_cast<std::size_t>(b)];
  });
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (Index f : order) {
      const double span = spans[static_cast<std::size_t>(f)];
      if (!(span > 1)) continue;
      const double w = std::log(span) / std::pow(2.0, sweep);
      VecX x = logm;
      double best = r.cost, best_v = logm(f);
      golden_section(
          [&](double v) {
            x(f) = v;
            const double c = cost(x);
            if (c < best) best = c, best_v = v;
            return c;
          },
          logm(f) - w, logm(f) + w, probes - 2);
      logm(f) = best_v;
      r.cost = best;
    }
  r.m = logm.array().exp().matrix();
  return r;
}

VolumetricFit calibrate_volumetric_nonlinear(const Response& response, const VecX& small_strain,
                                             const std::vector<CalibrationCase>& training, int probes,
                                             int sweeps) {
  require(small_strain.size() == 2 && small_strain.minCoeff() > 0,
          "calibrate: the small-strain fit must be two positive multipliers (springs, volume terms)");
  auto to_m = [](const VecX& p) {
    VecX m(3);
    m << p(0), p(0) * p(1), p(2);
    return m;
  };
  const Response in_p = [&](const VecX& p, const ContactLoad& l) { return response(to_m(p), l); };
  VecX from_fit(3), from_closed_forms = VecX::Ones(3);
  from_fit << small_strain(0), small_strain(1) / small_strain(0), 1.0;
  VolumetricFit out;
  // c first from each start (the one family the small-strain fit cannot see), then all three from the better
  const RefineResult a = refine_multipliers(in_p, from_fit, {1.0, 1.0, kVolumetricRefineSpans[2]}, training,
                                            probes, 1),
                     b = refine_multipliers(in_p, from_closed_forms, {1.0, 1.0, kVolumetricRefineSpans[2]},
                                            training, probes, 1);
  out.small_strain_cost = a.start_cost;
  out.closed_forms_cost = b.start_cost;
  out.from_small_strain = a.cost <= b.cost;
  out.refine =
      refine_multipliers(in_p, out.from_small_strain ? a.m : b.m,
                         {kVolumetricRefineSpans[0], kVolumetricRefineSpans[1], kVolumetricRefineSpans[1]},
                         training, probes, sweeps);
  out.refine.start_cost = std::min(a.start_cost, b.start_cost);
  out.refine.evaluations += a.evaluations + b.evaluations;
  out.m = to_m(out.refine.m);
  return out;
}

SurfaceSpringFit refine_surface_springs(const Response& response, const VecX& fit,
                                        const std::vector<CalibrationCase>& training, int probes,
                                        int sweeps) {
  require(fit.size() == 3 && fit.minCoeff() > 0,
          "calibrate: the surface-layer family refines a fit of three positive multipliers (springs, volume "
          "terms, c)");
  auto to_m = [](const VecX& p) {  // (s, r, c, q) -> (springs, volume terms, c, surface springs)
    VecX m(4);
    m << p(0), p(0) * p(1), p(2), p(3);
    return m;
  };
  const Response in_p = [&](const VecX& p, const ContactLoad& l) { return response(to_m(p), l); };
  VecX start(4);
  start << fit(0), fit(1) / fit(0), fit(2), 1.0;
  SurfaceSpringFit out;
  out.refine = refine_multipliers(
      in_p, start,
      {kVolumetricRefineSpans[0], kVolumetricRefineSpans[1], kVolumetricRefineSpans[1], kSurfaceSpringSpan},
      training, probes, sweeps);
  out.m = to_m(out.refine.m);
  return out;
}

}  // namespace medspring::fem
