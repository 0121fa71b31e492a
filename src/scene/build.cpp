// Building the model of a scene and resolving its loads (scene/build.hpp).
#include "medspring/scene/build.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "medspring/core/check.hpp"
#include "medspring/core/memory.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_tree.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/skeleton/centerline_extraction.hpp"
#include "medspring/skeleton/centerline_tree.hpp"
#include "medspring/skeleton/voxelize.hpp"

namespace medspring {

namespace fs = std::filesystem;

VolumetricMesh SceneLoader::tetrahedralize(const SurfaceMesh&, Index, MeshSizing) {
  throw InvalidInput(
      "a volumetric model needs a tetrahedral mesher (TetGen): the loader of the medspring command or of the "
      "Python module");
}

SurfaceMesh SceneLoader::tree_surface(const CenterlineTree&, const SmrmTree&, double,
                                      std::vector<std::string>&) {
  throw InvalidInput(
      "a blended (watertight) vessel tree surface needs CGAL (the builders layer): the loader of the "
      "medspring "
      "command or of the Python module");
}

std::shared_ptr<const SmrmTree> SceneLoader::organ_tree(const OrganTreeRequest&, std::vector<std::string>&) {
  throw InvalidInput(
      "a vessel tree from a mesh or a segmentation needs the builders layer (CGAL, build_vessel): the loader "
      "of the medspring command or of the Python module");
}

namespace {

struct Builder {
  const Scene& scene;
  SceneLoader* loader;
  std::string origin;
  BuiltScene out;
  Index num_atoms = 0;
  MatX3 atoms_rest;
  std::shared_ptr<const SmrmVessel> vessel;  // set for an smrm model
  std::shared_ptr<const SmrmTree> tree;      // set for an smrm vessel tree ("branches": "all")

  [[noreturn]] void fail(const std::string& path, const std::string& message) const {
    throw InvalidInput(cat(origin, ": ", path, ": ", message));
  }

  SceneLoader& files(const std::string& path) {
    if (loader == nullptr) fail(path, "a file source needs the file loader of the medspring command");
    return *loader;
  }

  // An organ is 5..1000 mm across: anything else is almost surely a wrong unit.
  void check_size(double size_mm, const std::string& path, LengthUnit unit, const std::string& what) const {
    if (!(size_mm >= 5.0 && size_mm <= 1000.0))
      fail(path, cat("the ", what, " is ", size_mm, " mm across when read in '", to_string(unit),
                     "': wrong unit? (an organ is 5-1000 mm across)"));
  }

  SurfaceMesh read_organ_mesh() {
    const ModelSource& s = scene.model.source;
    SurfaceMesh mesh = files("model.source.mesh").read_mesh(s.mesh, s.mesh_unit);
    const MeshReport r = validate_mesh(mesh);
    check_size(r.bbox_diagonal, "model.source.mesh.unit", s.mesh_unit,
               cat("mesh ", s.mesh.filename().string()));
    if (!r.valid() || !r.closed())
      fail("model.source.mesh.file",
           cat(s.mesh.filename().string(), " is not a closed valid surface (", r.summary(),
               r.first_problem.empty() ? "" : "; " + r.first_problem, ")"));
    out.notes.push_back(cat("read ", s.mesh.filename().string(), ": ", r.summary()));
    return mesh;
  }

  SurfaceMesh maybe_balloon(const SurfaceMesh& organ) {
    const Index n = scene.model.surface_nodes;
    if (n <= 0) return organ;
    std::vector<std::string> notes;
    SurfaceMesh m = files("model.surface_nodes").balloon(organ, n, notes);
    for (auto& s : notes) out.notes.push_back("balloon: " + s);
    return m;
  }

  MatX3 skeleton_atoms(const SkeletonResult& sk) {
    out.notes.push_back(cat("skeleton: ", sk.atoms.rows(), " atoms over ", sk.component_voxels,
                            " voxels (h = ", sk.h_min, " mm), radii ", sk.radii.minCoeff(), "-",
                            sk.radii.maxCoeff(), " mm"));
    for (const auto& note : sk.notes) out.notes.push_back("skeleton: " + note);
    return sk.atoms;
  }

