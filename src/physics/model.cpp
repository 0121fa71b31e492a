#include "medspring/physics/model.hpp"

#include <algorithm>

#include "compression_rows.hpp"
#include "medspring/core/binary.hpp"
#include "medspring/core/check.hpp"
#include "medspring/core/memory.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/physics/stability.hpp"
#include "medspring/physics/state.hpp"
#include "spring_gather.hpp"
#include "volume_f32.hpp"

namespace medspring {

double duffing_coefficient(double k, double L0, const DuffingSettings& s) {
  double kp = 0.0;
  switch (s.mode) {
    case DuffingMode::Linear:
      return 0.0;
    case DuffingMode::Strain:  // D-3: phi = k L0 (eps + eta eps^3)
      require_positive(L0, "duffing: rest length");
      kp = s.eta * k / (L0 * L0);
      break;
    case DuffingMode::Absolute:  // the paper's k' = 0.01 k with a 10 mm Duffing length
      require_positive(s.length, "duffing: length");
      kp = k / (s.length * s.length);
      break;
    case DuffingMode::ScaledStrain:
      require_positive(L0, "duffing: rest length");
      kp = k / (100.0 * L0 * L0);
      break;
  }
  return s.soft ? -kp : kp;
}

DuffingMode parse_duffing_mode(const std::string& text) {
  if (text == "linear" || text == "Linear") return DuffingMode::Linear;
  if (text == "strain" || text == "Strain") return DuffingMode::Strain;
  if (text == "absolute" || text == "Absolute" || text == "paper" || text == "PaperLiteral")
    return DuffingMode::Absolute;
  if (text == "scaled_strain" || text == "ScaledStrain") return DuffingMode::ScaledStrain;
  throw InvalidInput(
      cat("duffing mode: unknown value '", text, "' (expected linear, strain, absolute or scaled_strain)"));
}

std::string to_string(DuffingMode mode) {
  switch (mode) {
    case DuffingMode::Linear:
      return "linear";
    case DuffingMode::Strain:
      return "strain";
    case DuffingMode::Absolute:
      return "absolute";
    case DuffingMode::ScaledStrain:
      return "scaled_strain";
  }
  return "strain";
}

void Springs::reserve(Index n) {
  for (auto* v : {&i, &j}) v->reserve(static_cast<std::size_t>(n));
  for (auto* v : {&L0, &k, &kp}) v->reserve(static_cast<std::size_t>(n));
}

Index Springs::add(Index a, Index b, double rest_length, double stiffness, double cubic) {
  const Index s = size();
  i.push_back(a);
  j.push_back(b);
  L0.push_back(rest_length);
  k.push_back(stiffness);
  kp.push_back(cubic);
  return s;
}

void finalize(Model& m) {
  const std::string& w = m.name;
  const Index n = m.num_nodes();
  require(n >= 1, w, ": model has no nodes");
  require(m.mass.size() == n, w, ": mass has ", m.mass.size(), " entries, expected ", n);
  require(m.damping.size() == n, w, ": damping has ", m.damping.size(), " entries, expected ", n);
  require(m.kr.size() == n, w, ": kr has ", m.kr.size(), " entries, expected ", n);
  if (m.fixed.empty()) m.fixed.assign(static_cast<std::size_t>(n), 0);
  require(static_cast<Index>(m.fixed.size()) == n, w, ": fixed has ", m.fixed.size(), " entries, expected ",
          n);
  require_finite_points(m.x0, cat(w, ": x0"));
  for (Index a = 0; a < n; ++a) {
    require_positive(m.mass[a], w, ": nodes[", a, "].mass");
    require_nonnegative(m.damping[a], w, ": nodes[", a, "].damping");
    require_nonnegative(m.kr[a], w, ": nodes[", a, "].kr");
  }
  const Springs& S = m.springs;
  const Index ns = S.size();
  const auto nss = static_cast<std::size_t>(ns);
  require(S.j.size() == nss && S.L0.size() == nss && S.k.size() == nss && S.kp.size() == nss, w,
          ": springs arrays have inconsistent sizes");
  m.has_soft_springs = false;
  m.inv_k.resize(ns);
  for (Index s = 0; s < ns; ++s) {
    require_index(S.i[s], n, w, ": springs[", s, "].i");
    require_index(S.j[s], n, w, ": springs[", s, "].j");
    require(S.i[s] != S.j[s], w, ": springs[", s, "]: joins node ", S.i[s], " to itself");
    require_nonnegative(S.k[s], w, ": springs[", s, "].k");
    require_finite(S.kp[s], w, ": springs[", s, "].kp");
    require_nonnegative(S.L0[s], w, ": springs[", s, "].L0");
    require(S.L0[s] >= 1e-9, w, ": springs[", s, "].L0: zero-length spring between nodes ", S.i[s], " and ",
            S.j[s], " (rest length ", S.L0[s], " mm < 1e-9 mm)");
    if (S.kp[s] < 0) {
      require(S.k[s] > 0, w, ": springs[", s, "]: a soft spring (kp < 0) needs k > 0");
      m.has_soft_springs = true;
    }
    m.inv_k[s] = S.k[s] > 0 ? 1.0 / S.k[s] : 0.0;
  }
  const BendingTerms& B = m.bending;
  for (Index t = 0; t < B.size(); ++t) {
    require_index(B.a[t], n, w, ": bending[", t, "].a");
    require_index(B.b[t], n, w, ": bending[", t, "].b");
    require_index(B.c[t], n, w, ": bending[", t, "].c");
    require_nonnegative(B.kb[t], w, ": bending[", t, "].kb");
  }
  if (m.volume.size() > 0) {
    // The records alone: letting them own springs too (plan_owned_springs, the fused pass) measured
    // slower than the packed volume pass followed by the plain spring pass (docs/volumetric-speed.md).
    finalize_volume_terms(m.volume, m.x0, w);
    set_volume_rest_rows(m.volume, m.x0, m.mass, m.fixed);  // the stable step's local stiffening
  }
  if (m.compression.size() > 0) {
    finalize_compression_terms(m.compression, m.x0, w);
    fuse_compression_terms(m.volume, m.compression);  // on the volume terms' tetrahedra: one pass (issue 23)
  }
  if (m.thin.size() > 0) validate_thin_tet_corrections(m.thin, n, w);  // issue 23, thin tetrahedra
  if (m.volume_f32) set_volume_single_precision(m, true);  // its float rest data from the records just built
  m.free_nodes.clear();
  for (Index a = 0; a < n; ++a)
    if (!m.fixed[a]) m.free_nodes.push_back(a);
  m.omega_gershgorin = gershgorin_omega(m, m.x0);
  m.omega_rest = power_iteration_omega(m, m.x0);
  if (!(m.omega_rest > 0)) m.omega_rest = m.omega_gershgorin > 0 ? m.omega_gershgorin : 1e-12;
  detail::build_spring_gather(m);
  m.finalized = true;
}

ModelBuilder::ModelBuilder(std::string name) : name_(std::move(name)) {}

Index ModelBuilder::add_node(const Vec3& p, const NodeParams& q) {
  return add_node(p, q.mass, q.beta * q.mass, q.return_k, false);
}

Index ModelBuilder::add_node(const Vec3& p, double mass, double damping, double return_k, bool fixed) {
  nodes_.push_back(p);
  mass_.push_back(mass);
  damping_.push_back(damping);
  kr_.push_back(return_k);
  fixed_.push_back(fixed ? 1 : 0);
  return static_cast<Index>(nodes_.size()) - 1;
}

Index ModelBuilder::add_spring(Index a, Index b, double k, const DuffingSettings& duffing) {
  require_index(a, num_nodes(), name_, ": spring end a");
  require_index(b, num_nodes(), name_, ": spring end b");
  const double L0 = (nodes_[b] - nodes_[a]).norm();
  return springs_.add(a, b, L0, k, L0 > 0 ? duffing_coefficient(k, L0, duffing) : 0.0);
}

Index ModelBuilder::add_spring(Index a, Index b, double k, double kp, double rest_length) {
  return springs_.add(a, b, rest_length, k, kp);
}

void ModelBuilder::set_fixed(Index node, bool fixed) {
  require_index(node, num_nodes(), name_, ": fixed node");
  fixed_[node] = fixed ? 1 : 0;
}

void ModelBuilder::add_bending(Index a, Index b, Index c, double kb) {
  bending_.a.push_back(a);
  bending_.b.push_back(b);
  bending_.c.push_back(c);
  const Index t = bending_.size() - 1;
  bending_.kb.conservativeResize(t + 1);
  bending_.kb[t] = kb;
  bending_.D0.conservativeResize(t + 1, 3);
  require_index(a, num_nodes(), name_, ": bending[", t, "].a");
  require_index(b, num_nodes(), name_, ": bending[", t, "].b");
  require_index(c, num_nodes(), name_, ": bending[", t, "].c");
  bending_.D0.row(t) = (nodes_[a] - 2.0 * nodes_[b] + nodes_[c]).transpose();
}

Model ModelBuilder::build() {
  Model m;
  m.name = name_;
  const Index n = num_nodes();
  m.x0.resize(n, 3);
  m.mass.resize(n);
  m.damping.resize(n);
  m.kr.resize(n);
  for (Index a = 0; a < n; ++a) {
    m.x0.row(a) = nodes_[a].transpose();
    m.mass[a] = mass_[a];
    m.damping[a] = damping_[a];
    m.kr[a] = kr_[a];
  }
  // The builder hands its arrays over (a 1M-node model is not held twice while finalize runs); it is
  // left empty, as after construction.
  std::vector<Vec3>().swap(nodes_);
  for (auto* v : {&mass_, &damping_, &kr_}) std::vector<double>().swap(*v);
  m.fixed = std::move(fixed_);
  m.springs = std::move(springs_);
  m.bending = std::move(bending_);
  m.volume = std::move(volume_);
  m.compression = std::move(compression_);
  m.thin = std::move(thin_);
  fixed_.clear();
  springs_ = Springs{};
  bending_ = BendingTerms{};
  volume_ = VolumeTerms{};
  compression_ = CompressionTerms{};
  thin_ = ThinTetCorrections{};
  finalize(m);
  return m;
}

Model make_surface_model(const SurfaceMesh& mesh, const SurfaceBodyParams& p, const std::string& name) {
  require_memory(kModelBuildBytesPerNode * static_cast<double>(mesh.num_vertices()),
                 cat(name, ": a model of ", mesh.num_vertices(), " nodes"));
  require_valid_mesh(mesh, name, {.closed = false, .manifold = false});
  ModelBuilder b(name);
  for (Index a = 0; a < mesh.num_vertices(); ++a) b.add_node(mesh.V.row(a).transpose(), p.node);
  {
    const MatX2i E = unique_edges(mesh.F);
    b.reserve_springs(static_cast<Index>(E.rows()));
    for (Index s = 0; s < E.rows(); ++s) {
      const double L0 = (mesh.V.row(E(s, 1)) - mesh.V.row(E(s, 0))).norm();
      if (L0 < 1e-9) continue;  // §1.1: drop edges shorter than 1e-9 mm
      b.add_spring(E(s, 0), E(s, 1), p.k, p.duffing);
    }
  }
  for (std::size_t q = 0; q < p.fixed.size(); ++q) {
    require_index(p.fixed[q], mesh.num_vertices(), name, ": fixed[", q, "]");
    b.set_fixed(p.fixed[q]);
  }
  return b.build();
}

State make_state(const Model& m) {
  require(m.finalized, m.name, ": model is not finalized (call finalize or ModelBuilder::build)");
  const Index n = m.num_nodes();
  const Index ns = m.num_springs();
  State s;
  s.x = m.x0;
  s.v.setZero(n, 3);
  s.f_ext.setZero(n, 3);
  s.f.setZero(n, 3);
  s.x_save.setZero(n, 3);
  s.v_save.setZero(n, 3);
  s.x_trial.setZero(n, 3);
  s.step_coef.setZero(n);
  if (m.volume.size() > 0 || m.compression.size() > 0)
    s.stiff_rows.setZero(stiff_rows_size(n, m.volume.size(), m.compression.size()));  // issue 23
  if (m.volume_f32) s.volume_f32.assign(static_cast<std::size_t>(kVolumeF32ScratchPerNode * n), 0.0f);
  for (VecX* b : {&s.cg_r, &s.cg_z, &s.cg_p, &s.cg_q, &s.dv, &s.rhs, &s.jacobi}) b->setZero(3 * n);
  s.spring_a.setZero(ns);
  s.spring_b.setZero(ns);
  s.spring_n.setZero(ns, 3);
  detail::gather_ready(m, s);  // the gather pass's slot buffer (spring_gather.hpp)
  return s;
}

namespace {

template <class T>
std::uint64_t hash_vector(const std::vector<T>& v, std::uint64_t h) {
  const std::uint64_t n = v.size();
  h = fnv1a64(&n, sizeof n, h);
  return v.empty() ? h : fnv1a64(v.data(), v.size() * sizeof(T), h);
}
template <class Derived>
std::uint64_t hash_dense(const Eigen::DenseBase<Derived>& m, std::uint64_t h) {
  const std::uint64_t n = static_cast<std::uint64_t>(m.size());
  h = fnv1a64(&n, sizeof n, h);
  for (Index r = 0; r < m.rows(); ++r)
    for (Index c = 0; c < m.cols(); ++c) {
      const auto v = m.derived()(r, c);
      h = fnv1a64(&v, sizeof v, h);
    }
  return h;
}

}  // namespace

std::uint64_t model_fingerprint(const Model& m) {
  std::uint64_t h = fnv1a64("medspring-model-v1", 18);
  const std::uint64_t n = static_cast<std::uint64_t>(m.num_nodes());
  h = fnv1a64(&n, sizeof n, h);
  h = hash_dense(m.x0, h);
  h = hash_dense(m.mass, h);
  h = hash_dense(m.damping, h);
  h = hash_dense(m.kr, h);
  h = hash_vector(m.fixed, h);
  const Springs& S = m.springs;
  h = hash_vector(S.i, h);
  h = hash_vector(S.j, h);
  h = hash_vector(S.L0, h);
  h = hash_vector(S.k, h);
  h = hash_vector(S.kp, h);
  const BendingTerms& B = m.bending;
  h = hash_vector(B.a, h);
  h = hash_vector(B.b, h);
  h = hash_vector(B.c, h);
  h = hash_dense(B.kb, h);
  if (m.volume.size() > 0) {  // appended only when present: fingerprints of other models unchanged
    const VolumeTerms& T = m.volume;
    h = hash_vector(T.a, h);
    h = hash_vector(T.b, h);
    h = hash_vector(T.c, h);
    h = hash_vector(T.d, h);
    h = hash_vector(T.kv, h);
  }
  if (m.compression.size() > 0) {  // appended only when present (issue 23, compression stiffening)
    const CompressionTerms& C = m.compression;
    for (const auto* v : {&C.a, &C.b, &C.c, &C.d}) h = hash_vector(*v, h);
    h = hash_vector(C.kc, h);
  }
  if (m.thin.size() > 0) {  // appended only when present (issue 23, thin-tetrahedron terms)
    const ThinTetCorrections& C = m.thin;
    h = hash_vector(C.n, h);
    h = hash_vector(C.V0, h);
    for (const Mat3& D : C.DmInv) h = hash_dense(D, h);
    for (const Mat6& c : C.C) h = hash_dense(c, h);
  }
  if (m.volume_f32) {  // appended only when present (issue 23): the float volume pass changes the trajectory,
    // so a checkpoint resumes, and a package rebuilds, with the precision it was saved with
    static constexpr char kF32[] = "volume_precision=float";
    h = fnv1a64(kF32, sizeof kF32 - 1, h);
  }
  return h;
}

void require_state_in_reach(const Model& m, const MatX3& x, const MatX3& v, const std::string& what) {
  const Index n = m.num_nodes();
  require(x.rows() == n && v.rows() == n, what, ": state has ", x.rows(), " positions and ", v.rows(),
          " velocities, the model has ", n, " nodes");
  require_finite_points(x, what, ": state.x");
  require_finite_points(v, what, ": state.v");
  if (n == 0) return;
  const double size = (m.x0.colwise().maxCoeff() - m.x0.colwise().minCoeff()).norm();
  const double reach = kStateReach * (1.0 + size);
  for (Index i = 0; i < n; ++i) {
    const double d = (x.row(i) - m.x0.row(i)).stableNorm();
    require(d <= reach, what, ": state.x: node ", i, " is ", d, " mm from its rest position (the model is ",
            size, " mm across; at most ", reach, ")");
    const double s = v.row(i).stableNorm();
    require(s <= reach, what, ": state.v: node ", i, " moves at ", s, " mm/ms (at most ", reach, ")");
  }
}

}  // namespace medspring
