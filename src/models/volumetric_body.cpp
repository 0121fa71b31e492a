#include "medspring/models/volumetric_body.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>

#include "medspring/core/check.hpp"
#include "medspring/models/volumetric_moduli.hpp"

namespace medspring {

const char* to_string(MeshSizing s) {
  return s == MeshSizing::Surface ? "surface" : "volume";
}

MeshSizing parse_mesh_sizing(const std::string& text) {
  if (text == "volume") return MeshSizing::Volume;
  if (text == "surface") return MeshSizing::Surface;
  throw InvalidInput(cat("unknown interior sizing '", text, "' (expected volume or surface)"));
}

const char* to_string(ThinTetMode m) {
  return m == ThinTetMode::ScaleSprings ? "scale_springs" : m == ThinTetMode::Clip ? "clip" : "off";
}

ThinTetMode parse_thin_tet_mode(const std::string& text) {
  if (text == "off") return ThinTetMode::Off;
  if (text == "scale_springs") return ThinTetMode::ScaleSprings;
  if (text == "clip") return ThinTetMode::Clip;
  throw InvalidInput(cat("unknown thin-tetrahedron term '", text, "' (expected off, scale_springs or clip)"));
}

const char* to_string(VolumePrecision p) {
  return p == VolumePrecision::Float ? "float" : "double";
}

VolumePrecision parse_volume_precision(const std::string& text) {
  if (text == "double") return VolumePrecision::Double;
  if (text == "float") return VolumePrecision::Float;
  throw InvalidInput(cat("unknown volume pass precision '", text, "' (expected double or float)"));
}

void lame_parameters(double E_kPa, double nu, double& mu, double& lambda, const std::string& where) {
  require(std::isfinite(E_kPa) && E_kPa > 0, where, ".E_kPa: must be > 0 (got ", E_kPa, ")");
  require(std::isfinite(nu) && nu > -1.0 && nu < 0.5, where, ".nu: must be in (-1, 0.5) (got ", nu, ")");
  const double E = E_kPa * 1e-3;  // kPa -> N/mm^2
  mu = E / (2.0 * (1.0 + nu));
  lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
}

double winding_number(const MatX3& V, const MatX3i& F, const Vec3& p) {
  double omega = 0;
  for (Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = V.row(F(f, 0)).transpose() - p, b = V.row(F(f, 1)).transpose() - p,
               c = V.row(F(f, 2)).transpose() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    omega += 2.0 * std::atan2(num, den);
  }
  return omega / (4.0 * M_PI);
}

namespace {

constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

}  // namespace

VolumetricBody::VolumetricBody(const VolumetricMesh& mesh, const VolumetricSettings& s, std::string name)
    : mesh_(mesh), F_(mesh.F), settings_(s) {
  const std::string& w = name;
  double mu = 0, lambda = 0;
  lame_parameters(s.E_kPa, s.nu, mu, lambda, w + ": material");
  require(std::isfinite(s.density) && s.density > 0, w, ": density must be > 0 (got ", s.density, ")");
  require(std::isfinite(s.beta) && s.beta >= 0, w, ": beta must be >= 0 (got ", s.beta, ")");
  require(std::isfinite(s.spring_scale) && s.spring_scale > 0, w, ": spring_scale must be > 0");
  require(std::isfinite(s.volume_scale) && s.volume_scale >= 0, w, ": volume_scale must be >= 0");
  require(std::isfinite(s.surface_spring_scale) && s.surface_spring_scale > 0, w,
          ": surface_spring_scale must be > 0 (got ", s.surface_spring_scale, ")");
  require(std::isfinite(s.overlay_compliance) && s.overlay_compliance >= 0, w,
          ": overlay_compliance must be >= 0 (0 = no local overlay; got ", s.overlay_compliance, ")");
  require(std::isfinite(s.compression) && s.compression >= 0, w, ": compression must be >= 0 (got ",
          s.compression, ")");
  const Index n = static_cast<Index>(mesh.X.rows()), ns = mesh.surface_nodes,
              nt = static_cast<Index>(mesh.T.rows());
  require(ns >= 4 && ns <= n, w, ": surface_nodes ", ns, " must be in [4, ", n, "]");
  require(nt >= 1, w, ": the mesh has no tetrahedra");
  require(mesh.X.allFinite(), w, ": node coordinates must be finite");
  for (Index f = 0; f < mesh.F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      require(mesh.F(f, k) >= 0 && mesh.F(f, k) < ns, w, ": surface face ", f, ": node ", mesh.F(f, k),
              " is not a surface node [0, ", ns, ")");
  const double scale = (mesh.X.colwise().maxCoeff() - mesh.X.colwise().minCoeff()).norm();

  // tetrahedra: range, then (after the interior nodes are located) orientation and degeneracy
  const MatX4i& T = mesh.T;
  std::vector<double> vol(static_cast<std::size_t>(nt));
  std::vector<int> used(static_cast<std::size_t>(n), 0);
  for (Index t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) {
      require(T(t, k) >= 0 && T(t, k) < n, w, ": tetrahedron ", t, ": node ", T(t, k), " out of range [0, ",
              n, ")");
      used[static_cast<std::size_t>(T(t, k))] = 1;
    }
  for (Index i = 0; i < n; ++i)
    require(used[static_cast<std::size_t>(i)], w, ": node ", i, " belongs to no tetrahedron");
  rest_surface_ = mesh.X.topRows(ns);
  // interior nodes inside the surface (generalised winding number)
  for (Index i = ns; i < n; ++i) {
    const double wn = winding_number(rest_surface_, mesh.F, mesh.X.row(i).transpose());
    require(wn > 0.5, w, ": interior node ", i, " at (", mesh.X(i, 0), ", ", mesh.X(i, 1), ", ", mesh.X(i, 2),
            ") lies outside the surface (winding number ", wn, ")");
  }
  stats_.min_tet_volume = 1e300;
  for (Index t = 0; t < nt; ++t) {
    const Vec3 p0 = mesh.X.row(T(t, 0)), p1 = mesh.X.row(T(t, 1)), p2 = mesh.X.row(T(t, 2)),
               p3 = mesh.X.row(T(t, 3));
    const double V = signed_tet_volume(p0, p1, p2, p3);
    double L = 0;
    for (const auto& e : kEdges) L = std::max(L, (mesh.X.row(T(t, e[0])) - mesh.X.row(T(t, e[1]))).norm());
    require(std::abs(V) > 1e-9 * L * L * L && L > 1e-12 * scale, w, ": tetrahedron ", t, " (nodes ", T(t, 0),
            " ", T(t, 1), " ", T(t, 2), " ", T(t, 3), ") is degenerate (volume ", V, " mm^3)");
    require(V > 0, w, ": tetrahedron ", t, " (nodes ", T(t, 0), " ", T(t, 1), " ", T(t, 2), " ", T(t, 3),
            ") is inverted (volume ", V,
            " mm^3; corners must be ordered so that (x1-x0).((x2-x0)x(x3-x0)) > 0)");
    vol[static_cast<std::size_t>(t)] = V;
    stats_.volume_mm3 += V;
    stats_.min_tet_volume = std::min(stats_.min_tet_volume, V);
  }

  // the surface must be the mesh's boundary (faces used by one tetrahedron), so that the identity map holds
  {
    std::map<std::array<Index, 3>, int> count;
    for (Index t = 0; t < nt; ++t)
      for (int o = 0; o < 4; ++o) {
        std::array<Index, 3> f{};
        int m = 0;
        for (int k = 0; k < 4; ++k)
          if (k != o) f[static_cast<std::size_t>(m++)] = T(t, k);
        std::sort(f.begin(), f.end());
        ++count[f];
      }
    std::set<std::array<Index, 3>> boundary, surface;
    for (const auto& [f, c] : count) {
      require(c <= 2, w, ": face (", f[0], " ", f[1], " ", f[2], ") is shared by ", c,
              " tetrahedra (overlapping elements)");
      if (c == 1) boundary.insert(f);
    }
    for (Index f = 0; f < mesh.F.rows(); ++f) {
      std::array<Index, 3> a{mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2)};
      std::sort(a.begin(), a.end());
      surface.insert(a);
    }
    for (const auto& f : boundary)
      require(surface.count(f), w, ": boundary face (", f[0], " ", f[1], " ", f[2],
              ") of the tetrahedra is not a surface triangle (the surface must be the mesh's boundary)");
    for (const auto& f : surface)
      require(boundary.count(f), w, ": surface triangle (", f[0], " ", f[1], " ", f[2],
              ") is not a boundary face of the tetrahedra");
  }
  // supports
  for (Index a : s.fixed)
    require(a >= 0 && a < ns, w, ": fixed node ", a, " is not a surface node [0, ", ns, ")");
  const double kr = s.return_k ? *s.return_k : (s.fixed.empty() ? 0.02 : 0.0);
  require(std::isfinite(kr) && kr >= 0, w, ": return_k must be >= 0 (got ", kr, ")");
  if (kr == 0) {
    require(!s.fixed.empty(), w,
            ": no supports and no return springs: every rigid motion is free (pin surface nodes or set "
            "return_k)");
    Vec3 c = Vec3::Zero();
    for (Index a : s.fixed) c += mesh.X.row(a).transpose();
    c /= static_cast<double>(s.fixed.size());
    Mat3 C = Mat3::Zero();
    for (Index a : s.fixed) {
      const Vec3 d = mesh.X.row(a).transpose() - c;
      C += d * d.transpose();
    }
    const Eigen::JacobiSVD<Mat3> svd(C);
    const double tol = 1e-10 * scale * scale * static_cast<double>(s.fixed.size());
    require(svd.singularValues()(1) > tol, w, ": the ", s.fixed.size(),
            " fixed nodes are collinear or coincident: the rotation about their line is free (pin at least "
            "three non-collinear surface nodes or set return_k)");
  }

  // stiffness rule (header): springs k = 5/2 mu V / L^2 per tetrahedron, volume modulus lambda - mu
  const double kv = std::max(lambda - mu, 0.0);
  if (s.moduli_correction) {  // opt-in: the measured effective moduli (volumetric_moduli.hpp)
    const ModuliCorrection c = moduli_correction(mesh, mu, lambda);
    settings_.spring_scale *= c.spring;
    settings_.volume_scale *= c.volume;
    settings_.moduli_correction = false;
    stats_.spring_correction = c.spring;
    stats_.volume_correction = c.volume;
    stats_.mu_ratio_before = c.mu_before;
    stats_.K_ratio_before = c.K_before;
  }
  const double spring_scale = settings_.spring_scale, volume_scale = settings_.volume_scale;
  if (lambda < mu)
    warnings_.push_back(
        cat(w, ": nu = ", s.nu, " < 1/4: the volume term is off and the springs alone give nu near 1/4"));
  stats_.mu = mu;
  stats_.lambda = lambda;
  stats_.kv = kv * volume_scale;
  // opt-in thin-tetrahedron terms (thin_tet_correction.hpp): built before the springs, whose share of each
  // flagged tetrahedron scale_springs scales by the term's spring_factor
  ThinTetCorrections thin;
  std::vector<double> share(static_cast<std::size_t>(nt), 1.0);
  if (s.thin_tet != ThinTetMode::Off) {
    require(std::isfinite(s.thin_tet_q_max) && s.thin_tet_q_max > 0 && s.thin_tet_q_max <= 1, w,
            ": thin_tet_q_max must be in (0, 1] (got ", s.thin_tet_q_max, ")");
    std::vector<std::array<Index, 4>> tets(static_cast<std::size_t>(nt));
    for (Index t = 0; t < nt; ++t) tets[static_cast<std::size_t>(t)] = {T(t, 0), T(t, 1), T(t, 2), T(t, 3)};
    const ThinTetSettings ts{.E = s.E_kPa * 1e-3,
                             .nu = s.nu,
                             .q_max = s.thin_tet_q_max,
                             .spring_scale = spring_scale,
                             .volume_scale = volume_scale,
                             .projection = s.thin_tet == ThinTetMode::Clip ? ThinTetProjection::Clip
                                                                           : ThinTetProjection::ScaleSprings};
    thin = build_thin_tet_corrections(mesh.X, tets, ts, w + ": thin_tet");
    double sum = 0;
    for (Index k = 0; k < thin.size(); ++k) {
      share[static_cast<std::size_t>(thin.tet[static_cast<std::size_t>(k)])] =
          thin.spring_factor[static_cast<std::size_t>(k)];
      sum += thin.spring_factor[static_cast<std::size_t>(k)];
    }
    stats_.thin_tets = thin.size();
    stats_.thin_spring_factor = thin.size() > 0 ? sum / static_cast<double>(thin.size()) : 1.0;
  }
  std::map<std::pair<Index, Index>, double> edge_k;
  std::vector<double> mass(static_cast<std::size_t>(n), 0.0);
  for (Index t = 0; t < nt; ++t) {
    const double V = vol[static_cast<std::size_t>(t)];
    for (const auto& e : kEdges) {
      const Index a = T(t, e[0]), b = T(t, e[1]);
      const double L2 = (mesh.X.row(a) - mesh.X.row(b)).squaredNorm();
      edge_k[std::minmax(a, b)] += 2.5 * mu * V / L2 * spring_scale * share[static_cast<std::size_t>(t)];
    }
    for (int k = 0; k < 4; ++k) mass[static_cast<std::size_t>(T(t, k))] += 0.25 * s.density * V;
  }
  // the opt-in surface-layer family: the springs between two surface nodes scaled once more (1: untouched)
  for (auto& [e, k] : edge_k)
    if (e.first < ns && e.second < ns) {
      ++stats_.surface_springs;
      if (s.surface_spring_scale != 1.0) k *= s.surface_spring_scale;
    }
  require(std::isfinite(s.min_mass_fraction) && s.min_mass_fraction >= 0 && s.min_mass_fraction <= 1, w,
          ": min_mass_fraction must be in [0, 1]");
  require(std::isfinite(s.mass_scaling_dt) && s.mass_scaling_dt >= 0, w,
          ": mass_scaling_dt must be >= 0 ms (got ", s.mass_scaling_dt, ")");
  double lumped = 0;
  for (double m : mass) lumped += m;
  {
    const double floor = s.min_mass_fraction * lumped / static_cast<double>(n);
    for (double& m : mass) m = std::max(m, floor);
  }
  if (s.mass_scaling_dt > 0) {
    // Selective mass scaling: the block Gershgorin bound omega^2 <= max_i (1/m_i) sum_j |K_ij| of M^-1 K at
    // rest (springs: |K_ij| = k; volume terms: kv/V0 |g_k| |g_l|, g = dV/dx), with the free neighbours
    // only. m_i >= R_i / omega_t^2 puts every row below omega_t = 2 * 0.8 / (1.25 dt): the run-time step
    // (dt_safe: safety 0.8, power iteration x 1.05) then allows dt with 1.25 / 1.05 to spare for the
    // run-time stiffening.
    std::vector<std::uint8_t> pinned(static_cast<std::size_t>(n), 0);
    for (Index a : s.fixed) pinned[static_cast<std::size_t>(a)] = 1;
    std::vector<double> row(static_cast<std::size_t>(n), 0.0);
    for (const auto& [e, k] : edge_k) {
      const auto a = static_cast<std::size_t>(e.first), b = static_cast<std::size_t>(e.second);
      row[a] += k * (pinned[b] ? 1.0 : 2.0);
      row[b] += k * (pinned[a] ? 1.0 : 2.0);
    }
    const double kvs = kv * volume_scale;
    if (kvs > 0)
      for (Index t = 0; t < nt; ++t) {
        const Vec3 x0 = mesh.X.row(T(t, 0)).transpose(), e1 = mesh.X.row(T(t, 1)).transpose() - x0,
                   e2 = mesh.X.row(T(t, 2)).transpose() - x0, e3 = mesh.X.row(T(t, 3)).transpose() - x0;
        Vec3 g[4];
        g[1] = e2.cross(e3) / 6.0;
        g[2] = e3.cross(e1) / 6.0;
        g[3] = e1.cross(e2) / 6.0;
        g[0] = -(g[1] + g[2] + g[3]);
        const double c = kvs / vol[static_cast<std::size_t>(t)];
        for (int k = 0; k < 4; ++k) {
          double sum = 0;
          for (int l = 0; l < 4; ++l)
            if (l == k || !pinned[static_cast<std::size_t>(T(t, l))]) sum += g[l].norm();
          row[static_cast<std::size_t>(T(t, k))] += c * g[k].norm() * sum;
        }
      }
    const double wt = 2.0 * 0.8 / (1.25 * s.mass_scaling_dt);
    for (Index i = 0; i < n; ++i) {
      const double need = row[static_cast<std::size_t>(i)] / (wt * wt);
      if (!pinned[static_cast<std::size_t>(i)] && need > mass[static_cast<std::size_t>(i)]) {
        mass[static_cast<std::size_t>(i)] = need;
        ++stats_.scaled_nodes;
      }
    }
  }
  for (double m : mass) stats_.mass_g += m;
  stats_.added_mass_fraction = stats_.mass_g / lumped - 1.0;
  ModelBuilder b(name);
  for (Index i = 0; i < n; ++i) {
    const double m = mass[static_cast<std::size_t>(i)];
    b.add_node(mesh.X.row(i).transpose(), m, s.beta * m, i < ns ? kr : 0.0, false);
  }
  for (Index a : s.fixed) b.set_fixed(a);
  b.reserve_springs(static_cast<Index>(edge_k.size()));
  std::vector<double> surf_k;
  for (const auto& [e, k] : edge_k) {
    b.add_spring(e.first, e.second, k, s.duffing);
    if (e.first < ns && e.second < ns) surf_k.push_back(k);
  }
  if (kv * volume_scale > 0)
    for (Index t = 0; t < nt; ++t) b.add_volume(T(t, 0), T(t, 1), T(t, 2), T(t, 3), kv * volume_scale);
  if (s.compression > 0) {  // compression stiffening (physics/compression_terms.hpp)
    stats_.kc = s.compression * mu * spring_scale;
    for (Index t = 0; t < nt; ++t) b.add_compression(T(t, 0), T(t, 1), T(t, 2), T(t, 3), stats_.kc);
  }
  if (thin.size() > 0) b.set_thin_tet(std::move(thin));
  model_ = b.build();
  if (s.volume_precision == VolumePrecision::Float &&
      model_.volume.size() > 0)  // opt-in (docs/volumetric-speed.md)
    set_volume_single_precision(model_, true);
  if (!surf_k.empty()) {
    std::nth_element(surf_k.begin(), surf_k.begin() + static_cast<long>(surf_k.size() / 2), surf_k.end());
    k_local_ = surf_k[surf_k.size() / 2];
  }
  stats_.nodes = n;
  stats_.surface_nodes = ns;
  stats_.interior_nodes = n - ns;
  stats_.tetrahedra = nt;
  stats_.springs = model_.num_springs();
}

void VolumetricBody::map_to_surface(const State& state, MatX3& surface) const {
  const Index ns = static_cast<Index>(rest_surface_.rows());
  if (surface.rows() != ns) surface.resize(ns, 3);
  surface = state.x.topRows(ns);
}

void VolumetricBody::transfer_force(Index node, const Vec3& F, MatX3& f_dof) const {
  f_dof.row(node) += F.transpose();
}

std::vector<std::uint8_t> VolumetricBody::fixed_surface_nodes() const {
  return {model_.fixed.begin(), model_.fixed.begin() + rest_surface_.rows()};
}

}  // namespace medspring
