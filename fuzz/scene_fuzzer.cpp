// Fuzz target: scene files (scene/scene.hpp). parse_scene on the bytes as JSON text; an accepted scene
// must survive scene_to_json -> parse_scene -> scene_to_json unchanged (what `medspring run` writes as
// scene.json must read back as the same scene). Scenes built from a small phantom are also built
// (build_scene), so that what the parser lets through is checked against what the builder needs. File sources resolve against empty placeholder files (the parser only checks
// that they exist; reading them is the job of the mesh, volume and centerline targets).
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

#include "fuzz_support.hpp"
#include "medspring/core/check.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/scene.hpp"

using namespace medspring;
namespace fs = std::filesystem;

namespace {

const fs::path& scene_dir() {
  static const fs::path dir = [] {
    const fs::path base = fuzz::scratch_dir() / "scene";
    const fs::path data = fuzz::scratch_dir() / "data";
    fs::create_directories(base);
    fs::create_directories(data);
    for (const char* f : {"mesh.obj", "mesh.stl", "mask.nii.gz", "mask.mha", "line.vtp", "line.vtk"})
      std::ofstream(base / f).put('\n');
    for (const char* f : {"kidney_left_hubmap_vhm.obj", "aorta_totalseg_ct.obj", "aorta_totalseg_mask.nii.gz",
                          "vmr-0159-aorta-centerline.vtp"})
      std::ofstream(data / f).put('\n');
    ::setenv("MEDSPRING_DATA", data.c_str(), 1);
    return base;
  }();
  return dir;
}

/// Phantom models small enough to build on every input (the 458-node kidney, a tube of <= 600 nodes,
/// the vessel phantom with <= 64 atoms x 32 spokes).
bool small_phantom(const Scene& s) {
  const ModelSource& src = s.model.source;
  if (src.type != ModelSource::Type::Phantom) return false;
  if (src.phantom == "tube") return src.rings * src.spokes <= 600;
  if (src.phantom == "vessel") return s.model.atoms <= 64 && s.model.smrm.spokes <= 32;
  return s.model.atoms <= 200;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fs::path& base = scene_dir();
  const std::string text(reinterpret_cast<const char*>(data), size);
  Scene s;
  if (!fuzz::accepts([&] { s = parse_scene(text, base, "fuzz.json"); })) return 0;
  std::string once, twice;
  const bool round_trip = fuzz::accepts([&] {
    once = scene_to_json(s);
    twice = scene_to_json(parse_scene(once, base, "fuzz.json"));
  });
  MEDSPRING_FUZZ_CHECK(round_trip, "scene_to_json output is rejected by parse_scene:\n" + once);
  MEDSPRING_FUZZ_CHECK(once == twice, "scene_to_json is not stable:\n" + once + "\n---\n" + twice);
  if (small_phantom(s)) {
    BuiltScene b;
    if (!fuzz::accepts([&] { b = build_scene(s, nullptr); })) return 0;
    MEDSPRING_FUZZ_CHECK(b.body != nullptr, "no body");
    MEDSPRING_FUZZ_CHECK(std::isfinite(b.dt_safe_rest) && b.dt_safe_rest > 0, cat("dt_safe ", b.dt_safe_rest));
    for (const PointLoad& L : b.loads) MEDSPRING_FUZZ_CHECK(L.force.allFinite(), "load force");
  }
  return 0;
}
