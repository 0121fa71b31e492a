// Seed generator: medspring_fuzz_seeds OUT writes small valid inputs for every target into
// OUT/<target>/ with MedSpring's own writers (binary formats the Python half of make-seeds.sh does not
// produce): meshes in every format, a centerline, MetaImage volumes, checkpoints and model packages of
// the fuzz models (models.hpp). Built next to the fuzz targets; fuzz/make-seeds.sh runs it.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/sim/checkpoint.hpp"
#include "models.hpp"
#ifdef MEDSPRING_FUZZ_WITH_IO
#include "medspring/io/centerline_io.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/io/volume_io.hpp"
#endif

using namespace medspring;
namespace fs = std::filesystem;

namespace {

fs::path out_dir(const fs::path& root, const char* target) {
  const fs::path d = root / target;
  fs::create_directories(d);
  return d;
}

void put(const fs::path& file, const std::string& bytes) {
  std::ofstream f(file, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!f) throw IoError(cat(file.string(), ": cannot write"));
}

#ifdef MEDSPRING_FUZZ_WITH_IO
void mesh_seeds(const fs::path& root) {
  const std::pair<const char*, SurfaceMesh> meshes[] = {
      {"icosphere1", icosphere(1, 5.0)}, {"tube4x6", tube(4, 6, 2.0, 2.0)}, {"kidney", kidney_phantom()}};
  const std::pair<const char*, const char*> formats[] = {
      {"mesh_obj", ".obj"}, {"mesh_stl", ".stl"}, {"mesh_ply", ".ply"}, {"mesh_vtp", ".vtp"}, {"mesh_vtk", ".vtk"}};
  for (const auto& [target, ext] : formats) {
    const fs::path d = out_dir(root, target);
    for (const auto& [name, mesh] : meshes) write_mesh(d / (std::string("gen_") + name + ext), mesh);
  }
  // a VTP with point arrays (what `medspring run` writes)
  const SurfaceMesh m = icosphere(1, 5.0);
  write_vtp(out_dir(root, "mesh_vtp") / "gen_arrays.vtp", m,
            {{"displacement", MatX3(0.1 * m.V)}, {"magnitude", VecX(m.V.rowwise().norm())}});
}

void centerline_seeds(const fs::path& root) {
  const fs::path d = out_dir(root, "centerline");
  write_centerlines(d / "gen_arc.vtp", {vessel_phantom_centerline(VesselPath::Arc, 12, 3.0)});
  Centerline a = vessel_phantom_centerline(VesselPath::StraightX, 5, 2.0);
  Centerline b = vessel_phantom_centerline(VesselPath::Helix, 7, 1.5);
  write_centerlines(d / "gen_two.vtp", {a, b});
}

void volume_seeds(const fs::path& root) {
  const fs::path d = out_dir(root, "volume_mha");
  LabelVolume v;
  v.dims = {6, 5, 4};
  v.spacing = Vec3(0.5, 0.8, 1.25);
  v.origin = Vec3(-3, 2, 10);
  v.data.assign(v.size(), 0);
  for (std::size_t i = 0; i < v.size(); ++i) v.data[i] = static_cast<std::int32_t>((i * 7) % 5 == 0);
  write_label_volume(d / "gen_small.mha", v);
  v.direction = Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  for (auto& x : v.data) x *= 300;  // stored as short
  write_label_volume(d / "gen_rotated_short.mha", v);
}
#endif

void checkpoint_seeds(const fs::path& root) {
  const fs::path d = out_dir(root, "checkpoint");
  int k = 0;
  for (const BodyPtr& body : fuzz::fuzz_bodies()) {
    Simulation sim(body);
    put(d / cat("gen_", k, "_rest.mscp"), encode_checkpoint(make_checkpoint(sim)));
    sim.set_loads({{.node = 3, .force = {0, 0, -0.2}, .t_ramp = 2, .t_release = 6},
                   {.node = 1, .force = {0.1, 0, 0}, .t_on = 1, .ramp_down = true}});
    for (int i = 0; i < 10; ++i) sim.update();
    put(d / cat("gen_", k, "_loaded.mscp"), encode_checkpoint(make_checkpoint(sim)));
    SimulationSettings s = sim.settings();
    s.step.integrator = Integrator::ImplicitEuler;
    s.step.newton_iterations = 2;
    sim.set_settings(s);
    for (int i = 0; i < 3; ++i) sim.update();
    put(d / cat("gen_", k, "_implicit.mscp"), encode_checkpoint(make_checkpoint(sim)));
    ++k;
  }
}

void model_package_seeds(const fs::path& root) {
  const fs::path d = out_dir(root, "model_package");
  int k = 0;
  for (const BodyPtr& body : fuzz::fuzz_bodies()) {
    put(d / cat("gen_", k, "_", body->kind(), ".msm"),
        encode_model_package(package_of(*body, cat("fuzz ", body->kind()), "seed")));
    ++k;
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: medspring_fuzz_seeds OUT_DIR\n");
    return 2;
  }
  const fs::path root = argv[1];
  try {
#ifdef MEDSPRING_FUZZ_WITH_IO
    mesh_seeds(root);
    centerline_seeds(root);
    volume_seeds(root);
#endif
    checkpoint_seeds(root);
    model_package_seeds(root);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "medspring_fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
