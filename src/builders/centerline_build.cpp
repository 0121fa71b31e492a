#include "medspring/builders/centerline_build.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "medspring/core/check.hpp"
#include "medspring/io/centerline_io.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/skeleton/distance_transform.hpp"

namespace medspring {

CenterlineBuild build_centerline(const CenterlineBuildSettings& st) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  require(st.atoms >= 2, "centerline: atoms must be >= 2 (got ", st.atoms, ")");
  CenterlineBuild out;
  CenterlineSummary& s = out.summary;
  LoadedOrgan organ =
      load_organ(st.source, {.allow_open_tube = true, .surface = st.surface, .isosurface = st.isosurface});
  s.input = organ.name;
  s.input_kind = organ.from_mask ? "mask" : "mesh";
  s.notes = organ.notes;
  s.warnings = organ.warnings;

  SkeletonSettings sk = st.skeleton;
  sk.atom_count = st.atoms;
  if (organ.from_mask) {
    out.mask = std::move(organ.mask);
    out.skeleton = extract_centerline(out.mask, sk);
    s.components = organ.components;
  } else {
    MeshCenterline mc = centerline_from_mesh(organ.surface, sk, st.voxelize);
    if (!mc.caps.empty()) s.notes.push_back(cat(mc.caps.size(), " boundary loop(s) capped by fans (§3.6)"));
    out.mask = std::move(mc.mask);
    out.skeleton = std::move(mc.skeleton);
    s.components = organ.components;
  }
  out.surface = std::move(organ.surface);
  for (const auto& n : out.skeleton.notes) s.notes.push_back("skeleton: " + n);

  const SkeletonResult& r = out.skeleton;
  s.atoms = static_cast<Index>(r.atoms.rows());
  s.length_mm = r.atom_arc_length[s.atoms - 1] - r.atom_arc_length[0];
  s.atom_spacing_min_mm = std::numeric_limits<double>::infinity();
  for (Index a = 1; a < s.atoms; ++a) {
    const double d = (r.atoms.row(a) - r.atoms.row(a - 1)).norm();
    s.atom_spacing_min_mm = std::min(s.atom_spacing_min_mm, d);
    s.atom_spacing_max_mm = std::max(s.atom_spacing_max_mm, d);
  }
  s.min_radius_mm = r.radii.minCoeff();
  s.max_radius_mm = r.radii.maxCoeff();
  s.mean_radius_mm = r.radii.mean();
  for (int e = 0; e < 2; ++e) s.ends[e] = to_string(r.ends[e].kind);
  s.open_end_sizes = r.open_end_sizes;
  s.object_voxels = r.component_voxels;
  s.voxel_size_mm = r.h_min;

  // Checks: atoms in the lumen, radii against the distance map of the object on its own grid (§3.2).
  // Atoms on the linear extension to a cap plane (§3.6) take the radius at the junction: not compared.
  const DistanceField field = distance_from_boundary(out.mask);
  const double s_first = r.ends[0].extended, s_last = r.atom_arc_length[s.atoms - 1] - r.ends[1].extended;
  for (Index a = 0; a < s.atoms; ++a) {
    const Vec3 p = r.atoms.row(a).transpose();
    if (!mask_contains(out.mask, p)) {
      ++s.atoms_outside_mask;
      s.max_distance_outside_mm = std::max(s.max_distance_outside_mm, distance_outside_mask(out.mask, p));
    }
    const double dfb = sample_trilinear(field.dfb, p);
    const bool on_extension = r.atom_arc_length[a] < s_first - 1e-9 || r.atom_arc_length[a] > s_last + 1e-9;
    if (std::isfinite(dfb) && !on_extension) {
      const double r_map = std::max(dfb - 0.5 * r.h_min, 0.5 * r.h_min);
      s.max_radius_deviation_mm = std::max(s.max_radius_deviation_mm, std::abs(r.radii[a] - r_map));
    }
  }
  if (s.max_distance_outside_mm > 0.5 * r.h_min)
    s.warnings.push_back(cat(s.atoms_outside_mask, " of ", s.atoms,
                             " atoms lie outside the object voxels (by up to ", s.max_distance_outside_mm,
                             " mm)"));
  s.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return out;
}

std::string CenterlineSummary::text() const {
  std::string t = cat("centerline of ", input, " (", input_kind, ")\n");
  t += cat("  ", atoms, " atoms over ", length_mm, " mm (", atom_spacing_min_mm, "..", atom_spacing_max_mm,
           " mm apart); radii ", min_radius_mm, "..", max_radius_mm, " mm (mean ", mean_radius_mm, ")\n");
  t += cat("  ends: ", ends[0], ", ", ends[1]);
  if (!open_end_sizes.empty()) {
    t += " (open-end voxels";
    for (Index n : open_end_sizes) t += cat(" ", n);
    t += ")";
  }
  t += cat("\n  object: ", object_voxels, " voxels of ", voxel_size_mm, " mm, ", components,
           " component(s)\n");
  t += cat("  atoms outside the object: ", atoms_outside_mask, " (max ", max_distance_outside_mm,
           " mm); radii vs distance map: max deviation ", max_radius_deviation_mm, " mm\n");
  t += cat("  built in ", seconds, " s\n");
  for (const auto& n : notes) t += cat("  note: ", n, "\n");
  for (const auto& w : warnings) t += cat("  warning: ", w, "\n");
  return t;
}

void write_centerline_files(const std::filesystem::path& dir, const CenterlineBuild& build) {
  Centerline line = build.centerline();
  line.name = "centerline";
  write_centerlines(dir / "centerline.vtp", {line});
  const MatX3& curve = build.skeleton.curve;
  if (curve.rows() >= 2) {
    std::vector<Index> ids(static_cast<std::size_t>(curve.rows()));
    for (Index i = 0; i < curve.rows(); ++i) ids[i] = i;
    write_polyline_vtp(dir / "curve.vtp", curve, {ids});
  }
  if (build.surface.num_faces() > 0) write_vtp(dir / "surface.vtp", build.surface);
}

}  // namespace medspring