  Centerline read_branch() {
    const ModelSource& s = scene.model.source;
    std::vector<Centerline> lines =
        files("model.source.centerline").read_centerlines(s.centerline, s.centerline_unit, s.radius_array);
    const Index n = static_cast<Index>(lines.size());
    if (s.branch >= n)
      fail("model.source.centerline.branch",
           cat("index ", s.branch, " out of range [0, ", n, ") (", s.centerline.filename().string(), " has ",
               n, " polyline", n == 1 ? "" : "s", ")"));
    Centerline line = lines[static_cast<std::size_t>(s.branch)];
    const double length = line.length();
    check_size(length, "model.source.centerline.unit", s.centerline_unit,
               cat("branch ", s.branch, " of ", s.centerline.filename().string()));
    if (s.range_start > 0 || std::isfinite(s.range_end)) {
      if (s.range_start >= length)
        fail("model.source.centerline.range_mm",
             cat("starts at ", s.range_start, " mm, beyond the end of branch ", s.branch, " (", length,
                 " mm)"));
      line = cut(line, s.range_start, std::min(s.range_end, length));
    }
    out.notes.push_back(cat("centerline: branch ", s.branch, " of ", s.centerline.filename().string(), ", ",
                            line.length(), " mm of ", length, " mm, radius ", line.radii.minCoeff(), "-",
                            line.radii.maxCoeff(), " mm"));
    return line;
  }

  // The part of a polyline between arc lengths a < b (end points interpolated).
  static Centerline cut(const Centerline& line, double a, double b) {
    const VecX s = line.arc_length();
    std::vector<Vec3> P;
    std::vector<double> R;
    auto at = [&](double q) {
      Index i = 0;
      while (i + 2 < line.size() && s[i + 1] < q) ++i;
      const double len = s[i + 1] - s[i];
      const double t = len > 0 ? std::clamp((q - s[i]) / len, 0.0, 1.0) : 0.0;
      P.push_back((1 - t) * line.points.row(i).transpose() + t * line.points.row(i + 1).transpose());
      R.push_back((1 - t) * line.radii[i] + t * line.radii[i + 1]);
    };
    at(a);
    for (Index i = 0; i < line.size(); ++i)
      if (s[i] > a + 1e-9 && s[i] < b - 1e-9) {
        P.push_back(line.points.row(i).transpose());
        R.push_back(line.radii[i]);
      }
    at(b);
    Centerline c;
    c.name = line.name;
    c.points.resize(static_cast<Index>(P.size()), 3);
    c.radii.resize(static_cast<Index>(P.size()));
    for (std::size_t k = 0; k < P.size(); ++k) {
      c.points.row(static_cast<Index>(k)) = P[k].transpose();
      c.radii[static_cast<Index>(k)] = R[k];
    }
    return c;
  }

  MaskVolume read_mask() {
    const ModelSource& s = scene.model.source;
    const LabelVolume labels = files("model.source.segmentation").read_label_volume(s.segmentation);
    MaskVolume mask = select_label(labels, s.label);
    Index count = 0;
    for (auto v : mask.data) count += v != 0;
    if (count == 0)
      fail("model.source.segmentation.label",
           cat("no voxel of ", s.segmentation.filename().string(), " has label ", s.label));
    out.notes.push_back(
        cat("segmentation ", s.segmentation.filename().string(), ": ", count, " voxels of label ", s.label));
    return mask;
  }

  BodyPtr surface_body(const SurfaceMesh& mesh, const std::string& name, GridLayout grid = {}) {
    return std::make_shared<SurfaceBody>(mesh, scene.model.surface, name, grid);
  }

  BodyPtr hybrid_body(const SurfaceMesh& surface, const MatX3& atoms, const std::string& name,
                      const MaskVolume* mask = nullptr) {
    auto h = std::make_shared<HybridKidney>(surface, atoms, scene.model.hybrid, name, mask);
    const HybridStats st = h->stats();
    if (st.visibility_filtered)
      out.notes.push_back(
          cat("spokes: visibility filter (D-9) on the organ's voxels: ", st.visibility.rejected,
              " candidates leaving the organ rejected, ", st.visibility.fallbacks,
              " surface nodes without a visible atom kept on their nearest"));
    out.notes.push_back(cat("hybrid: ", st.surface_nodes, " surface nodes + ", st.atoms, " atoms, ",
                            st.surface_springs, " surface springs, ", st.centerline_springs,
                            " centerline springs, ", st.spokes, " spokes (", st.min_spokes_per_atom, "-",
                            st.max_spokes_per_atom, " per atom)"));
    num_atoms = h->num_atoms();
    atoms_rest = h->model().x0.bottomRows(num_atoms);
    return h;
  }

