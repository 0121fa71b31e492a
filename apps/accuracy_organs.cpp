// `medspring accuracy`: the organs it scores (docs/accuracy.md) -- the phantom, the real kidney of the
// bundled scene and the real aorta as a solid organ -- with their principal frames, load sites and supports.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "accuracy_tables.hpp"
#include "medspring/core/check.hpp"
#include "medspring/io/data_dir.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/scene.hpp"
#include "scene_support.hpp"
#ifdef MEDSPRING_HAVE_MESHING
#include "medspring/meshing/balloon.hpp"
#endif

namespace medspring::cli::accuracy {

namespace fs = std::filesystem;

Frame principal_frame(const MatX3& V) {
  Frame f;
  f.c = V.colwise().mean().transpose();
  const MatX3 D = V.rowwise() - f.c.transpose();
  Eigen::SelfAdjointEigenSolver<Mat3> es(D.transpose() * D);
  f.e3 = es.eigenvectors().col(0);
  f.e1 = es.eigenvectors().col(2);
  const VecX p1 = D * f.e1, p3 = D * f.e3;
  f.half_length = 0.5 * (p1.maxCoeff() - p1.minCoeff());
  f.thickness = p3.maxCoeff() - p3.minCoeff();
  return f;
}

// Sites on the +e3 side at fractions t of the half length along e1: the most +e3 node near each.
std::vector<Index> pick_sites(const MatX3& V, const Frame& f, const std::vector<double>& ts) {
  std::vector<Index> out;
  for (double t : ts) {
    Index best = -1;
    double top = -1e300;
    for (Index i = 0; i < V.rows(); ++i) {
      const Vec3 d = V.row(i).transpose() - f.c;
      if (std::abs(d.dot(f.e1) - t * f.half_length) > 0.1 * f.half_length) continue;
      if (d.dot(f.e3) > top) {
        top = d.dot(f.e3);
        best = i;
      }
    }
    require(best >= 0, "accuracy: no surface node near site t = ", t);
    out.push_back(best);
  }
  return out;
}

Organ phantom_organ() {
  const HybridKidney hk = hybrid_kidney_phantom();
  Organ o;
  o.name = "kidney phantom";
  o.surface = {hk.rest_surface(), hk.faces()};
  o.atoms = kidney_phantom_atoms();
  return o;
}

std::optional<Organ> real_kidney(const fs::path& scenes, FileLoader& loader, std::string& why) {
  const fs::path file = scenes / "kidney_1.0N_nonlinear.json";
  try {
    const Scene scene = load_scene(file);
    const BuiltScene built = build_scene(scene, &loader);
    Organ o;
    o.name = "real kidney";
    o.surface = {built.body->rest_surface(), built.body->faces()};
    o.atoms = built.atoms_rest;
    return o;
  } catch (const Error& e) {
    why = e.what();
    return std::nullopt;
  }
}

fem::SupportRule aorta_support_rule(const Frame& f) {
  fem::SupportRule r{-f.e3, 0.0};
  r.facing_deg = 60;
  r.caps = {{Vec3(0, 0, -1), 1.0}};
  return r;
}

std::optional<Organ> real_aorta(std::string& why, Index surface_nodes) {
#ifdef MEDSPRING_HAVE_MESHING
  try {
    const SurfaceMesh raw =
        read_mesh(find_data_file("aorta_totalseg_ct.obj"), {.unit = LengthUnit::Millimetre});
    Organ o;
    o.name = "real aorta (solid)";
    o.surface = balloon_surface(raw, {.target_nodes = surface_nodes});
    o.support = aorta_support_rule(principal_frame(o.surface.V));
    o.support_text =
        "surface facing away from the load (outward normal within 60 deg of -e3: a bed along the whole "
        "vessel) + the cut cap (within 1 mm of the lowest point, -z)";
    return o;
  } catch (const Error& e) {
    why = e.what();
    return std::nullopt;
  }
#else
  (void)surface_nodes;
  why = "this medspring was built without the meshing layer (CGAL), which makes the aorta's surface";
  return std::nullopt;
#endif
}

}  // namespace medspring::cli::accuracy
