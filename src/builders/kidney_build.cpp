#include "medspring/builders/kidney_build.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "medspring/core/check.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/io/centerline_io.hpp"
#include "medspring/io/mesh_io.hpp"

namespace medspring {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace

KidneyBuild build_kidney_model(const KidneyBuildSettings& st) {
  const auto t0 = Clock::now();
  require(st.nodes >= st.balloon.min_nodes, "kidney: nodes must be >= ", st.balloon.min_nodes, " (got ",
          st.nodes, "): too few nodes to follow an organ's shape");
  require(st.atoms >= 2, "kidney: atoms must be >= 2 (got ", st.atoms, ")");
  require(st.atoms <= st.nodes, "kidney: atoms (", st.atoms, ") must not exceed surface nodes (", st.nodes,
          ")");

  KidneyBuild out;
  KidneySummary& s = out.summary;
  LoadedOrgan organ = load_organ(st.source, {.surface = true, .isosurface = st.isosurface});
  s.input = organ.name;
  s.input_kind = organ.from_mask ? "mask" : "mesh";
  s.notes = organ.notes;
  s.warnings = organ.warnings;
  {
    const MeshReport r = validate_mesh(organ.surface);
    s.input_vertices = r.vertices;
    s.input_faces = r.faces;
    s.organ_volume_mm3 = std::abs(r.signed_volume);
    s.organ_diagonal_mm = r.bbox_diagonal;
  }

  // Skeleton (§3): the mask itself, or the voxelised organ mesh (§3.6); closed ends (D-8).
  const auto t_skeleton = Clock::now();
  if (organ.from_mask) {
    out.mask = std::move(organ.mask);
  } else {
    VoxelizeStats vs;
    out.mask = voxelize(organ.surface, st.voxelize, &vs);
    if (vs.odd_rows > 0)
      s.notes.push_back(cat("voxelisation: ", vs.odd_rows, " of ", vs.rows,
                            " scanlines classified by winding number (mesh not watertight there)"));
  }
  SkeletonSettings sk = st.skeleton;
  sk.atom_count = st.atoms;
  out.skeleton = extract_centerline(out.mask, sk);
  s.seconds_skeleton = seconds_since(t_skeleton);
  s.voxel_size_mm = out.skeleton.h_min;
  s.object_voxels = out.skeleton.component_voxels;
  for (const auto& n : out.skeleton.notes) s.notes.push_back("skeleton: " + n);

  // Balloon surface at the exact node count (§1.1, §4.4).
  const auto t_surface = Clock::now();
  BalloonSettings bs = st.balloon;
  bs.target_nodes = st.nodes;
  bs.measure_distance = true;
  BalloonResult balloon = build_balloon_surface(organ.surface, bs);
  s.seconds_surface = seconds_since(t_surface);
  const std::string size_warning = organ_size_warning(balloon.report.organ_size_mm);
  for (const auto& w : balloon.report.warnings)
    if (w != size_warning || organ.warnings.empty()) s.warnings.push_back("surface: " + w);
  s.notes.push_back(cat("surface: remeshed at edge length ", balloon.report.target_edge_length, " mm to ",
                        balloon.report.remeshed_nodes, " nodes, then ", balloon.report.collapses,
                        " collapses, ", balloon.report.splits, " splits, ", balloon.report.flips,
                        " valence flips"));

  // A surface too coarse for the shape cuts through the skeleton: spokes would cross the surface.
  Index outside_model = 0;
  for (Index a = 0; a < out.skeleton.atoms.rows(); ++a)
    if (winding_number(balloon.mesh, out.skeleton.atoms.row(a).transpose()) < 0.5) ++outside_model;
  require(outside_model == 0, "kidney: ", st.nodes, " surface nodes are too few for the shape of ",
          organ.name, ": ", outside_model, " of ", out.skeleton.atoms.rows(),
          " atoms lie outside the model surface (Hausdorff distance to the organ ",
          balloon.report.hausdorff_mm, " mm); use more nodes (--nodes)");

  // The hybrid model (§4, D-9, §9).
  auto model =
      std::make_shared<const HybridKidney>(balloon.mesh, out.skeleton.atoms, st.model, "kidney", &out.mask);

  // Summary.
  const SurfaceMesh& surface = balloon.mesh;
  const MatX2i E = unique_edges(surface.F);
  s.nodes = surface.num_vertices();
  s.edges = static_cast<Index>(E.rows());
  s.faces = surface.num_faces();
  s.atoms = static_cast<Index>(out.skeleton.atoms.rows());
  s.valence_histogram = valence_histogram(vertex_adjacency(s.nodes, E));
  s.valence6_fraction = s.valence_histogram.size() > 6
                            ? static_cast<double>(s.valence_histogram[6]) / static_cast<double>(s.nodes)
                            : 0.0;
  s.hausdorff_mm = balloon.report.hausdorff_mm;
  s.mean_distance_mm = balloon.report.mean_distance_mm;
  for (Index a = 0; a < s.atoms; ++a) {
    const Vec3 p = out.skeleton.atoms.row(a).transpose();
    if (winding_number(organ.surface, p) < 0.5) ++s.atoms_outside_organ;
    if (!mask_contains(out.mask, p)) ++s.atoms_outside_mask;
  }
  if (s.atoms_outside_organ > 0)
    s.warnings.push_back(cat(s.atoms_outside_organ, " of ", s.atoms, " atoms lie outside the organ surface"));
  s.skeleton_length_mm = out.skeleton.curve.rows() > 1
                             ? out.skeleton.atom_arc_length[s.atoms - 1] - out.skeleton.atom_arc_length[0]
                             : 0.0;
  s.atom_spacing_min_mm = std::numeric_limits<double>::infinity();
  for (Index a = 1; a < s.atoms; ++a) {
    const double d = (out.skeleton.atoms.row(a) - out.skeleton.atoms.row(a - 1)).norm();
    s.atom_spacing_min_mm = std::min(s.atom_spacing_min_mm, d);
    s.atom_spacing_max_mm = std::max(s.atom_spacing_max_mm, d);
  }
  s.min_radius_mm = out.skeleton.radii.minCoeff();
  s.max_radius_mm = out.skeleton.radii.maxCoeff();
  const HybridStats hs = model->stats();
  s.surface_springs = hs.surface_springs;
  s.centerline_springs = hs.centerline_springs;
  s.spokes = hs.spokes;
  s.min_spokes_per_atom = hs.min_spokes_per_atom;
  s.max_spokes_per_atom = hs.max_spokes_per_atom;
  s.surface_nodes_without_spoke = hs.surface_nodes_without_spoke;
  s.dt_safe_ms = model->model().dt_safe_rest();

  out.organ = std::move(organ.surface);
  out.balloon = std::move(balloon.report);
  out.model = std::move(model);
  s.seconds = seconds_since(t0);
  return out;
}

std::string KidneySummary::text() const {
  std::string t = cat("hybrid kidney from ", input, " (", input_kind, ")\n");
  t += cat("  organ: ", input_vertices, " vertices, ", input_faces, " faces, ", organ_volume_mm3 / 1000.0,
           " cm^3, ", organ_diagonal_mm, " mm across\n");
  t += cat("  surface: ", nodes, " nodes, ", edges, " springs, ", faces, " triangles; valences");
  for (std::size_t d = 0; d < valence_histogram.size(); ++d)
    if (valence_histogram[d] > 0) t += cat(" ", d, ":", valence_histogram[d]);
  t += cat(" (", std::round(valence6_fraction * 1000.0) / 10.0, " % with six)\n");
  t += cat("  distance to the organ: Hausdorff ", hausdorff_mm, " mm, mean ", mean_distance_mm, " mm\n");
  t += cat("  skeleton: ", atoms, " atoms over ", skeleton_length_mm, " mm (", atom_spacing_min_mm, "..",
           atom_spacing_max_mm, " mm apart), radii ", min_radius_mm, "..", max_radius_mm, " mm (voxels of ",
           voxel_size_mm, " mm, ", object_voxels, " in the organ)\n");
  t += cat("  atoms outside: organ ", atoms_outside_organ, ", voxel mask ", atoms_outside_mask,
           ", model surface ", atoms_outside_model, "\n");
  t += cat("  springs: ", surface_springs, " surface, ", centerline_springs, " centerline, ", spokes,
           " spokes (", min_spokes_per_atom, "..", max_spokes_per_atom, " per atom; ",
           surface_nodes_without_spoke, " surface nodes without a spoke)\n");
  t += cat("  stable step at rest: ", dt_safe_ms, " ms\n");
  t += cat("  built in ", seconds, " s (surface ", seconds_surface, " s, skeleton ", seconds_skeleton,
           " s)\n");
  for (const auto& n : notes) t += cat("  note: ", n, "\n");
  for (const auto& w : warnings) t += cat("  warning: ", w, "\n");
  return t;
}

void write_kidney_files(const std::filesystem::path& dir, const KidneyBuild& build) {
  require(build.model != nullptr, "write_kidney_files: the build holds no model");
  const HybridKidney& m = *build.model;
  const MatX3& S = m.rest_surface();
  const Index ns = static_cast<Index>(S.rows()), na = m.num_atoms();
  const Adjacency adj = vertex_adjacency(ns, unique_edges(m.faces()));
  VecX valence(ns), spoke_count = VecX::Zero(ns);
  for (Index i = 0; i < ns; ++i) valence[i] = static_cast<double>(adj.degree(i));
  const MatX2i& spokes = m.spokes();
  for (Index r = 0; r < spokes.rows(); ++r) spoke_count[spokes(r, 0)] += 1.0;
  write_vtp(dir / "surface.vtp", SurfaceMesh{S, m.faces()}, {{"valence", valence}, {"spokes", spoke_count}});

  Centerline line = build.skeleton.centerline();
  line.name = "kidney skeleton";
  write_centerlines(dir / "centerline.vtp", {line});

  MatX3 P(ns + na, 3);
  P.topRows(ns) = S;
  P.bottomRows(na) = build.skeleton.atoms;
  MatX2i seg = spokes;
  seg.col(1).array() += ns;
  VecX is_atom = VecX::Zero(ns + na);
  is_atom.tail(na).setOnes();
  write_segments_vtp(dir / "spokes.vtp", P, seg, {{"atom", is_atom}});
}

}  // namespace medspring