  // The volumetric organ (issue 23): the loader's TetGen mesh of the surface, constants from E and nu.
  BodyPtr volumetric_body(const SurfaceMesh& surface, const std::string& name) {
    if (loader == nullptr)
      fail("model.kind", "a volumetric model needs the tetrahedral mesher (TetGen) of the medspring command");
    const SceneModel& m = scene.model;
    std::shared_ptr<VolumetricBody> b;
    try {
      b = std::make_shared<VolumetricBody>(
          loader->tetrahedralize(surface, m.volumetric.mesh_nodes, m.volumetric.mesh_sizing), m.volumetric,
          name);
    } catch (const InvalidInput& e) {
      fail("model", e.what());
    }
    const VolumetricStats& st = b->stats();
    out.notes.push_back(cat("volumetric: ", st.nodes, " nodes (", st.surface_nodes, " on the surface), ",
                            st.tetrahedra, " tetrahedra (interior sizing ",
                            to_string(m.volumetric.mesh_sizing), "), ", st.springs,
                            " springs; E = ", m.volumetric.E_kPa, " kPa, nu = ", m.volumetric.nu,
                            ", return springs ", b->model().kr.maxCoeff() > 0 ? "on" : "off (supports)"));
    if (st.thin_tets > 0)  // opt-in thin-tetrahedron terms (docs/volumetric-mesh.md)
      out.notes.push_back(cat("volumetric: thin-tetrahedron terms (", to_string(m.volumetric.thin_tet),
                              ") on ", st.thin_tets, " tetrahedra, their springs x ", st.thin_spring_factor));
    for (const std::string& w : b->warnings()) out.notes.push_back(w);
    return b;
  }

  BodyPtr smrm_body(SmrmVessel v) {
    auto p = std::make_shared<SmrmVessel>(std::move(v));
    out.notes.push_back(cat("smrm: ", p->num_atoms(), " atoms, ", p->num_surface_nodes(), " surface nodes"));
    for (const auto& note : p->report().notes) out.notes.push_back("smrm: " + note);
    num_atoms = p->num_atoms();
    atoms_rest = p->rest_atoms();
    vessel = p;
    return p;
  }

  // A vessel tree from a mesh or a segmentation: the loader builds it as `medspring build vessel
  // --branches all` does (builders' build_vessel; holes filled, skeleton re-centred, surface fitted).
  BodyPtr tree_from_organ(const std::string& where) {
    const ModelSource& s = scene.model.source;
    OrganTreeRequest r;
    if (s.type == ModelSource::Type::Mesh) {
      r.mesh = s.mesh;
      r.mesh_unit = s.mesh_unit;
    } else {
      r.segmentation = s.segmentation;
      r.label = s.label;
    }
    r.smrm = scene.model.smrm;
    r.blend = s.blend;
    r.blend_spacing = s.blend_spacing;
    std::vector<std::string> notes;
    std::shared_ptr<const SmrmTree> t;
    try {
      t = files(where).organ_tree(r, notes);
    } catch (const InvalidInput& e) {
      fail(where, e.what());
    }
    for (const std::string& n : notes) out.notes.push_back("vessel tree: " + n);
    return adopt_tree(std::move(t), "the skeleton of " + (s.type == ModelSource::Type::Mesh
                                                              ? s.mesh.filename().string()
                                                              : s.segmentation.filename().string()));
  }

  BodyPtr tree_body() {
    const ModelSource& s = scene.model.source;
    return tree_body(
        files("model.source.centerline").read_centerlines(s.centerline, s.centerline_unit, s.radius_array),
        0.05);
  }

