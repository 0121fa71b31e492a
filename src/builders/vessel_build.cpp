#include "medspring/builders/vessel_build.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>

#include "medspring/builders/centerline_build.hpp"
#include "medspring/core/check.hpp"
#include "medspring/io/centerline_io.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/medial/reconstruction.hpp"
#include "medspring/meshing/mesh_repair.hpp"
#include "medspring/meshing/mesh_union.hpp"
#include "medspring/meshing/surface_distance.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/physics/stability.hpp"
#include "medspring/physics/state.hpp"
#include "medspring/skeleton/centerline_tree.hpp"
#include "medspring/skeleton/voxelize.hpp"
#include "vessel_tree_march.hpp"

namespace medspring {

namespace {

// The rebuilt rest surface against the input surface: Hausdorff and mean distance (both ways, sampled) and
// the rebuilt nodes' distance to the input (max, mean), into the summary.
void measure_distance_to_input(const SurfaceMesh& rebuilt, const SurfaceMesh& input, VesselSummary& s) {
  const SurfaceDistance d = surface_distance(rebuilt, input);
  s.has_distance = true;
  s.hausdorff_mm = d.hausdorff;
  s.mean_distance_mm = d.mean;
  const VecX dn = distances_to_surface(rebuilt.V, input);
  s.to_input_max_mm = dn.maxCoeff();
  s.to_input_mean_mm = dn.mean();
}

// The summary of a tree build (centerline input, every branch).
VesselBuild finish_tree(std::shared_ptr<SmrmTree> tree, VesselSummary s,
                        std::chrono::steady_clock::time_point t0) {
  VesselBuild out;
  const SmrmTree& t = *tree;
  s.atoms = t.num_atoms();
  s.branches = t.num_branches();
  s.junctions = t.num_junctions();
  s.surface_nodes = t.num_surface_nodes();
  s.faces = static_cast<Index>(t.faces().rows());
  s.spokes = t.branch_vessel(0).grid().spokes;
  s.radius_min_mm = std::numeric_limits<double>::infinity();
  s.radius_max_mm = 0.0;
  for (Index b = 0; b < t.num_branches(); ++b) {
    const SmrmVessel& v = t.branch_vessel(b);
    const MatX3& C = v.rest_atoms();
    for (Index i = 1; i < C.rows(); ++i) s.length_mm += (C.row(i) - C.row(i - 1)).norm();
    s.radius_min_mm = std::min(s.radius_min_mm, v.atom_radius().minCoeff());
    s.radius_max_mm = std::max(s.radius_max_mm, v.atom_radius().maxCoeff());
    s.max_rho_kappa = std::max(s.max_rho_kappa, v.report().curvature.max_rho_kappa);
    Centerline c;
    c.name = cat("branch ", b);
    c.points = C;
    c.radii = v.atom_radius();
    out.centerlines.push_back(std::move(c));
  }
  {
    State st = make_state(t.model());
    MatX3 S;
    t.map_to_surface(st, S);
    s.rest_error_mm = (S - t.rest_surface()).rowwise().norm().maxCoeff();
  }
  const VecX& kb = t.model().bending.kb;
  if (kb.size() > 0) {
    s.kb_min = kb.minCoeff();
    s.kb_max = kb.maxCoeff();
  }
  s.dt_safe_ms = dt_safe(t.model(), 1.0);
  if (t.blended()) {
    s.spokes = t.branch_vessel(0).settings().spokes;
    s.notes.push_back(cat(s.input_branches, " polylines merged into ", s.branches, " branches at ",
                          s.junctions,
                          " junctions (shared junction atoms); one watertight surface: the union "
                          "of ",
                          s.path_tubes, " closed path tubes"));
  } else {
    s.notes.push_back(
        cat(s.input_branches, " polylines merged into ", s.branches, " branches at ", s.junctions,
            " junctions (shared junction atoms); one tube per branch, not one watertight surface"));
  }
  out.tree = std::move(tree);
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.summary = std::move(s);
  return out;
}

// The blended tree (--blend) and its summary fields.
std::shared_ptr<SmrmTree> blended(const CenterlineTree& ct, const SmrmTreeSettings& ts, double spacing,
                                  VesselSummary& s) {
  TreeSurface r;
  auto tree = make_blended_tree(ct, ts, spacing, &r);
  s.blended = true;
  s.path_tubes = r.path_tubes;
  s.surface_closed = r.closed;
  s.surface_components = r.components;
  s.self_intersections = r.self_intersections;
  s.surface_volume_mm3 = r.volume_mm3;
  for (auto& n : r.notes) s.notes.push_back(std::move(n));
  for (auto& w : r.warnings) s.warnings.push_back(std::move(w));
  return tree;
}

// A tree from a closed surface mesh or a segmentation (--branches all): the tree skeleton of the mask
// (the voxelised mesh), merged into branches, and the rebuilt surface's distance to the input.
VesselBuild tree_from_organ(const VesselBuildSettings& st, std::chrono::steady_clock::time_point t0) {
  LoadedOrgan organ = load_organ(st.source, {.allow_open_tube = true});
  if (organ.from_mask && organ.components > 1)
    throw InvalidInput(cat(organ.name, ": label ", organ.label, " has ", organ.components,
                           " separate components (26-connected); a vessel tree must be one component (",
                           organ.notes.empty() ? std::string() : organ.notes.front(), ")"));
  VesselSummary s;
  s.input = organ.name;
  s.input_kind = organ.from_mask ? "mask" : "mesh";
  s.notes = organ.notes;
  s.warnings = organ.warnings;
  MaskVolume mask;
  if (organ.from_mask) {
    mask = organ.mask;
    Index holes = 0;  // enclosed holes: the skeleton would bend around them, the wall get an inner surface
    if (const Index filled = builders_detail::fill_enclosed_holes(mask, &holes); filled > 0) {
      organ.surface = isosurface(mask);
      s.notes.push_back(cat(organ.name, ": ", filled, " voxels in ", holes,
                            " enclosed hole(s) of the label filled (a vessel's lumen has none)"));
    }
  } else {
    SurfaceMesh closed = organ.surface;
    const std::vector<BoundaryCap> caps = close_boundary_loops(closed);  // open ends of a tube mesh
    if (!caps.empty())
      s.notes.push_back(cat(caps.size(), " open end(s) of the mesh capped for voxelisation"));
    // a tree is long and thin: the voxel size from the bounding box's volume (about 2 million voxels),
    // not from its smallest extent (the default would resolve a flat Y at 48 voxels across its depth)
    const Vec3 ext = (closed.V.colwise().maxCoeff() - closed.V.colwise().minCoeff()).transpose();
    VoxelizeSettings vset;
    vset.voxel_size = std::cbrt(std::max(ext.prod(), 1e-9) / 2e6);
    VoxelizeStats vs;
    mask = voxelize(closed, vset, &vs);
    s.notes.push_back(cat("voxelised at ", vs.voxel_size, " mm (", vs.inside_voxels, " voxels)"));
  }
  const TreeSkeleton sk = extract_centerline_tree(mask);
  for (const auto& n : sk.notes) s.notes.push_back("tree skeleton: " + n);
  s.input_branches = sk.endpoints;
  SmrmTreeSettings ts;
  ts.vessel = st.smrm;
  builders_detail::Recentring rc;
  const CenterlineTree ct = builders_detail::recentre_tree(
      merge_centerlines(sk.lines, std::max(st.merge_tolerance, 1e-3 * sk.h_min)), organ.surface, rc);
  s.notes.push_back(cat("tree skeleton re-centred in its cross-sections: ", rc.points, " of ", rc.total,
                        " points moved to their wall section's centroid, by ", rc.mean_shift_mm,
                        " mm on average (max ", rc.max_shift_mm, " mm); radii from there to the wall"));
  // the watertight surface marched to the wall is the default here (docs/vessels.md: the plain tubes are
  // open, a radius short of the input's caps, and circles); no_blend keeps the tubes
  const bool blend = !st.no_blend;
  std::shared_ptr<SmrmTree> tree =
      blend ? blended(ct, ts, st.blend_spacing, s) : std::make_shared<SmrmTree>(ct, ts);
  if (blend)
    if (auto marched = builders_detail::marched_tree(ct, ts, *tree, organ.surface, s))
      tree = std::move(marched);
  VesselBuild out = finish_tree(std::move(tree), s, t0);
  VesselSummary& r = out.summary;
  const SmrmTree& t = *out.tree;
  measure_distance_to_input(SurfaceMesh{t.rest_surface(), t.faces()}, organ.surface, r);
  std::vector<builders_detail::CutEnd> cuts{{0, false}};  // the root's start and every leaf's end
  for (Index b = 0; b < t.num_branches(); ++b) {
    bool leaf = true;
    for (Index c = 0; c < t.num_branches(); ++c) leaf = leaf && t.parent(c) != b;
    if (leaf) cuts.push_back({b, true});
  }
  builders_detail::measure_away_from_ends(SurfaceMesh{t.rest_surface(), t.faces()}, organ.surface,
                                          out.centerlines, cuts, r);
  out.input = std::move(organ.surface);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace

namespace {

// The path tubes at base ring spacing `spacing` (each path its first simple spacing of spacing x 1, 0.9,
// 1.1, ...) and their union.
TreeSurface path_tube_union(const CenterlineTree& ct, Index spokes, double spacing) {
  // Rings too far apart on a tight bend, or too close on a wavy wide stretch (neighbouring rings of a
  // 12 mm radius tilt into each other), make a tube cross itself: every path takes the first ring
  // spacing of spacing x (1, 0.9, 1.1, 0.8, 1.2, ...) that gives a simple tube.
  const std::vector<double> factors{1.0, 0.9, 1.1, 0.8, 1.2, 0.7, 1.3, 0.6, 1.4, 1.5};
  std::vector<SurfaceMesh> tubes;
  std::vector<double> used;
  for (double f : factors) {
    const std::vector<SurfaceMesh> cand = tree_path_tubes(ct, spokes, f * spacing);
    if (tubes.empty()) {
      tubes.resize(cand.size());
      used.assign(cand.size(), 0.0);
    }
    bool all = true;
    for (std::size_t q = 0; q < cand.size(); ++q) {
      if (used[q] > 0) continue;
      if (self_intersections(cand[q], "vessel tree tube") == 0) {
        tubes[q] = cand[q];
        used[q] = f * spacing;
      } else {
        all = false;
      }
    }
    if (all) break;
  }
  for (std::size_t q = 0; q < used.size(); ++q)
    require(used[q] > 0, "vessel tree surface: path tube ", q,
            " intersects itself at every ring spacing tried (", factors.back() * spacing, " to ",
            0.6 * spacing, " mm): a bend tighter than the vessel's radius");
  TreeSurface r;
  r.spacing_min_mm = *std::min_element(used.begin(), used.end());
  r.spacing_max_mm = *std::max_element(used.begin(), used.end());
  r.notes.push_back(cat("path tube ring spacing ", r.spacing_min_mm, "..", r.spacing_max_mm,
                        " mm (the first of ", spacing, " mm x 1, 0.9, 1.1, ... without self-intersection)"));
  r.path_tubes = static_cast<Index>(tubes.size());
  r.mesh = union_of_closed_meshes(tubes, "vessel tree surface");
  return r;
}

}  // namespace

TreeSurface blended_tree_surface(const CenterlineTree& ct, const SmrmTree& plain, double spacing_mm) {
  require(std::isfinite(spacing_mm) && spacing_mm >= 0,
          "vessel tree surface: blend spacing must be >= 0 mm (got ", spacing_mm, ")");
  const MatX3& C = plain.branch_vessel(0).rest_atoms();
  const double spacing = spacing_mm > 0 ? spacing_mm : (C.row(1) - C.row(0)).norm();
  const Index spokes = plain.settings().vessel.spokes;
  // A tube vertex that falls exactly on another tube's edge (a planar, mirror-symmetric tree, or a
  // coincidence) leaves zero-area triangles in CGAL's union: then the whole tree takes the next base
  // spacing of spacing x (1, 0.97, 1.03, 0.94, 1.06).
  const std::vector<double> bases{1.0, 0.97, 1.03, 0.94, 1.06};
  TreeSurface r;
  std::string first_error;
  for (double m : bases) {
    try {
      r = path_tube_union(ct, spokes, m * spacing);
    } catch (const InvalidInput& e) {
      if (std::string(e.what()).find("zero-area") == std::string::npos) throw;
      if (first_error.empty()) first_error = e.what();
      if (m == bases.back())
        throw InvalidInput(cat(first_error, "; also at base ring spacings ", bases[1] * spacing, " to ",
                               bases.back() * spacing, " mm"));
      continue;
    }
    if (m != 1.0)
      r.notes.push_back(cat("base ring spacing ", m * spacing, " mm (", spacing,
                            " mm left zero-area triangles in the union: ", first_error, ")"));
    break;
  }
  const ClosedManifoldReport cm = check_closed_manifold(r.mesh);
  r.closed = cm.ok();
  r.components = cm.mesh.components;
  r.self_intersections = self_intersections(r.mesh, "vessel tree surface");
  r.volume_mm3 = signed_volume(r.mesh.V, r.mesh.F);
  require(r.closed, "vessel tree surface: the union of the path tubes is not a closed manifold (",
          cm.mesh.summary(), ")");
  if (r.self_intersections > 0)
    r.warnings.push_back(cat("the tree surface intersects itself: ", r.self_intersections,
                             " triangle pairs (try another blend spacing)"));
  return r;
}

std::shared_ptr<SmrmTree> make_blended_tree(const CenterlineTree& ct, const SmrmTreeSettings& settings,
                                            double spacing, TreeSurface* report) {
  const SmrmTree plain(ct, settings);
  TreeSurface r = blended_tree_surface(ct, plain, spacing);
  auto tree = std::make_shared<SmrmTree>(ct, settings, r.mesh);
  if (report) *report = std::move(r);
  return tree;
}

VesselBuild build_vessel(const VesselBuildSettings& st) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const bool has_line = !st.centerline.empty();
  const bool has_organ = !st.source.mesh.empty() || !st.source.mask.empty();
  require(has_line != has_organ, "vessel: give exactly one of a centerline, a mesh and a segmentation");
  require(!(st.blend && st.no_blend), "vessel: give at most one of blend and no_blend");
  require(!st.no_blend || (has_organ && st.all_branches),
          "vessel: no_blend applies to a tree from a mesh or a segmentation (its default is the watertight "
          "surface)");
  require(!st.blend || st.all_branches,
          "vessel: a blended (watertight) surface applies to a tree (all branches)");
  require(st.smrm.atoms >= 3, "vessel: atoms must be >= 3 (got ", st.smrm.atoms, ")");
  require(st.smrm.spokes >= 3, "vessel: spokes must be >= 3 (got ", st.smrm.spokes, ")");
  if (has_organ && st.all_branches) return tree_from_organ(st, t0);
  VesselBuild out;
  VesselSummary& s = out.summary;
  std::shared_ptr<SmrmVessel> vessel;
  if (has_line) {
    const std::vector<Centerline> lines = read_centerlines(st.centerline, st.centerline_unit);
    s.input = st.centerline.filename().string();
    s.input_kind = "centerline";
    s.input_branches = static_cast<Index>(lines.size());
    std::size_t k = 0;
    if (st.all_branches) {
      require(st.branch < 0, "vessel: give a branch or all branches, not both");
      SmrmTreeSettings ts;
      ts.vessel = st.smrm;
      const CenterlineTree ct = merge_centerlines(lines, st.merge_tolerance);
      std::shared_ptr<SmrmTree> tree;
      if (!st.blend) {
        tree = std::make_shared<SmrmTree>(ct, ts);
      } else {  // the watertight junction surface: union of the closed path tubes
        tree = blended(ct, ts, st.blend_spacing, s);
      }
      return finish_tree(std::move(tree), s, t0);
    }
    if (st.branch < 0) {
      const Centerline& longest = longest_centerline(lines);
      k = static_cast<std::size_t>(&longest - lines.data());
    } else {
      require(st.branch < s.input_branches, s.input, ": branch ", st.branch, " does not exist (the file has ",
              s.input_branches, " polylines, 0..", s.input_branches - 1, ")");
      k = static_cast<std::size_t>(st.branch);
    }
    s.branch = static_cast<Index>(k);
    Centerline line = lines[k];
    line.name = cat(s.input, " branch ", k);
    require(line.size() >= 2, s.input, ": branch ", k, " has ", line.size(),
            " point(s); a vessel needs at least 2");
    vessel = std::make_shared<SmrmVessel>(smrm_from_centerline(line, st.smrm));
    if (s.input_branches > 1)
      s.notes.push_back(cat("the file has ", s.input_branches, " polylines; branch ", k,
                            st.branch < 0 ? " (the longest)" : "", " was used"));
  } else {
    if (!st.source.mask.empty()) {  // a vessel (tree) is one component: refuse, naming the count
      const LoadedOrgan organ = load_organ(st.source, {.surface = false});
      if (organ.components > 1)
        throw InvalidInput(cat(organ.name, ": label ", organ.label, " has ", organ.components,
                               " separate components (26-connected); a vessel must be one component (",
                               organ.notes.empty() ? std::string() : organ.notes.front(), ")"));
    }
    CenterlineBuildSettings cs;
    cs.source = st.source;
    cs.atoms = st.smrm.atoms;
    const CenterlineBuild c = build_centerline(cs);
    s.input = c.summary.input;
    s.input_kind = c.summary.input_kind;
    s.notes = c.summary.notes;
    s.warnings = c.summary.warnings;
    Centerline line = c.centerline();
    line.name = s.input;
    require(c.surface.num_faces() > 0, s.input, ": no boundary surface to march the spokes to");
    vessel = std::make_shared<SmrmVessel>(smrm_from_marched_spokes(line, c.surface, st.smrm));
    out.input = c.surface;
  }
  const SmrmVessel& v = *vessel;
  s.atoms = v.num_atoms();
  s.surface_nodes = static_cast<Index>(v.rest_surface().rows());
  s.faces = static_cast<Index>(v.faces().rows());
  s.spokes = v.grid().valid() ? v.grid().spokes : 0;
  const MatX3& C = v.rest_atoms();
  for (Index i = 1; i < s.atoms; ++i) s.length_mm += (C.row(i) - C.row(i - 1)).norm();
  s.radius_min_mm = v.atom_radius().minCoeff();
  s.radius_max_mm = v.atom_radius().maxCoeff();
  {
    SmrmVessel::Workspace ws = v.make_workspace();
    MatX3 S;
    v.map_to_surface(C, ws, S);
    s.rest_error_mm = (S - v.rest_surface()).rowwise().norm().maxCoeff();
  }
  const VecX& kb = v.bending_stiffness();
  if (s.atoms > 2) {
    s.kb_min = kb.segment(1, s.atoms - 2).minCoeff();
    s.kb_max = kb.segment(1, s.atoms - 2).maxCoeff();
  }
  s.max_rho_kappa = v.report().curvature.max_rho_kappa;
  s.dt_safe_ms = dt_safe(v.model(), 1.0);
  s.spokes_without_hit = v.report().spokes_without_hit;
  for (const auto& n : v.report().notes) s.notes.push_back(n);
  if (out.input.num_faces() > 0) {
    measure_distance_to_input(SurfaceMesh{v.rest_surface(), v.faces()}, out.input, s);
  }
  Centerline atoms_line;
  atoms_line.name = v.name();
  atoms_line.points = C;
  atoms_line.radii = v.atom_radius();
  out.centerlines.push_back(std::move(atoms_line));
  if (out.input.num_faces() > 0)
    builders_detail::measure_away_from_ends(SurfaceMesh{v.rest_surface(), v.faces()}, out.input,
                                            out.centerlines, {{0, false}, {0, true}}, s);
  out.vessel = std::move(vessel);
  s.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return out;
}

std::string VesselSummary::text() const {
  std::string t = cat("vessel from ", input_kind, " ", input, "\n");
  t += cat("  atoms: ", atoms, ", branches: ", branches, ", junctions: ", junctions,
           ", surface nodes: ", surface_nodes, " (", spokes, " spokes per atom, ", faces, " triangles)\n");
  t += cat("  length ", length_mm, " mm, radii ", radius_min_mm, "..", radius_max_mm, " mm\n");
  t += cat("  rest reconstruction error: ", rest_error_mm, " mm\n");
  t += cat("  bending k_b ", kb_min, "..", kb_max, " N/mm, max rho kappa at rest ", max_rho_kappa,
           ", stable step at rest ", dt_safe_ms, " ms\n");
  if (has_distance)
    t += cat("  rebuilt surface vs input: Hausdorff ", hausdorff_mm, " mm, mean distance ", mean_distance_mm,
             " mm (both count the input's end caps, which the open tube lacks); surface nodes to the input: "
             "max ",
             to_input_max_mm, " mm, mean ", to_input_mean_mm, " mm\n");
  if (away.measured) {
    t +=
        cat("  away from the cut ends (samples whose axis point is more than an end radius of arc from a cut "
            "end): Hausdorff ",
            away.hausdorff_mm, " mm, mean ", away.mean_mm, " mm; ", away.samples_over_2mm, " of ",
            away.samples, " samples and ", away.nodes_over_2mm, " of ", away.nodes,
            " surface nodes farther than 2 mm (nodes max ", away.node_max_mm, " mm)\n");
    if (away.worst_branch >= 0)
      t += cat("    largest at branch ", away.worst_branch, " atom ", away.worst_atom, ", ",
               away.worst_from_cut_mm, " mm of arc from the nearest cut end, (", away.worst_point.x(), ", ",
               away.worst_point.y(), ", ", away.worst_point.z(), ") mm, ", away.worst_direction, "\n");
  }
  if (blended)
    t += cat("  watertight surface: union of ", path_tubes, " closed path tubes, ",
             surface_closed ? "closed and manifold" : "NOT closed", ", ", surface_components,
             " component(s), ", self_intersections, " self-intersecting triangle pairs, volume ",
             surface_volume_mm3, " mm^3\n");
  t += cat("  built in ", seconds, " s\n");
  for (const auto& n : notes) t += cat("  note: ", n, "\n");
  for (const auto& w : warnings) t += cat("  warning: ", w, "\n");
  return t;
}

void write_vessel_files(const std::filesystem::path& dir, const VesselBuild& build) {
  require(build.vessel != nullptr || build.tree != nullptr, "write_vessel_files: the build holds no vessel");
  const Body& body = build.vessel ? static_cast<const Body&>(*build.vessel) : *build.tree;
  const MatX3& S = body.rest_surface();
  const MatX3& X = body.model().x0;
  const Index ns = static_cast<Index>(S.rows()), na = static_cast<Index>(X.rows());
  VecX atom(ns), branch = VecX::Zero(ns);
  for (Index k = 0; k < ns; ++k) {
    atom[k] = static_cast<double>(build.vessel ? build.vessel->node_atom(k) : build.tree->node_atom(k));
    if (build.tree) branch[k] = static_cast<double>(build.tree->node_branch(k));
  }
  write_vtp(dir / "surface.vtp", SurfaceMesh{S, body.faces()}, {{"atom", atom}, {"branch", branch}});
  write_centerlines(dir / "atoms.vtp", build.centerlines);
  MatX3 P(ns + na, 3);
  P.topRows(ns) = S;
  P.bottomRows(na) = X;
  MatX2i seg(ns, 2);
  for (Index k = 0; k < ns; ++k) seg.row(k) << ns + static_cast<Index>(atom[k]), k;
  VecX is_atom = VecX::Zero(ns + na);
  is_atom.tail(na).setOnes();
  write_segments_vtp(dir / "spokes.vtp", P, seg, {{"atom", is_atom}});
  if (build.vessel)
    save_model_package(dir / "vessel.msm",
                       package_of(*build.vessel, build.vessel->name(),
                                  cat("SMRM vessel from ", build.summary.input_kind, " ", build.summary.input,
                                      ", ", na, " atoms x ", build.summary.spokes, " spokes")));
  else
    save_model_package(
        dir / "vessel.msm",
        package_of(*build.tree, "vessel tree",
                   cat("SMRM vessel tree from ", build.summary.input_kind, " ", build.summary.input, ", ",
                       build.tree->num_branches(), " branches, ", na, " atoms")));
}

}  // namespace medspring
