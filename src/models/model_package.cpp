// Model packages (models/model_package.hpp): encode, decode with every field checked, rebuild.
#include "medspring/models/model_package.hpp"

#include <cmath>
#include <memory>

#include "medspring/core/binary.hpp"
#include "medspring/core/check.hpp"
#include "medspring/core/params_binary.hpp"

namespace medspring {

namespace {

const std::string kKind = "model package";
constexpr std::size_t kMaxText = 1 << 16;  // name, description

void put_points(ByteWriter& w, const MatX3& P) {
  w.u64(static_cast<std::uint64_t>(P.rows()));
  for (Index r = 0; r < P.rows(); ++r)
    for (int c = 0; c < 3; ++c) w.f64(P(r, c));
}
MatX3 get_points(ByteReader& r, const char* field) {
  const Index n = r.count(field, 3 * sizeof(double));
  MatX3 P(n, 3);
  for (Index i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) P(i, c) = r.f64();
  return P;
}
void put_indices(ByteWriter& w, const std::vector<Index>& v) {
  w.u64(v.size());
  for (Index i : v) w.i64(i);
}
std::vector<Index> get_indices(ByteReader& r, const char* field, Index bound) {
  const Index n = r.count(field, 8);
  std::vector<Index> v(static_cast<std::size_t>(n));
  for (Index k = 0; k < n; ++k) {
    const std::int64_t i = r.i64();
    if (i < 0 || i >= bound) r.fail(cat(field, "[", k, "]: index ", i, " out of range [0, ", bound, ")"));
    v[static_cast<std::size_t>(k)] = static_cast<Index>(i);
  }
  return v;
}
/// A node list read by get_params (which is structural): every index in [0, bound).
void check_indices(ByteReader& r, const std::vector<Index>& v, const char* field, Index bound) {
  for (std::size_t k = 0; k < v.size(); ++k)
    if (v[k] < 0 || v[k] >= bound)
      r.fail(cat(field, "[", k, "]: index ", v[k], " out of range [0, ", bound, ")"));
}
void put_doubles(ByteWriter& w, const VecX& v) {
  w.u64(static_cast<std::uint64_t>(v.size()));
  w.doubles(v.data(), static_cast<Index>(v.size()));
}
VecX get_doubles(ByteReader& r, const char* field) {
  const Index n = r.count(field, sizeof(double));
  VecX v(n);
  r.doubles(v.data(), n);
  return v;
}
template <class E>
E get_enum(ByteReader& r, const char* field, int count) {
  const std::uint8_t v = r.u8();
  if (v >= count) r.fail(cat(field, ": unknown value ", int{v}));
  return static_cast<E>(v);
}

NodeParams get_node(ByteReader& r) {
  NodeParams p;
  p.mass = r.f64();
  p.beta = r.f64();
  p.return_k = r.f64();
  return p;
}
void put_duffing(ByteWriter& w, const DuffingSettings& d) {
  w.u8(static_cast<std::uint8_t>(d.mode));
  w.f64(d.eta);
  w.f64(d.length);
  w.flag(d.soft);
}
DuffingSettings get_duffing(ByteReader& r) {
  DuffingSettings d;
  d.mode = get_enum<DuffingMode>(r, "duffing.mode", 4);
  d.eta = r.f64();
  d.length = r.f64();
  d.soft = r.flag("duffing.soft");
  return d;
}

// Version 5: the SMRM settings by declared name (smrm_vessel.hpp), beside the two fields the
// declaration leaves to the model's own keys (atoms, chain.nonlinear).
void put_smrm_settings(ByteWriter& w, const SmrmSettings& s) {
  w.i64(s.atoms);
  w.flag(s.chain.nonlinear);
  put_params(w, s);
}
void check_smrm_sizes(ByteReader& r, std::int64_t atoms, std::int64_t spokes) {
  if (atoms < 0 || spokes < 0 || atoms > (1 << 24) || spokes > (1 << 24))
    r.fail(cat("settings: atoms ", atoms, ", spokes ", spokes));
}
void get_smrm_settings(ByteReader& r, SmrmSettings& s, std::uint32_t version) {
  if (version >= 5) {
    const std::int64_t atoms = r.i64();
    s.chain.nonlinear = r.flag("chain.nonlinear");
    get_params(r, s, "smrm settings");
    check_smrm_sizes(r, atoms, s.spokes);
    s.atoms = static_cast<Index>(atoms);
    return;
  }
  // versions 1 to 4: the fields in a fixed order
  const std::int64_t atoms = r.i64(), sp = r.i64();
  check_smrm_sizes(r, atoms, sp);
  s.atoms = static_cast<Index>(atoms);
  s.spokes = static_cast<Index>(sp);
  s.frames.mode = get_enum<FrameMode>(r, "frames.mode", 2);
  s.frames.anchor = get_enum<FrameAnchor>(r, "frames.anchor", 3);
  ChainSettings& c = s.chain;
  c.k = r.f64();
  c.kr = r.f64();
  c.mass = r.f64();
  c.beta = r.f64();
  c.nonlinear = r.flag("chain.nonlinear");
  c.duffing = get_duffing(r);
  c.fix_first = r.flag("chain.fix_first");
  c.fix_last = r.flag("chain.fix_last");
  c.kb = r.f64();
  s.k_loc = r.f64();
  s.dedup_tolerance = r.f64();
  s.max_radius_factor = r.f64();
  if (version >= 2) {
    s.bending = get_enum<BendingMode>(r, "bending", 2);
    s.wall.E = r.f64();
    s.wall.thickness_ratio = r.f64();
  } else {
    s.bending = BendingMode::Constant;  // version 1 packages were saved from the chain.kb model
  }
}
}  // namespace

ModelPackage package_of(const Body& body, const std::string& name, const std::string& description) {
  ModelPackage p;
  p.name = name.empty() ? body.model().name : name;
  p.description = description;
  p.kind = body.kind();
  p.surface.V = body.rest_surface();
  p.surface.F = body.faces();
  p.grid = body.grid();
  p.fingerprint = model_fingerprint(body.model());
  if (const auto* s = dynamic_cast<const SurfaceBody*>(&body)) {
    p.surface_params = s->params();
  } else if (const auto* h = dynamic_cast<const HybridKidney*>(&body)) {
    // The package rebuilds the spokes by the union rule, without the organ's voxels (D-9).
    if (h->stats().visibility.rejected > 0)
      throw InvalidInput(cat("package_of: the spokes of '", body.model().name,
                             "' passed the visibility filter (", h->stats().visibility.rejected,
                             " rejected), which a model package cannot rebuild without the organ's voxels; "
                             "build it with HybridSettings::visibility_filter off to package it"));
    p.atoms = h->model().x0.bottomRows(h->num_atoms());
    p.hybrid = h->settings();
  } else if (const auto* v = dynamic_cast<const SmrmVessel*>(&body)) {
    p.atoms = v->rest_atoms();
    p.atom_radius = v->atom_radius();
    p.binding = v->binding();
    p.smrm = v->settings();
  } else if (const auto* q = dynamic_cast<const VolumetricBody*>(&body)) {
    p.volumetric_mesh = q->mesh();
    p.volumetric = q->settings();
  } else if (const auto* t = dynamic_cast<const SmrmTree*>(&body)) {
    p.tree = t->centerline_tree();
    p.smrm = t->settings().vessel;
  } else {
    throw InvalidInput(cat("package_of: unknown body kind '", body.kind(), "'"));
  }
  return p;
}

BodyPtr make_body(const ModelPackage& p) {
  const std::string w = cat("model package '", p.name, "'");
  try {
    if (p.kind == "surface")
      return std::make_shared<SurfaceBody>(p.surface, p.surface_params, p.name, p.grid);
    if (p.kind == "hybrid") return std::make_shared<HybridKidney>(p.surface, p.atoms, p.hybrid, p.name);
    if (p.kind == "smrm") {
      SmrmParts parts;
      parts.name = p.name;
      parts.atoms = p.atoms;
      parts.atom_radius = p.atom_radius;
      parts.binding = p.binding;
      finalize_binding(parts.binding);
      parts.rest_surface = p.surface.V;
      parts.faces = p.surface.F;
      parts.grid = p.grid;
      return std::make_shared<SmrmVessel>(std::move(parts), p.smrm);
    }
    if (p.kind == "smrm_tree") {
      auto t = std::make_shared<SmrmTree>(p.tree, SmrmTreeSettings{p.smrm});
      // A surface other than the tree's own tubes is its watertight junction surface (SmrmTree blended).
      if (p.surface.V.rows() > 0 && (p.surface.F.rows() != t->faces().rows() || p.surface.F != t->faces() ||
                                     p.surface.V.rows() != t->rest_surface().rows()))
        return std::make_shared<SmrmTree>(p.tree, SmrmTreeSettings{p.smrm}, p.surface);
      return t;
    }
    if (p.kind == "volumetric") {
      VolumetricMesh m = p.volumetric_mesh;
      m.F = p.surface.F;
      return std::make_shared<VolumetricBody>(m, p.volumetric, p.name);
    }
  } catch (const InvalidInput& e) {
    throw InvalidInput(cat(w, ": ", e.what()));
  }
  throw InvalidInput(
      cat(w, ": unknown kind '", p.kind, "' (expected surface, hybrid, smrm, smrm_tree or volumetric)"));
}

std::string encode_model_package(const ModelPackage& p) {
  ByteWriter w;
  w.str(p.name, kMaxText);
  w.str(p.description, kMaxText);
  w.str(p.kind);
  put_points(w, p.surface.V);
  w.u64(static_cast<std::uint64_t>(p.surface.F.rows()));
  for (Index f = 0; f < p.surface.F.rows(); ++f)
    for (int c = 0; c < 3; ++c) w.i64(p.surface.F(f, c));
  w.i64(p.grid.rings);
  w.i64(p.grid.spokes);
  if (p.kind == "surface") {
    put_params(w, p.surface_params);  // version 5: every declared field by name (physics/model.hpp)
  } else if (p.kind == "hybrid") {
    put_points(w, p.atoms);
    w.flag(p.hybrid.nonlinear);
    put_params(w, p.hybrid);  // version 3: every declared field by name (hybrid_kidney.hpp)
  } else if (p.kind == "smrm") {
    put_points(w, p.atoms);
    put_doubles(w, p.atom_radius);
    const SurfaceBinding& b = p.binding;
    w.i64(b.num_atoms);
    put_indices(w, b.atom);
    w.u64(b.lambda.size());
    for (double l : b.lambda) w.f64(l);
    put_points(w, b.offset);
    put_smrm_settings(w, p.smrm);
  } else if (p.kind == "smrm_tree") {
    w.u64(p.tree.branches.size());
    for (const CenterlineTree::Branch& b : p.tree.branches) {
      w.str(b.line.name, kMaxText);
      w.i64(b.parent);
      put_points(w, b.line.points);
      put_doubles(w, b.line.radii);
    }
    put_smrm_settings(w, p.smrm);
  } else if (p.kind == "volumetric") {
    const VolumetricMesh& m = p.volumetric_mesh;
    put_points(w, m.X);
    w.i64(m.surface_nodes);
    w.u64(static_cast<std::uint64_t>(m.T.rows()));
    for (Index t = 0; t < m.T.rows(); ++t)
      for (int c = 0; c < 4; ++c) w.i64(m.T(t, c));
    const VolumetricSettings& s = p.volumetric;
    for (double v : {s.E_kPa, s.nu, s.density, s.beta, s.spring_scale, s.volume_scale, s.min_mass_fraction})
      w.f64(v);
    w.flag(s.return_k.has_value());
    w.f64(s.return_k.value_or(0.0));
    put_duffing(w, s.duffing);
    put_indices(w, s.fixed);
    w.f64(s.mass_scaling_dt);                      // version 4
    w.f64(s.compression);                          // version 6
    w.i64(static_cast<std::int64_t>(s.thin_tet));  // version 7
    w.f64(s.thin_tet_q_max);
    w.f64(s.surface_spring_scale);                         // version 8
    w.f64(s.overlay_compliance);                           // version 9
    w.i64(static_cast<std::int64_t>(s.volume_precision));  // version 10
  } else {
    throw InvalidInput(cat("model package '", p.name, "': unknown kind '", p.kind, "'"));
  }
  w.u64(p.fingerprint);
  return frame_payload(kModelPackageMagic, kModelPackageVersion, w.bytes());
}

ModelPackage decode_model_package(std::string_view bytes, const std::string& what) {
  std::uint32_t version = 0;
  const std::string_view payload = unframe_payload(bytes, kModelPackageMagic, kModelPackageMinVersion,
                                                   kModelPackageVersion, kKind, what, &version);
  ByteReader r(payload, what, kKind);
  ModelPackage p;
  p.name = r.str("name", kMaxText);
  p.description = r.str("description", kMaxText);
  p.kind = r.str("kind");
  if (p.kind != "surface" && p.kind != "hybrid" && p.kind != "smrm" && p.kind != "smrm_tree" &&
      p.kind != "volumetric")
    r.fail(cat("kind: '", p.kind, "' (expected surface, hybrid, smrm, smrm_tree or volumetric)"));
  p.surface.V = get_points(r, "surface vertices");
  const Index nv = static_cast<Index>(p.surface.V.rows());
  const Index nf = r.count("surface faces", 3 * 8);
  p.surface.F.resize(nf, 3);
  for (Index f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      const std::int64_t i = r.i64();
      if (i < 0 || i >= nv) r.fail(cat("face ", f, ": vertex ", i, " out of range [0, ", nv, ")"));
      p.surface.F(f, c) = static_cast<Index>(i);
    }
  const std::int64_t rings = r.i64(), spokes = r.i64();
  if (rings < 0 || spokes < 0 || rings > nv || spokes > nv)
    r.fail(cat("grid ", rings, " x ", spokes, " for ", nv, " vertices"));
  p.grid = GridLayout{static_cast<Index>(rings), static_cast<Index>(spokes)};
  if (p.kind == "surface") {
    SurfaceBodyParams& s = p.surface_params;
    if (version >= 5) {
      get_params(r, s, "surface parameters");
      check_indices(r, s.fixed, "fixed", nv);
    } else {  // versions 1 to 4: the fields in a fixed order
      s.node = get_node(r);
      s.k = r.f64();
      s.duffing = get_duffing(r);
      s.fixed = get_indices(r, "fixed", nv);
    }
  } else if (p.kind == "hybrid") {
    HybridSettings& h = p.hybrid;
    p.atoms = get_points(r, "atoms");
    if (version >= 3) {
      h.nonlinear = r.flag("nonlinear");
      get_params(r, h, "hybrid settings");
      if (h.spokes_per_atom < 0 || h.spokes_per_atom > nv)
        r.fail(cat("spokes_per_atom: ", h.spokes_per_atom, " out of range [0, ", nv, "]"));
      check_indices(r, h.fixed, "fixed", nv);
    } else {  // versions 1 and 2: the fields in a fixed order
      h.surface_node = get_node(r);
      h.atom_node = get_node(r);
      h.k_surf = r.f64();
      h.k_spoke = r.f64();
      h.k_cl = r.f64();
      h.nonlinear = r.flag("nonlinear");
      h.duffing = get_duffing(r);
      const std::int64_t k = r.i64();
      if (k < 0 || k > nv) r.fail(cat("spokes_per_atom: ", k, " out of range [0, ", nv, "]"));
      h.spokes_per_atom = static_cast<Index>(k);
      h.fixed = get_indices(r, "fixed", nv);
    }
  } else if (p.kind == "smrm") {
    p.atoms = get_points(r, "atoms");
    const Index na = static_cast<Index>(p.atoms.rows());
    p.atom_radius = get_doubles(r, "atom radius");
    if (p.atom_radius.size() != 0 && p.atom_radius.size() != na)
      r.fail(cat("atom radius: ", p.atom_radius.size(), " values for ", na, " atoms"));
    SurfaceBinding& b = p.binding;
    const std::int64_t bn = r.i64();
    if (bn != na) r.fail(cat("binding: for ", bn, " atoms, the package has ", na));
    b.num_atoms = na;
    b.atom = get_indices(r, "binding atom", na);
    const Index nl = r.count("binding lambda", sizeof(double));
    b.lambda.resize(static_cast<std::size_t>(nl));
    for (double& l : b.lambda) l = r.f64();
    b.offset = get_points(r, "binding offsets");
    const Index m = b.size();
    if (m != nv || b.offset.rows() != m || (nl != 0 && nl != m))
      r.fail(cat("binding: ", m, " nodes, ", b.offset.rows(), " offsets, ", nl, " bracket parameters for ",
                 nv, " surface vertices"));
    get_smrm_settings(r, p.smrm, version);
  } else if (p.kind == "volumetric") {
    VolumetricMesh& m = p.volumetric_mesh;
    m.X = get_points(r, "volumetric nodes");
    const Index nn = static_cast<Index>(m.X.rows());
    const std::int64_t ns = r.i64();
    if (ns != nv || ns > nn)
      r.fail(cat("volumetric: ", ns, " surface nodes for ", nv, " surface vertices and ", nn, " nodes"));
    m.surface_nodes = static_cast<Index>(ns);
    const Index nt = r.count("tetrahedra", 4 * 8);
    m.T.resize(nt, 4);
    for (Index t = 0; t < nt; ++t)
      for (int c = 0; c < 4; ++c) {
        const std::int64_t i = r.i64();
        if (i < 0 || i >= nn) r.fail(cat("tetrahedron ", t, ": node ", i, " out of range [0, ", nn, ")"));
        m.T(t, c) = static_cast<Index>(i);
      }
    VolumetricSettings& s = p.volumetric;
    for (double* v :
         {&s.E_kPa, &s.nu, &s.density, &s.beta, &s.spring_scale, &s.volume_scale, &s.min_mass_fraction})
      *v = r.f64();
    const bool has_kr = r.flag("return_k");
    const double kr = r.f64();
    if (has_kr) s.return_k = kr;
    s.duffing = get_duffing(r);
    s.fixed = get_indices(r, "fixed", nv);
    s.mass_scaling_dt = version >= 4 ? r.f64() : 0.0;  // earlier packages were built without it
    s.compression = version >= 6 ? r.f64() : 0.0;      // nor without compression stiffening
    if (version >= 7) {                                // thin-tetrahedron terms (off before)
      const std::int64_t mode = r.i64();
      if (mode < 0 || mode > 2) r.fail(cat("volumetric thin_tet: mode ", mode, " (expected 0, 1 or 2)"));
      s.thin_tet = static_cast<ThinTetMode>(mode);
      s.thin_tet_q_max = r.f64();
    }
    // the surface-layer family (none before version 8)
    s.surface_spring_scale = version >= 8 ? r.f64() : 1.0;
    // the overlay's compliance multiplier (before version 9: the overlay as it was, a = 1)
    s.overlay_compliance = version >= 9 ? r.f64() : 1.0;
    // the sub-steps' volume pass: stored from version 10; earlier packages were written while double was
    // the default (and a float model's package did not say so): they read double, as they were run
    s.volume_precision = VolumePrecision::Double;
    if (version >= 10) {
      const std::int64_t prec = r.i64();
      if (prec < 0 || prec > 1)
        r.fail(cat("volumetric volume_precision: ", prec, " (expected 0 double or 1 float)"));
      s.volume_precision = static_cast<VolumePrecision>(prec);
    }
  } else {  // smrm_tree
    const Index nb = r.count("tree branches", 4 + 8 + 8 + 8);
    p.tree.branches.resize(static_cast<std::size_t>(nb));
    for (Index b = 0; b < nb; ++b) {
      CenterlineTree::Branch& br = p.tree.branches[static_cast<std::size_t>(b)];
      br.line.name = r.str("branch name", kMaxText);
      const std::int64_t parent = r.i64();
      if (b == 0 ? parent != -1 : (parent < 0 || parent >= b))
        r.fail(cat("tree branch ", b, ": parent ", parent,
                   (b == 0 ? " (the root's is -1)" : " out of range [0, "),
                   (b == 0 ? std::string() : cat(b, ")"))));
      br.parent = static_cast<Index>(parent);
      br.line.points = get_points(r, "tree branch points");
      br.line.radii = get_doubles(r, "tree branch radii");
      if (br.line.radii.size() != br.line.points.rows())
        r.fail(cat("tree branch ", b, ": ", br.line.radii.size(), " radii for ", br.line.points.rows(),
                   " points"));
    }
    get_smrm_settings(r, p.smrm, version);
  }
  p.fingerprint = r.u64();
  r.finish();
  return p;
}

void save_model_package(const std::filesystem::path& path, const ModelPackage& package) {
  write_file_atomically(path, encode_model_package(package), kKind);
}

ModelPackage read_model_package(const std::filesystem::path& path) {
  return decode_model_package(read_file_bytes(path, kKind), path.string());
}

bool check_fingerprint(const ModelPackage& package, const Body& rebuilt) {
  return package.fingerprint == 0 || package.fingerprint == model_fingerprint(rebuilt.model());
}

TissueParams tissue_params(const ModelPackage& p) {
  TissueParams t;
  if (p.kind == "surface") {
    const SurfaceBodyParams& s = p.surface_params;
    t = {s.k, s.duffing.eta, s.node.return_k, s.node.beta, s.duffing.mode != DuffingMode::Linear};
  } else if (p.kind == "hybrid") {
    const HybridSettings& h = p.hybrid;
    t = {h.k_surf, h.duffing.eta, h.surface_node.return_k, h.surface_node.beta, h.nonlinear};
  } else if (p.kind == "volumetric") {  // k: Young's modulus in N/mm^2 (the springs and volume terms follow)
    const VolumetricSettings& s = p.volumetric;
    t = {s.E_kPa * 1e-3, s.duffing.eta, s.return_k.value_or(0.0), s.beta,
         s.duffing.mode != DuffingMode::Linear};
  } else {
    const ChainSettings& c = p.smrm.chain;
    t = {c.k, c.duffing.eta, c.kr, c.beta, c.nonlinear};
  }
  return t;
}

void set_tissue_params(ModelPackage& p, const TissueParams& t) {
  const std::string w = cat("model package '", p.name, "': tissue parameter ");
  require_positive(t.k, w, "k");
  require_nonnegative(t.eta, w, "eta");
  require_nonnegative(t.kr, w, "kr");
  require_nonnegative(t.beta, w, "beta");
  if (p.kind == "surface") {
    SurfaceBodyParams& s = p.surface_params;
    s.k = t.k;
    s.duffing.eta = t.eta;
    if (!t.nonlinear)
      s.duffing.mode = DuffingMode::Linear;
    else if (s.duffing.mode == DuffingMode::Linear)
      s.duffing.mode = DuffingMode::Strain;
    s.node.return_k = t.kr;
    s.node.beta = t.beta;
  } else if (p.kind == "hybrid") {
    HybridSettings& h = p.hybrid;
    const double ratio = t.k / h.k_surf;  // spokes and centerline keep their ratio to the surface springs
    h.k_surf = t.k;
    h.k_spoke *= ratio;
    h.k_cl *= ratio;
    h.duffing.eta = t.eta;
    h.nonlinear = t.nonlinear;
    if (t.nonlinear && h.duffing.mode == DuffingMode::Linear) h.duffing.mode = DuffingMode::Strain;
    h.surface_node.return_k = h.atom_node.return_k = t.kr;
    h.surface_node.beta = h.atom_node.beta = t.beta;
  } else if (p.kind == "volumetric") {
    VolumetricSettings& s = p.volumetric;
    s.E_kPa = t.k * 1e3;
    s.duffing.eta = t.eta;
    if (!t.nonlinear)
      s.duffing.mode = DuffingMode::Linear;
    else if (s.duffing.mode == DuffingMode::Linear)
      s.duffing.mode = DuffingMode::Strain;
    s.return_k = t.kr;
    s.beta = t.beta;
  } else if (p.kind == "smrm" || p.kind == "smrm_tree") {
    ChainSettings& c = p.smrm.chain;
    c.k = t.k;
    c.duffing.eta = t.eta;
    c.nonlinear = t.nonlinear;
    if (t.nonlinear && c.duffing.mode == DuffingMode::Linear) c.duffing.mode = DuffingMode::Strain;
    c.kr = t.kr;
    c.beta = t.beta;
  } else {
    throw InvalidInput(cat("model package '", p.name, "': unknown kind '", p.kind, "'"));
  }
  p.fingerprint = 0;  // the package no longer describes the model it was saved from
}

}  // namespace medspring
