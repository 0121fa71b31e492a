#include "medspring/models/smrm_vessel.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/loads.hpp"

namespace medspring {

namespace {

inline Vec3 row3(const MatX3& M, Index i) {
  return {M(i, 0), M(i, 1), M(i, 2)};
}

double spoke_angle(Index j, Index M) {
  return 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(M);
}

// Validates, deduplicates and resamples a centerline to settings.atoms atoms (mm).
Centerline prepare_centerline(const Centerline& line, const SmrmSettings& s, Index& removed) {
  const std::string w = cat("centerline '", line.name, "'");
  require(line.radii.size() == line.points.rows(), w, ": ", line.points.rows(), " points but ",
          line.radii.size(), " radii");
  for (Index k = 0; k < line.size(); ++k) {
    require(line.points.row(k).allFinite(), w, ": point ", k, ": coordinates must be finite");
    require(std::isfinite(line.radii[k]) && line.radii[k] > 0, w, ": point ", k, ": radius must be > 0 (got ",
            line.radii[k], ")");
  }
  require(s.atoms >= 3, "vessel settings: atoms must be >= 3 (got ", s.atoms, ")");
  require_nonnegative(s.dedup_tolerance, "vessel settings: dedup_tolerance");
  const Centerline d = deduplicate(line, s.dedup_tolerance);
  removed = line.size() - d.size();
  require(d.size() >= 3, w, ": fewer than 3 distinct points (", d.size(), " of ", line.size(),
          " left after merging points closer than ", s.dedup_tolerance, " mm)");
  return resample(d, s.atoms);
}

// Structured parts: node (i, j) = i M + j rides on atom i with offset row i M + j.
SmrmParts structured_parts(const std::string& name, const MatX3& atoms, const MatX3& offsets, Index M) {
  const Index n = static_cast<Index>(atoms.rows());
  require(n >= 3, "vessel '", name, "': needs at least 3 atoms (got ", n, ")");
  require(M >= 3, "vessel '", name, "': needs at least 3 spokes per atom (got ", M, ")");
  require(offsets.rows() == n * M, "vessel '", name, "': ", offsets.rows(), " offsets for ", n, " x ", M,
          " nodes");
  for (Index k = 0; k < offsets.rows(); ++k) {
    require(offsets.row(k).allFinite(), "vessel '", name, "': atom ", k / M, " spoke ", k % M,
            ": offset must be finite");
    const double rho = std::hypot(offsets(k, 0), offsets(k, 1));
    require(rho > 1e-9, "vessel '", name, "': atom ", k / M, " spoke ", k % M,
            ": spoke length must be > 0 (got ", rho, " mm)");
  }
  SmrmParts p;
  p.name = name;
  p.atoms = atoms;
  std::vector<Index> atom(static_cast<std::size_t>(n * M));
  for (Index k = 0; k < n * M; ++k) atom[static_cast<std::size_t>(k)] = k / M;
  p.binding = bind_offsets(atom, offsets, n);
  p.faces = tube_grid_faces(n, M);
  p.grid = {n, M};
  return p;
}

// Circular offsets (eq. (4), D-11): (r_i cos th_j, r_i sin th_j, 0).
MatX3 circular_offsets(const VecX& radii, Index M) {
  const Index n = static_cast<Index>(radii.size());
  MatX3 O(n * M, 3);
  for (Index i = 0; i < n; ++i)
    for (Index j = 0; j < M; ++j) {
      const double th = spoke_angle(j, M);
      O.row(i * M + j) << radii[i] * std::cos(th), radii[i] * std::sin(th), 0.0;
    }
  return O;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------

SmrmVessel::SmrmVessel(SmrmParts parts, const SmrmSettings& settings)
    : name_(std::move(parts.name)), settings_(settings) {
  const std::string w = cat("vessel '", name_, "'");
  const Index n = static_cast<Index>(parts.atoms.rows());
  require(n >= 3, w, ": needs at least 3 atoms (got ", n, ")");
  require_finite_points(parts.atoms, cat(w, ": atom"));
  for (Index i = 0; i + 1 < n; ++i) {
    const double L = (parts.atoms.row(i + 1) - parts.atoms.row(i)).norm();
    require(L >= 1e-9, w, ": atoms ", i, " and ", i + 1, " coincide (", L, " mm apart)");
  }
  require_positive(settings.k_loc, cat(w, ": k_loc"));
  ref_ = make_frame_reference(parts.atoms, settings.frames);
  binding_ = std::move(parts.binding);
  const Index m = binding_.size();
  require(m > 0, w, ": has no surface nodes");
  require(binding_.num_atoms == n, w, ": binding is for ", binding_.num_atoms, " atoms, the centerline has ",
          n);
  require(binding_.offset.rows() == m, w, ": binding has ", binding_.offset.rows(), " offsets for ", m,
          " nodes");
  require(!binding_.generic() || static_cast<Index>(binding_.lambda.size()) == m, w, ": binding has ",
          binding_.lambda.size(), " bracket parameters for ", m, " nodes");
  require_finite_points(binding_.offset, cat(w, ": binding offset of surface node"));
  for (Index k = 0; k < m; ++k) {
    const Index a = binding_.atom[static_cast<std::size_t>(k)];
    require_index(a, binding_.generic() ? n - 1 : n, cat(w, ": node ", k, ": atom"));
    if (binding_.generic()) {
      const double lam = binding_.lambda[static_cast<std::size_t>(k)];
      require(lam >= 0 && lam <= 1, w, ": node ", k, ": bracket parameter must be in [0, 1] (got ", lam, ")");
    }
  }
  faces_ = std::move(parts.faces);
  require(faces_.rows() > 0, w, ": has no surface triangles");
  grid_ = parts.grid;
  if (grid_.valid())
    require(grid_.rings == n && grid_.rings * grid_.spokes == m, w, ": grid ", grid_.rings, " x ",
            grid_.spokes, " does not match ", n, " atoms and ", m, " nodes");
  normals_ =
      grid_.valid() ? make_normal_plan(m, faces_, grid_.rings, grid_.spokes) : make_normal_plan(m, faces_);
  Workspace ws = make_workspace();
  if (parts.rest_surface.rows() == 0) {
    reconstruct(binding_, ref_.C0, ref_.F0, ws.scratch, rest_surface_);
  } else {
    require(parts.rest_surface.rows() == m, w, ": ", parts.rest_surface.rows(), " rest positions for ", m,
            " nodes");
    require_finite_points(parts.rest_surface, cat(w, ": surface node"));
    rest_surface_ = std::move(parts.rest_surface);
  }
  vertex_normals(normals_, rest_surface_, ws.scratch, rest_normals_);

  // Spoke lengths (distance to the interpolated atom) and the largest in-plane spoke of every atom.
  spoke_length_.resize(m);
  VecX rho_max = VecX::Zero(n);
  require_finite_points(binding_.offset, cat(w, ": binding offset of surface node"));
  for (Index k = 0; k < m; ++k) {
    const Index a = binding_.atom[static_cast<std::size_t>(k)];
    const double lam = binding_.generic() ? binding_.lambda[static_cast<std::size_t>(k)] : 0.0;
    const Vec3 c =
        lam == 0.0 ? row3(ref_.C0, a) : Vec3((1 - lam) * row3(ref_.C0, a) + lam * row3(ref_.C0, a + 1));
    spoke_length_[k] = (row3(rest_surface_, k) - c).norm();
    const double in_plane =
        binding_.generic() ? spoke_length_[k] : std::hypot(binding_.offset(k, 0), binding_.offset(k, 1));
    const Index r = node_atom(k);
    rho_max[r] = std::max(rho_max[r], in_plane);
  }
  if (parts.atom_radius.size() == 0) {
    atom_radius_ = rho_max;
  } else {
    require(parts.atom_radius.size() == n, w, ": ", parts.atom_radius.size(), " radii for ", n, " atoms");
    for (Index i = 0; i < n; ++i) require_positive(parts.atom_radius[i], cat(w, ": atom ", i, ": radius"));
    atom_radius_ = std::move(parts.atom_radius);
  }
  rho_max_ = rho_max;
  rest_turning_.resize(n);
  {
    const VecX a = turning_angles_deg(ref_.C0);
    for (Index i = 0; i < n; ++i) rest_turning_[i] = a[i] * std::numbers::pi / 180.0;
  }
  if (settings.bending == BendingMode::Wall) {
    bending_k_ = wall_bending_stiffness(ref_.C0, atom_radius_, settings.wall);
  } else {
    require_nonnegative(settings.chain.kb, cat(w, ": chain.kb"));
    bending_k_ = VecX::Constant(n, settings.chain.kb);
    bending_k_[0] = bending_k_[n - 1] = 0.0;
  }
  model_ = make_chain_model(ref_.C0, settings.chain, name_, bending_k_);

  report_ = std::move(parts.report);
  report_.atoms = n;
  report_.surface_nodes = m;
  report_.rest_frames = ref_.report;
  report_.curvature = check_curvature(ref_.C0, rho_max);  // §5.6 validity
  if (report_.removed_duplicates > 0)
    report_.notes.push_back(cat("removed ", report_.removed_duplicates, " repeated centerline points"));
  if (report_.rest_frames.degenerate > 0)
    report_.notes.push_back(cat("PaperXOY frames degenerate at ", report_.rest_frames.degenerate,
                                " rest atoms (first: atom ", report_.rest_frames.first_degenerate,
                                "): tangent parallel to e_z, fallback frames used"));
  if (report_.curvature.violations > 0)
    report_.notes.push_back(cat("cross-sections may intersect: rho kappa >= 1 at ",
                                report_.curvature.violations, " atoms (first: atom ",
                                report_.curvature.first_atom,
                                ", max rho kappa = ", report_.curvature.max_rho_kappa, ")"));
  if (report_.spokes_without_hit > 0)
    report_.notes.push_back(cat(report_.spokes_without_hit, " spokes found no boundary (first: node ",
                                report_.first_spoke_without_hit, "): rho = r_i used"));
}

SmrmVessel::Workspace SmrmVessel::make_workspace() const {
  Workspace ws;
  ws.frames.resize(num_atoms());
  ws.scratch = ReconstructionScratch(num_atoms(), static_cast<Index>(faces_.rows()), normals_.tube_rings,
                                     normals_.tube_spokes);
  return ws;
}

FrameReport SmrmVessel::map_to_surface(const MatX3& atoms, Workspace& ws, MatX3& surface) const {
  const FrameReport rep = compute_frames(atoms, ref_, ws.frames);  // §5.5
  reconstruct(binding_, atoms, ws.frames, ws.scratch, surface);    // §5.7
  return rep;
}

void SmrmVessel::map_to_surface(const State& state, MatX3& surface) const {
  const auto ws = workspaces_.acquire([this] { return make_workspace(); });
  map_to_surface(state.x, *ws, surface);
}

void SmrmVessel::surface_normals(const MatX3& surface, Workspace& ws, MatX3& normals) const {
  vertex_normals(normals_, surface, ws.scratch, normals);
}

void SmrmVessel::transfer_force(Index node, const Vec3& F, MatX3& f_dof) const {  // D-14
  const std::size_t k = static_cast<std::size_t>(node);
  const Index a = binding_.atom[k];
  const double lam = binding_.generic() ? binding_.lambda[k] : 0.0;
  if (lam < 1.0 && !model_.fixed[static_cast<std::size_t>(a)]) f_dof.row(a) += ((1.0 - lam) * F).transpose();
  if (lam > 0.0 && !model_.fixed[static_cast<std::size_t>(a + 1)]) f_dof.row(a + 1) += (lam * F).transpose();
}

double SmrmVessel::spoke_length(Index node) const {
  return spoke_length_[node];
}

Index SmrmVessel::node_atom(Index node) const {
  const std::size_t k = static_cast<std::size_t>(node);
  const Index a = binding_.atom[k];
  return binding_.generic() && binding_.lambda[k] > 0.5 ? a + 1 : a;
}

Index SmrmVessel::contact_node(Index atom, const Vec3& F) const {
  require_index(atom, num_atoms(), cat("vessel '", name_, "': contact atom"));
  const double f = F.norm();
  require(f > 0 && std::isfinite(f), "vessel '", name_, "': contact force must be non-zero and finite");
  Index best = -1;
  double best_dot = std::numeric_limits<double>::infinity();
  for (Index k = 0; k < binding_.size(); ++k) {
    if (node_atom(k) != atom) continue;
    const double d = row3(rest_normals_, k).dot(F) / f;
    if (d < best_dot) {
      best_dot = d;
      best = k;
    }
  }
  require(best >= 0, "vessel '", name_, "': no surface node belongs to atom ", atom);
  return best;
}

Model SmrmVessel::make_chain(bool nonlinear) const {
  ChainSettings c = settings_.chain;
  c.nonlinear = nonlinear;
  return make_chain_model(ref_.C0, c, name_, bending_k_);
}

namespace {

// Turning angle at interior atom i (radians), 0 for a degenerate segment.
double turning_angle(const MatX3& C, Index i) {
  const Vec3 e1 = row3(C, i) - row3(C, i - 1), e2 = row3(C, i + 1) - row3(C, i);
  const double l1 = e1.norm(), l2 = e2.norm();
  if (l1 <= 0 || l2 <= 0) return 0.0;
  return std::atan2(e1.cross(e2).norm(), e1.dot(e2));
}

}  // namespace

VecX SmrmVessel::turning_angles_deg(const MatX3& atoms) {
  const Index n = static_cast<Index>(atoms.rows());
  VecX a = VecX::Zero(n);
  for (Index i = 1; i + 1 < n; ++i) a[i] = turning_angle(atoms, i) * 180.0 / std::numbers::pi;
  return a;
}

CurvatureCheck SmrmVessel::validity(const MatX3& atoms) const {  // §5.6, as check_curvature
  CurvatureCheck r;
  const Index n = std::min<Index>(static_cast<Index>(atoms.rows()), static_cast<Index>(rho_max_.size()));
  for (Index i = 1; i + 1 < n; ++i) {
    const Vec3 e1 = row3(atoms, i) - row3(atoms, i - 1), e2 = row3(atoms, i + 1) - row3(atoms, i);
    const double l1 = e1.norm(), l2 = e2.norm();
    if (l1 <= 0 || l2 <= 0) continue;
    const double rk = rho_max_[i] * (e2 / l2 - e1 / l1).norm() / (0.5 * (l1 + l2));
    r.max_rho_kappa = std::max(r.max_rho_kappa, rk);
    if (!(rk < 1.0)) {
      ++r.violations;
      if (r.first_atom < 0) r.first_atom = i;
    }
  }
  return r;
}

double SmrmVessel::max_turning_change_deg(const MatX3& atoms, Index* atom) const {
  double best = 0.0;
  Index where = -1;
  const Index n = std::min<Index>(static_cast<Index>(atoms.rows()), static_cast<Index>(rest_turning_.size()));
  for (Index i = 1; i + 1 < n; ++i) {
    const double d = std::abs(turning_angle(atoms, i) - rest_turning_[i]);
    if (d > best || where < 0) {
      best = d;
      where = i;
    }
  }
  if (atom) *atom = where;
  return best * 180.0 / std::numbers::pi;
}

BendingMode parse_bending_mode(const std::string& text) {
  if (text == "wall") return BendingMode::Wall;
  if (text == "constant") return BendingMode::Constant;
  throw InvalidInput(cat("unknown bending mode '", text, "' (expected wall or constant)"));
}

std::string to_string(BendingMode mode) {
  return mode == BendingMode::Wall ? "wall" : "constant";
}

VecX wall_bending_stiffness(const MatX3& C0, const VecX& radius, const WallSettings& wall) {
  const Index n = static_cast<Index>(C0.rows());
  require_positive(wall.E, "vessel wall: E");
  require_positive(wall.thickness_ratio, "vessel wall: thickness_ratio");
  require(radius.size() == n, "vessel wall: ", radius.size(), " radii for ", n, " atoms");
  VecX kb = VecX::Zero(n);
  for (Index i = 1; i + 1 < n; ++i) {
    require(std::isfinite(radius[i]) && radius[i] > 0, "vessel wall: atom ", i, ": radius must be > 0 (got ",
            radius[i], ")");
    const double h = 0.5 * ((row3(C0, i) - row3(C0, i - 1)).norm() + (row3(C0, i + 1) - row3(C0, i)).norm());
    require(h > 1e-9, "vessel wall: atom ", i, ": its neighbours coincide with it");
    const double ri = radius[i], ro = ri * (1.0 + wall.thickness_ratio);
    const double I = std::numbers::pi / 4.0 * (ro * ro * ro * ro - ri * ri * ri * ri);  // mm^4
    kb[i] = wall.E * I / (h * h * h);                                                   // N/mm
  }
  return kb;
}

Vec3 SmrmVessel::reaction_force(const State& state, Index node) const {
  require_index(node, binding_.size(), cat("vessel '", name_, "': reaction node"));
  const Index n = num_atoms();
  thread_local MatX3 zero, f;
  if (zero.rows() != n) {
    zero = MatX3::Zero(n, 3);
    f.resize(n, 3);
  }
  internal_forces(model_, state.x, zero, f);
  const std::size_t k = static_cast<std::size_t>(node);
  const Index a = binding_.atom[k];
  const double lam = binding_.generic() ? binding_.lambda[k] : 0.0;
  Vec3 r = Vec3::Zero();
  if (lam < 1.0 && !model_.fixed[static_cast<std::size_t>(a)]) r += (1.0 - lam) * row3(f, a);
  if (lam > 0.0 && !model_.fixed[static_cast<std::size_t>(a + 1)]) r += lam * row3(f, a + 1);
  return r;
}

// ---------------------------------------------------------------------------------------------------

SmrmVessel smrm_from_offsets(const MatX3& atoms, const MatX3& offsets, const SmrmSettings& settings,
                             const std::string& name) {
  const Index n = static_cast<Index>(atoms.rows());
  require(n >= 3, "vessel '", name, "': needs at least 3 atoms (got ", n, ")");
  Index M = settings.spokes;
  MatX3 O;
  if (offsets.rows() == n * settings.spokes) {
    O = offsets;
  } else {
    M = static_cast<Index>(offsets.rows());
    require(M >= 3, "vessel '", name, "': needs at least 3 spokes per atom (got ", M, " offsets)");
    O.resize(n * M, 3);
    for (Index i = 0; i < n; ++i) O.middleRows(i * M, M) = offsets;
  }
  return SmrmVessel(structured_parts(name, atoms, O, M), settings);
}

SmrmVessel smrm_from_centerline(const Centerline& line, const SmrmSettings& settings) {
  Index removed = 0;
  const Centerline c = prepare_centerline(line, settings, removed);
  require(settings.spokes >= 3, "vessel settings: spokes must be >= 3 (got ", settings.spokes, ")");
  SmrmParts p = structured_parts(line.name.empty() ? "vessel" : line.name, c.points,
                                 circular_offsets(c.radii, settings.spokes), settings.spokes);
  p.atom_radius = c.radii;
  p.report.removed_duplicates = removed;
  return SmrmVessel(std::move(p), settings);
}

const Centerline& longest_centerline(const std::vector<Centerline>& lines) {
  require(!lines.empty(), "centerlines: the list is empty");
  std::size_t best = 0;
  double best_length = -1.0;
  for (std::size_t k = 0; k < lines.size(); ++k) {
    const double L = lines[k].size() >= 2 ? lines[k].length() : 0.0;
    if (L > best_length) {
      best_length = L;
      best = k;
    }
  }
  return lines[best];
}

SmrmVessel smrm_from_surface(const SurfaceMesh& surface, const Centerline& line,
                             const SmrmSettings& settings) {
  require_valid_mesh(surface, "vessel surface", {.closed = true});
  Index removed = 0;
  const Centerline c = prepare_centerline(line, settings, removed);
  const FrameReference ref = make_frame_reference(c.points, settings.frames);
  VecX dist;
  SurfaceBinding b = bind_to_polyline(surface.V, ref, &dist);  // §5.9
  double max_ratio = 0.0;
  for (Index k = 0; k < surface.num_vertices(); ++k) {
    const Index i = b.atom[static_cast<std::size_t>(k)];
    const double lam = b.lambda[static_cast<std::size_t>(k)];
    // Local radius: the largest radius of the bracket atoms and their neighbours, so that a closed tip
    // (whose inscribed radius tapers towards zero, e.g. a skeleton end trimmed by D-8) does not reject
    // the nodes of its own cap.
    double r = 0.0;
    for (Index a = std::max<Index>(i - 1, 0); a <= std::min<Index>(i + 2, c.size() - 1); ++a)
      r = std::max(r, c.radii[a]);
    const double ratio = dist[k] / r;
    require(ratio <= settings.max_radius_factor, "vessel surface: node ", k, " is ", dist[k],
            " mm from centerline '", line.name, "', more than ", settings.max_radius_factor,
            " x the local radius ", r, " mm (near atom ", lam > 0.5 ? i + 1 : i, ")");
    max_ratio = std::max(max_ratio, ratio);
  }
  SmrmParts p;
  p.name = line.name.empty() ? "vessel" : line.name;
  p.atoms = c.points;
  p.atom_radius = c.radii;
  p.binding = std::move(b);
  p.rest_surface = surface.V;
  p.faces = surface.F;
  p.report.removed_duplicates = removed;
  p.report.max_distance_ratio = max_ratio;
  return SmrmVessel(std::move(p), settings);
}

double first_ray_hit(const SurfaceMesh& mesh, const Vec3& o, const Vec3& w, double t_max) {
  // Barycentric slack: a ray through a shared edge or vertex (e.g. a spoke of an end atom lying in a flat
  // cap) must not slip between the two triangles through rounding.
  constexpr double kBaryEps = 1e-9;
  double best = std::numeric_limits<double>::infinity();
  for (Index f = 0; f < mesh.num_faces(); ++f) {  // Moeller-Trumbore
    const Vec3 a = row3(mesh.V, mesh.F(f, 0));
    const Vec3 e1 = row3(mesh.V, mesh.F(f, 1)) - a, e2 = row3(mesh.V, mesh.F(f, 2)) - a;
    const Vec3 p = w.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-14 * e1.norm() * e2.norm()) continue;
    const double inv = 1.0 / det;
    const Vec3 s = o - a;
    const double u = s.dot(p) * inv;
    if (u < -kBaryEps || u > 1.0 + kBaryEps) continue;
    const Vec3 q = s.cross(e1);
    const double v = w.dot(q) * inv;
    if (v < -kBaryEps || u + v > 1.0 + kBaryEps) continue;
    const double t = e2.dot(q) * inv;
    if (t > 1e-9 && t <= t_max && t < best) best = t;
  }
  return best;
}

SmrmVessel smrm_from_marched_spokes(const Centerline& line, const SurfaceMesh& boundary,
                                    const SmrmSettings& settings) {
  require_valid_mesh(boundary, "vessel boundary");
  Index removed = 0;
  const Centerline c = prepare_centerline(line, settings, removed);
  const Index n = c.size(), M = settings.spokes;
  require(M >= 3, "vessel settings: spokes must be >= 3 (got ", M, ")");
  const FrameReference ref = make_frame_reference(c.points, settings.frames);
  MatX3 O(n * M, 3);
  std::vector<Index> missed;
  for (Index i = 0; i < n; ++i) {  // §5.6: rho_ij = first boundary hit along w_ij
    const Vec3 C = row3(c.points, i), u = row3(ref.F0.u, i), v = row3(ref.F0.v, i);
    for (Index j = 0; j < M; ++j) {
      const double th = spoke_angle(j, M);
      const Vec3 dir = std::cos(th) * u + std::sin(th) * v;
      double rho = first_ray_hit(boundary, C, dir, settings.max_radius_factor * c.radii[i]);
      if (!std::isfinite(rho)) {
        rho = c.radii[i];
        missed.push_back(i * M + j);
      }
      O.row(i * M + j) << rho * std::cos(th), rho * std::sin(th), 0.0;
    }
  }
  SmrmParts p = structured_parts(line.name.empty() ? "vessel" : line.name, c.points, O, M);
  p.atom_radius = c.radii;
  p.report.removed_duplicates = removed;
  p.report.spokes_without_hit = static_cast<Index>(missed.size());
  p.report.first_spoke_without_hit = missed.empty() ? -1 : missed.front();
  p.report.missed_spokes = std::move(missed);
  return SmrmVessel(std::move(p), settings);
}

SmrmVessel smrm_phantom(VesselPath path, CrossSectionShape shape, const SmrmSettings& settings) {
  return smrm_from_offsets(vessel_phantom_atoms(path, settings.atoms),
                           cross_section_offsets(shape, settings.spokes), settings,
                           cat(to_string(path), "/", to_string(shape)));
}

// ---------------------------------------------------------------------------------------------------

VesselExperimentResult run_vessel_experiment(const SmrmVessel& vessel, const VesselExperimentSettings& s) {
  const Index n = vessel.num_atoms();
  require_index(s.atom, n, "vessel experiment: atom");
  require(!vessel.model().fixed[static_cast<std::size_t>(s.atom)], "vessel experiment: atom ", s.atom,
          " is fixed (no global response)");
  require_positive(s.light, "vessel experiment: light");
  require_positive(s.strong, "vessel experiment: strong");
  require_positive(s.dt, "vessel experiment: dt");
  require_nonnegative(s.t_ramp, "vessel experiment: t_ramp");
  require(s.t_release >= 0 && s.t_release <= s.t_end && std::isfinite(s.t_end),
          "vessel experiment: need 0 <= t_release <= t_end (got ", s.t_release, ", ", s.t_end, ")");
  require_positive(s.rest_tolerance, "vessel experiment: rest_tolerance");
  const FrameReference& ref = vessel.frame_reference();
  const Vec3 t = row3(ref.F0.t, s.atom);
  Vec3 d = s.direction.isZero() ? row3(ref.F0.u, s.atom) : s.direction;
  require(d.allFinite(), "vessel experiment: direction must be finite");
  d -= d.dot(t) * t;  // transverse to the rest tangent
  require(d.norm() > 1e-12, "vessel experiment: direction is parallel to the tangent of atom ", s.atom);
  d.normalize();

  VesselExperimentResult res;
  res.atom = s.atom;
  res.direction = d;
  res.contact_node = vessel.contact_node(s.atom, d);
  const Index c = res.contact_node;
  const MatX3& S0 = vessel.rest_surface();
  const long frames = static_cast<long>(std::ceil(s.t_end / s.dt - 1e-9));

  auto run = [&](double force, bool nonlinear) {
    VesselRun r;
    r.force = force;
    r.nonlinear = nonlinear;
    const Model m = vessel.make_chain(nonlinear);
    State st = make_state(m);
    PointLoad load;
    load.node = s.atom;
    load.force = force * d;
    load.t_ramp = s.t_ramp;
    load.t_release = s.t_release;
    const std::vector<PointLoad> loads{load};
    const StepSettings step_settings{.dt = s.dt};
    SmrmVessel::Workspace ws = vessel.make_workspace();
    MatX3 S = S0;
    r.time.resize(frames);
    r.atom_displacement.resize(frames);
    r.contact_displacement.resize(frames);
    r.max_surface_displacement.resize(frames);
    bool held = false;
    for (long f = 0; f < frames; ++f) {
      step(m, st, step_settings, &loads);
      vessel.map_to_surface(st.x, ws, S);
      const Index q = static_cast<Index>(f);
      r.time[q] = st.t;
      r.atom_displacement[q] = (row3(st.x, s.atom) - row3(m.x0, s.atom)).norm();
      r.contact_displacement[q] = (row3(S, c) - row3(S0, c)).norm();
      r.max_surface_displacement[q] = (S - S0).rowwise().norm().maxCoeff();
      const CurvatureCheck v = vessel.validity(st.x);
      r.max_rho_kappa = std::max(r.max_rho_kappa, v.max_rho_kappa);
      r.rho_kappa_violations += v.violations;
      Index ta = -1;
      const double turn = vessel.max_turning_change_deg(st.x, &ta);
      if (turn > r.max_turning_change_deg || r.max_turning_atom < 0) {
        r.max_turning_change_deg = turn;
        r.max_turning_atom = ta;
      }
      if (!held && st.t >= s.t_release - 1e-9) {  // the last loaded state (release acts on the next frame)
        held = true;
        r.profile = st.x - m.x0;
        r.surface = S;
        r.atom_hold = r.atom_displacement[q];
        r.contact_hold = r.contact_displacement[q];
      }
    }
    Index last_out = -1;
    for (Index q = 0; q < static_cast<Index>(frames); ++q)
      if (r.time[q] >= s.t_release - 1e-9 && r.max_surface_displacement[q] > s.rest_tolerance) last_out = q;
    if (last_out + 1 < static_cast<Index>(frames))
      r.return_time = last_out < 0 ? 0.0 : std::max(0.0, r.time[last_out + 1] - s.t_release);
    r.warnings = st.warnings.total();
    return r;
  };
  res.light_linear = run(s.light, false);
  res.light_nonlinear = run(s.light, true);
  res.strong_linear = run(s.strong, false);
  res.strong_nonlinear = run(s.strong, true);
  return res;
}

}  // namespace medspring