  BodyPtr tree_body(const std::vector<Centerline>& lines, double tolerance) {
    const ModelSource& s = scene.model.source;
    const CenterlineTree ct = merge_centerlines(lines, tolerance);
    auto t = std::make_shared<SmrmTree>(ct, SmrmTreeSettings{scene.model.smrm});
    if (s.blend) {  // one watertight surface: the union of the closed path tubes (CGAL, in the loader)
      std::vector<std::string> notes;
      SurfaceMesh u;
      try {
        u = files("model.source.centerline.blend").tree_surface(ct, *t, s.blend_spacing, notes);
      } catch (const InvalidInput& e) {
        fail("model.source.centerline.blend", e.what());
      }
      t = std::make_shared<SmrmTree>(ct, SmrmTreeSettings{scene.model.smrm}, u);
      for (const std::string& n : notes) out.notes.push_back("smrm tree surface: " + n);
    }
    return adopt_tree(std::move(t), cat(lines.size(), " polylines"));
  }

  BodyPtr adopt_tree(std::shared_ptr<const SmrmTree> t, const std::string& from) {
    out.notes.push_back(cat("smrm tree: ", from, " -> ", t->num_branches(), " branches, ", t->num_junctions(),
                            " junctions, ", t->num_atoms(), " atoms, ", t->num_surface_nodes(),
                            " surface nodes (",
                            t->blended() ? "one watertight surface" : "one tube per branch", ")"));
    num_atoms = t->num_atoms();
    atoms_rest = t->model().x0;
    tree = t;
    return t;
  }

  BodyPtr build_body() {
    const SceneModel& m = scene.model;
    const ModelSource& s = m.source;
    const std::string name = scene.name.empty() ? "model" : scene.name;
    switch (s.type) {
      case ModelSource::Type::Phantom:
        if (s.phantom == "kidney") {
          if (m.kind == ModelKind::Surface) return surface_body(kidney_phantom(), "kidney phantom");
          if (m.kind == ModelKind::Volumetric) return volumetric_body(kidney_phantom(), "kidney phantom");
          return hybrid_body(kidney_phantom(), kidney_phantom_atoms(m.atoms), "kidney phantom");
        }
        if (s.phantom == "tube") {
          const double nodes = static_cast<double>(s.rings) * static_cast<double>(s.spokes);
          require_index_count(2.0 * nodes, cat("tube: ", s.rings, " x ", s.spokes, " nodes: the face count"));
          require_memory(kModelBuildBytesPerNode * nodes, cat("tube: a model of ", nodes, " nodes"));
          return surface_body(tube(s.rings, s.spokes, s.spacing, s.radius), "tube",
                              GridLayout{s.rings, s.spokes});
        }
        return smrm_body(smrm_phantom(s.path, s.cross_section, m.smrm));
      case ModelSource::Type::Mesh: {
        if (m.kind == ModelKind::Smrm && s.all_branches)  // a tree: as `medspring build vessel` builds it
          return tree_from_organ("model.source.mesh");
        const SurfaceMesh organ = read_organ_mesh();
        if (m.kind == ModelKind::Surface) return surface_body(maybe_balloon(organ), name);
        if (m.kind == ModelKind::Volumetric) return volumetric_body(maybe_balloon(organ), name);
        SkeletonSettings sk;
        sk.atom_count = m.atoms;
        const MeshCenterline mc = centerline_from_mesh(organ, sk);
        if (m.kind == ModelKind::Hybrid) {
          const MatX3 atoms = skeleton_atoms(mc.skeleton);
          return hybrid_body(maybe_balloon(organ), atoms, name, &mc.mask);
        }
        skeleton_atoms(mc.skeleton);
        return smrm_body(smrm_from_marched_spokes(mc.skeleton.centerline(), organ, m.smrm));
      }
      case ModelSource::Type::Segmentation: {
        if (m.kind == ModelKind::Smrm && s.all_branches)  // a tree: as `medspring build vessel` builds it
          return tree_from_organ("model.source.segmentation");
        const MaskVolume mask = read_mask();
        SkeletonSettings sk;
        sk.atom_count = m.atoms > 0 ? m.atoms : 40;
        if (m.kind == ModelKind::Smrm) {
          const SkeletonResult r = extract_centerline(mask, sk);
          skeleton_atoms(r);
          return smrm_body(smrm_from_centerline(r.centerline(), m.smrm));
        }
        const SurfaceMesh organ = files("model.source.segmentation").isosurface(mask);
        out.notes.push_back(cat("isosurface: ", organ.num_vertices(), " vertices"));
        if (m.kind == ModelKind::Surface) return surface_body(maybe_balloon(organ), name);
        if (m.kind == ModelKind::Volumetric) return volumetric_body(maybe_balloon(organ), name);
        const MatX3 atoms = skeleton_atoms(extract_centerline(mask, sk));
        return hybrid_body(maybe_balloon(organ), atoms, name, &mask);
      }
      case ModelSource::Type::Centerline: {
        if (s.all_branches) {
          if (!s.mesh.empty()) fail("model.source.centerline.branches", "a tree takes no mesh (yet)");
          if (s.range_start > 0 || std::isfinite(s.range_end))
            fail("model.source.centerline.range_mm", "applies to one branch, not to \"branches\": \"all\"");
          return tree_body();
        }
        const Centerline line = read_branch();
        if (!s.mesh.empty()) {
          SurfaceMesh boundary = files("model.source.mesh").read_mesh(s.mesh, s.mesh_unit);
          check_size(validate_mesh(boundary).bbox_diagonal, "model.source.mesh.unit", s.mesh_unit,
                     cat("mesh ", s.mesh.filename().string()));
          return smrm_body(smrm_from_marched_spokes(line, boundary, m.smrm));
        }
        return smrm_body(smrm_from_centerline(line, m.smrm));
      }
    }
    fail("model.source", "unknown source");
  }

  void resolve_loads() {
    const Body& body = *out.body;
    const Index S = body.num_surface_nodes();
    const MatX3& X0 = body.rest_surface();
    MatX3 N;
    vertex_normals(X0, body.faces(), N);
    const GridLayout grid = body.grid();
    for (const SceneLoad& L : scene.loads) {
      Index node = 0;
      switch (L.pick) {
        case SceneLoad::Pick::Node:
          if (L.node < 0 || L.node >= S)
            fail(L.where + ".node",
                 cat("index ", L.node, " out of range [0, ", S, ") (the model has ", S, " surface nodes)"));
          node = L.node;
          break;
        case SceneLoad::Pick::Point:
          node = nearest_node(X0, L.point);
          out.notes.push_back(cat(L.where, ".point picks surface node ", node, " at ",
                                  (X0.row(node).transpose() - L.point).norm(), " mm"));
          break;
        case SceneLoad::Pick::RingSpoke:
          if (!grid.valid())
            fail(L.where + ".ring", "the model has no ring/spoke grid (only tube and smrm models have one)");
          if (L.ring < 0 || L.ring >= grid.rings)
            fail(L.where + ".ring", cat("index ", L.ring, " out of range [0, ", grid.rings, ")"));
          if (L.spoke < 0 || L.spoke >= grid.spokes)
            fail(L.where + ".spoke", cat("index ", L.spoke, " out of range [0, ", grid.spokes, ")"));
          node = L.ring * grid.spokes + L.spoke;
          break;
      }
      Vec3 d = Vec3::Zero();
      switch (L.direction) {
        case SceneLoad::Direction::Vector:
          d = L.vector;
          break;
        case SceneLoad::Direction::InwardNormal:
          d = -N.row(node).transpose();
          break;
        case SceneLoad::Direction::TowardsAtom: {
          if (num_atoms == 0)
            fail(L.where + ".direction", "towards_atom needs a model with atoms (hybrid or smrm)");
          Index a = L.target_atom;
          if (a < 0)  // smrm: the node's own atom
            a = vessel ? vessel->node_atom(node) : tree ? tree->node_atom(node) : num_atoms / 2;
          if (a >= num_atoms) fail(L.where + ".atom", cat("index ", a, " out of range [0, ", num_atoms, ")"));
          d = atoms_rest.row(a).transpose() - X0.row(node).transpose();
          break;
        }
      }
      if (!(d.norm() > 1e-12)) fail(L.where + ".direction", cat("is undefined at surface node ", node));
      d.normalize();
      PointLoad p;
      p.node = node;
      p.force = L.magnitude * d;
      p.t_on = L.t_on;
      p.t_ramp = L.t_ramp;
      p.t_release = L.t_release;
      p.ramp_down = L.ramp_down;
      out.loads.push_back(p);
      if (std::find(out.trace_nodes.begin(), out.trace_nodes.end(), node) == out.trace_nodes.end())
        out.trace_nodes.push_back(node);
    }
    for (std::size_t k = 0; k < scene.record.nodes.size(); ++k) {
      const Index n = scene.record.nodes[k];
      if (n >= S)
        fail(cat("record.nodes[", k, "]"), cat("index ", n, " out of range [0, ", S, ") (surface nodes)"));
      if (std::find(out.trace_nodes.begin(), out.trace_nodes.end(), n) == out.trace_nodes.end())
        out.trace_nodes.push_back(n);
    }
    for (std::size_t k = 0; k < scene.record.atoms.size(); ++k) {
      const Index a = scene.record.atoms[k];
      if (a >= num_atoms)
        fail(cat("record.atoms[", k, "]"), cat("index ", a, " out of range [0, ", num_atoms, ")"));
      out.trace_atoms.push_back(a);
      out.trace_atom_dofs.push_back(vessel || tree ? a : S + a);
    }
  }

  void settings() {
    const Model& model = out.body->model();
    const StepSettings& st = scene.step;
    out.dt_safe_rest = model.dt_safe_rest(st.safety);
    if (st.integrator == Integrator::LinearStatic && !scene.tools.empty())
      fail("integrator.method",
           "linear_static takes point loads, not tools: the penalty contact needs a dynamic integrator "
           "(symplectic_euler or implicit_euler)");
    if (!st.substep && st.integrator == Integrator::SymplecticEuler && st.dt > out.dt_safe_rest)
      fail("integrator.dt",
           cat(st.dt, " ms is above the stable step ", out.dt_safe_rest,
               " ms of this model (integrator.substep is false: set it to true or use a smaller dt)"));
    try {
      validate_step_settings(model, st);
    } catch (const InvalidInput& e) {
      fail("integrator", e.what());
    }
    out.settings.step = st;
    out.settings.local = scene.local;
    out.settings.local.use_body_stiffness = scene.local_k_from_body;
    out.settings.normals = true;
  }
};

}  // namespace

namespace {

// Everything after the model exists: settings, loads, the probe, notes and timing.
BuiltScene finish_build(Builder& b, std::chrono::steady_clock::time_point t0) {
  const Scene& scene = b.scene;
  b.settings();
  b.resolve_loads();
  b.out.atoms_rest = b.atoms_rest;
  if (b.num_atoms > 0) b.out.atom_dof_begin = b.vessel || b.tree ? 0 : b.out.body->num_surface_nodes();
  // Everything Simulation checks (loads, local patches) is checked now, before anything is written.
  try {
    Simulation probe(b.out.body, b.out.settings);
    probe.set_loads(b.out.loads);
  } catch (const Error& e) {
    b.fail("loads", e.what());
  }
  const Model& m = b.out.body->model();
  b.out.notes.push_back(cat("model '", m.name, "': ", m.num_nodes(), " masses, ", m.num_springs(),
                            " springs; stable step at rest ", b.out.dt_safe_rest, " ms, dt ", scene.step.dt,
                            " ms"));
  b.out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return std::move(b.out);
}

}  // namespace

BuiltScene build_scene(const Scene& scene, SceneLoader* loader) {
  const auto t0 = std::chrono::steady_clock::now();
  Builder b{scene, loader, scene.file.empty() ? "scene" : scene.file.string(), {}, 0, {}, nullptr, nullptr};
  b.out.scene = scene;
  try {
    b.out.body = b.build_body();
  } catch (const InvalidInput& e) {
    const std::string what = e.what();
    if (what.rfind(b.origin + ":", 0) == 0) throw;
    b.fail("model", what);
  }
  return finish_build(b, t0);
}

BuiltScene build_scene_reusing(const Scene& scene, const BuiltScene& prior) {
  const auto t0 = std::chrono::steady_clock::now();
  require(prior.body != nullptr, "build_scene_reusing: the prior scene has no model");
  Builder b{scene, nullptr, scene.file.empty() ? "scene" : scene.file.string(), {}, 0, {}, nullptr, nullptr};
  b.out.scene = scene;
  b.out.body = prior.body;
  b.num_atoms = static_cast<Index>(prior.atoms_rest.rows());
  b.atoms_rest = prior.atoms_rest;
  b.vessel = std::dynamic_pointer_cast<const SmrmVessel>(prior.body);
  b.tree = std::dynamic_pointer_cast<const SmrmTree>(prior.body);
  b.out.notes.push_back(cat("model reused from an earlier build (", prior.build_seconds, " s)"));
  return finish_build(b, t0);
}

}  // namespace medspring
