// Scene files: parsing and validation with JSON paths, building models and resolving loads, runs and
// recording, static response (scene/scene.hpp, build.hpp, runner.hpp).
#include "medspring/scene/scene.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/core/units.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/runner.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

const char* kKidney = R"({
  "model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
  "loads": [{"node": 223, "direction": "towards_atom", "atom": 21, "magnitude": 1.0, "t_release": 500}],
  "duration": 1000,
  "record": {"every": 100, "key_times": [495], "atoms": [21]}
})";

/// The message of the InvalidInput (or IoError) that parsing `text` throws; "" if none.
std::string parse_error(const std::string& text, const std::filesystem::path& base = ".") {
  try {
    parse_scene(text, base, "t.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::string build_error(const std::string& text, SceneLoader* loader = nullptr,
                        const std::filesystem::path& base = ".") {
  try {
    build_scene(parse_scene(text, base, "t.json"), loader);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

/// A scene text with one substring replaced (the kidney scene by default).
std::string with(const std::string& from, const std::string& to, std::string text = kKidney) {
  const auto p = text.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return text.replace(p, from.size(), to);
}

TEST(SceneParse, MinimalKidneySceneGetsTheDefaultsOfSection9) {
  const Scene s = parse_scene(kKidney, ".", "t.json");
  EXPECT_EQ(s.model.kind, ModelKind::Hybrid);
  EXPECT_EQ(s.model.atoms, 42);
  EXPECT_TRUE(s.model.nonlinear && s.model.hybrid.nonlinear);
  EXPECT_DOUBLE_EQ(s.model.hybrid.k_surf, 0.05);
  EXPECT_DOUBLE_EQ(s.model.hybrid.k_cl, 0.1);
  EXPECT_DOUBLE_EQ(s.model.hybrid.surface_node.mass, 0.3);
  EXPECT_EQ(s.model.hybrid.duffing.mode, DuffingMode::Strain);
  EXPECT_DOUBLE_EQ(s.step.dt, 0.5);
  EXPECT_TRUE(s.step.substep);
  EXPECT_FALSE(s.local.enabled);
  ASSERT_EQ(s.loads.size(), 1u);
  EXPECT_DOUBLE_EQ(s.loads[0].t_ramp, 20.0);
  EXPECT_EQ(s.loads[0].direction, SceneLoad::Direction::TowardsAtom);
  EXPECT_EQ(s.loads[0].target_atom, 21);
}

TEST(SceneParse, SmrmDefaultsAreTheVesselColumnOfSection9) {
  const Scene s = parse_scene(
      R"({"model": {"kind": "smrm", "nonlinear": false,
                    "source": {"phantom": {"name": "vessel", "path": "arc", "cross_section": "elliptical"}}}})",
      ".", "t.json");
  EXPECT_EQ(s.model.atoms, 40);
  EXPECT_EQ(s.model.smrm.spokes, 30);
  EXPECT_DOUBLE_EQ(s.model.smrm.chain.k, 0.2);
  EXPECT_DOUBLE_EQ(s.model.smrm.chain.mass, 0.5);
  EXPECT_FALSE(s.model.smrm.chain.nonlinear);
  EXPECT_EQ(s.model.source.path, VesselPath::Arc);
  EXPECT_EQ(s.model.source.cross_section, CrossSectionShape::Elliptical);
}

TEST(SceneParse, UnknownKeysAreReportedWithTheirJsonPath) {
  EXPECT_NE(parse_error(with("\"duration\"", "\"durration\"")).find("t.json: durration: unknown key"),
            std::string::npos);
  const std::string e =
      parse_error(with("\"kind\": \"hybrid\",", "\"kind\": \"hybrid\", \"parameters\": {\"k_srf\": 1},"));
  EXPECT_NE(e.find("model.parameters.k_srf: unknown key (expected one of: mass, beta"), std::string::npos)
      << e;
  EXPECT_NE(parse_error(with("\"magnitude\"", "\"magnitud\"")).find("loads[0].magnitude: is required"),
            std::string::npos);
}

TEST(SceneParse, BadValuesNameTheJsonPath) {
  EXPECT_NE(
      parse_error(with("\"duration\": 1000", "\"duration\": -5")).find("duration: must be > 0 ms (got -5)"),
      std::string::npos);
  const std::string two_loads = with("\"t_release\": 500}]",
                                     "\"t_release\": 500}, {\"node\": 1, \"direction\": "
                                     "[0, 0, 1], \"magnitude\": -1}]");
  EXPECT_NE(parse_error(two_loads).find("loads[1].magnitude: must be >= 0 N (got -1)"), std::string::npos);
  EXPECT_NE(parse_error(with("\"magnitude\": 1.0", "\"magnitude\": \"1 N\""))
                .find("loads[0].magnitude: must be a number"),
            std::string::npos);
  EXPECT_NE(parse_error(with("\"magnitude\": 1.0", "\"magnitude\": 1e999")).find("numbers must be finite"),
            std::string::npos);
  EXPECT_NE(parse_error(with("\"node\": 223", "\"node\": 2.5")).find("loads[0].node: must be an integer"),
            std::string::npos);
  EXPECT_NE(parse_error(with("\"t_release\": 500", "\"t_release\": 500, \"t_on\": 600"))
                .find("loads[0].t_release: must be >= t_on"),
            std::string::npos);
  EXPECT_NE(parse_error(with("\"hybrid\"", "\"fem\"")).find("model.kind: unknown model kind 'fem'"),
            std::string::npos);
  EXPECT_NE(parse_error(with("[495]", "[1200]")).find("record.key_times[0]: must be within [0, duration"),
            std::string::npos);
  EXPECT_NE(parse_error(with("\"atoms\": [21]", "\"atoms\": [42]"))
                .find("record.atoms[0]: index 42 out of range [0, 42)"),
            std::string::npos);
  EXPECT_NE(parse_error("{\"model\": ").find("t.json: invalid JSON"), std::string::npos);
  EXPECT_NE(
      parse_error(with("\"phantom\": \"kidney\"", "\"phantom\": \"liver\"")).find("unknown phantom 'liver'"),
      std::string::npos);
}

TEST(SceneParse, MissingFilesAndUnknownUnitsNameTheJsonPath) {
  const auto dir = testing::temp_dir("scene-files");
  const std::string mesh_scene =
      with("\"phantom\": \"kidney\"", R"("mesh": {"file": "organ.obj", "unit": "m"})");
  std::string e = parse_error(mesh_scene, dir);
  EXPECT_NE(e.find("model.source.mesh.file: file not found: " + (dir / "organ.obj").string()),
            std::string::npos)
      << e;
  std::ofstream(dir / "organ.obj") << "# placeholder\n";
  EXPECT_EQ(parse_error(mesh_scene, dir), "");
  e = parse_error(with("\"unit\": \"m\"", "\"unit\": \"furlong\"", mesh_scene), dir);
  EXPECT_NE(e.find("model.source.mesh.unit: "), std::string::npos) << e;
  EXPECT_NE(
      parse_error(with(", \"unit\": \"m\"", "", mesh_scene), dir).find("model.source.mesh.unit: is required"),
      std::string::npos);
}

TEST(SceneParse, DataFolderVariableExpandsToMedspringData) {
  const auto dir = testing::temp_dir("scene-data");
  std::ofstream(dir / "organ.obj") << "# placeholder\n";
  const char* old = std::getenv("MEDSPRING_DATA");
  const std::string saved = old ? old : "";
  setenv("MEDSPRING_DATA", dir.c_str(), 1);
  const Scene s = parse_scene(
      with("\"phantom\": \"kidney\"", R"("mesh": {"file": "${MEDSPRING_DATA}/organ.obj", "unit": "m"})"),
      "/nowhere", "t.json");
  if (old)
    setenv("MEDSPRING_DATA", saved.c_str(), 1);
  else
    unsetenv("MEDSPRING_DATA");
  EXPECT_EQ(s.model.source.mesh, (dir / "organ.obj").lexically_normal());
  EXPECT_EQ(s.model.source.mesh_unit, LengthUnit::Metre);
}

TEST(SceneParse, WrittenSceneParsesBackToTheSameScene) {
  const Scene a = parse_scene(kKidney, ".", "t.json");
  const std::string text = scene_to_json(a);
  const Scene b = parse_scene(text, ".", "again.json");
  EXPECT_EQ(scene_to_json(b), text);
}

TEST(SceneBuild, OutOfRangeNodeIsReportedWithTheJsonPath) {
  EXPECT_NE(build_error(with("\"node\": 223", "\"node\": 9999"))
                .find("t.json: loads[0].node: index 9999 out of range [0, 458)"),
            std::string::npos);
  EXPECT_NE(
      build_error(
          R"({"model": {"kind": "hybrid", "source": {"phantom": "kidney"}}, "record": {"nodes": [458]}})")
          .find("record.nodes[0]: index 458 out of range [0, 458)"),
      std::string::npos);
}

TEST(SceneBuild, TimeStepAboveTheStableBoundWithSubsteppingOffIsRejected) {
  const std::string e = build_error(
      with("\"duration\": 1000", R"("duration": 1000, "integrator": {"dt": 2, "substep": false})"));
  EXPECT_NE(e.find("t.json: integrator.dt: 2 ms is above the stable step"), std::string::npos) << e;
  // the same step with sub-stepping on is accepted (§2.2: the frame is split)
  EXPECT_EQ(build_error(
                with("\"duration\": 1000", R"("duration": 1000, "integrator": {"dt": 2, "substep": true})")),
            "");
}

TEST(SceneParse, ThreadsAreReadWrittenAndRangeChecked) {
  const Scene s = parse_scene(with("\"duration\": 1000", R"("duration": 1000, "integrator": {"threads": 2})"),
                              ".", "t.json");
  EXPECT_EQ(s.step.threads, 2);
  EXPECT_NE(scene_to_json(s).find("\"threads\": 2"), std::string::npos);
  for (const char* bad : {"0", "-3", "1000"}) {
    const std::string e = build_error(
        with("\"duration\": 1000", cat(R"("duration": 1000, "integrator": {"threads": )", bad, "}")));
    EXPECT_NE(e.find("t.json: integrator.threads: must be"), std::string::npos) << e;
  }
}

TEST(SceneBuild, PicksAndDirectionsThatTheModelCannotHaveAreRejected) {
  EXPECT_NE(build_error(with("\"node\": 223", "\"ring\": 1, \"spoke\": 2"))
                .find("loads[0].ring: the model has no ring/spoke grid"),
            std::string::npos);
  EXPECT_NE(build_error(
                with("\"hybrid\"", "\"surface\"", with(", \"atoms\": [21]", "", with(", \"atom\": 21", ""))))
                .find("loads[0].direction: towards_atom needs a model with atoms"),
            std::string::npos);
  EXPECT_NE(build_error(R"({"model": {"kind": "smrm", "source": {"phantom": "vessel"}},
                           "loads": [{"ring": 40, "spoke": 0, "direction": "inward_normal", "magnitude": 1}]})")
                .find("loads[0].ring: index 40 out of range [0, 40)"),
            std::string::npos);
}

TEST(SceneBuild, FileSourcesWithAnImplausibleSizeAreReportedAsAWrongUnit) {
  // A loader that reads "the file" as the kidney phantom stored in metres.
  struct MetreKidney : SceneLoader {
    SurfaceMesh read_mesh(const std::filesystem::path&, LengthUnit unit) override {
      SurfaceMesh m = kidney_phantom();
      m.V *= to_mm(unit) / 1000.0;
      return m;
    }
    std::vector<Centerline> read_centerlines(const std::filesystem::path&, LengthUnit,
                                             const std::string&) override {
      return {};
    }
    LabelVolume read_label_volume(const std::filesystem::path&) override { return {}; }
    SurfaceMesh isosurface(const MaskVolume&) override { return {}; }
    SurfaceMesh balloon(const SurfaceMesh& organ, Index, std::vector<std::string>&) override { return organ; }
  } loader;
  const auto dir = testing::temp_dir("scene-unit");
  std::ofstream(dir / "organ.obj") << "# placeholder\n";
  const std::string surface =
      R"({"model": {"kind": "surface", "source": {"mesh": {"file": "organ.obj", "unit": "mm"}}},
                                  "loads": [{"node": 223, "direction": "inward_normal", "magnitude": 0.5}]})";
  const std::string e = build_error(surface, &loader, dir);
  EXPECT_NE(e.find("model.source.mesh.unit: the mesh organ.obj is 0.1"), std::string::npos) << e;
  EXPECT_NE(e.find("wrong unit?"), std::string::npos) << e;
  const BuiltScene ok = build_scene(parse_scene(with("\"mm\"", "\"m\"", surface), dir, "t.json"), &loader);
  EXPECT_EQ(ok.body->num_surface_nodes(), 458);
  EXPECT_NE(build_error(surface, nullptr, dir).find("needs the file loader"), std::string::npos);
}

TEST(SceneBuild, TreesFromAMaskOrMeshGoToTheLoadersOrganTreeWithBuildVesselDefaults) {
  // A scene's tree from a segmentation or a mesh is the loader's organ_tree (build_vessel in the
  // medspring command and the Python module): the request carries the file, label / unit, the smrm
  // settings and "blend" (default true, as `build vessel`; false = --no-blend). A loader without it refuses.
  struct Recorder : SceneLoader {
    OrganTreeRequest seen;
    SurfaceMesh read_mesh(const std::filesystem::path&, LengthUnit) override { return {}; }
    std::vector<Centerline> read_centerlines(const std::filesystem::path&, LengthUnit,
                                             const std::string&) override {
      return {};
    }
    LabelVolume read_label_volume(const std::filesystem::path&) override { return {}; }
    SurfaceMesh isosurface(const MaskVolume&) override { return {}; }
    SurfaceMesh balloon(const SurfaceMesh& organ, Index, std::vector<std::string>&) override { return organ; }
    std::shared_ptr<const SmrmTree> organ_tree(const OrganTreeRequest& r,
                                               std::vector<std::string>&) override {
      seen = r;
      throw InvalidInput("recorded");
    }
  } loader;
  struct NoBuilders : Recorder {
    std::shared_ptr<const SmrmTree> organ_tree(const OrganTreeRequest& r,
                                               std::vector<std::string>& n) override {
      return SceneLoader::organ_tree(r, n);
    }
  } bare;
  const auto dir = testing::temp_dir("scene-organ-tree");
  std::ofstream(dir / "y.mha") << "# placeholder\n";
  std::ofstream(dir / "y.obj") << "# placeholder\n";
  const std::string mask =
      R"({"model": {"kind": "smrm", "atoms": 16, "source": {"segmentation": {"file": "y.mha", "label": 3,
         "branches": "all"}}}, "loads": [{"node": 0, "direction": "inward_normal", "magnitude": 0.1}]})";
  std::string e = build_error(mask, &loader, dir);
  EXPECT_NE(e.find("model.source.segmentation: recorded"), std::string::npos) << e;
  EXPECT_EQ(loader.seen.segmentation, dir / "y.mha");
  EXPECT_TRUE(loader.seen.mesh.empty());
  EXPECT_EQ(loader.seen.label, 3);
  EXPECT_EQ(loader.seen.smrm.atoms, 16);
  EXPECT_TRUE(loader.seen.blend);
  EXPECT_EQ(loader.seen.blend_spacing, 0.0);
  build_error(with("\"branches\": \"all\"", "\"branches\": \"all\", \"blend\": false", mask), &loader, dir);
  EXPECT_FALSE(loader.seen.blend);
  const std::string mesh = with(R"("segmentation": {"file": "y.mha", "label": 3,)",
                                R"("mesh": {"file": "y.obj", "unit": "cm",)", mask);
  e = build_error(mesh, &loader, dir);
  EXPECT_NE(e.find("model.source.mesh: recorded"), std::string::npos) << e;
  EXPECT_EQ(loader.seen.mesh, dir / "y.obj");
  EXPECT_EQ(loader.seen.mesh_unit, LengthUnit::Centimetre);
  EXPECT_TRUE(loader.seen.blend);
  e = build_error(mask, &bare, dir);
  EXPECT_NE(
      e.find("model.source.segmentation: a vessel tree from a mesh or a segmentation needs the builders"),
      std::string::npos)
      << e;
}

TEST(SceneRun, KidneyPhantomReproducesThePrototypeValuesOfSection7_1) {
  const BuiltScene b = build_scene(parse_scene(kKidney, ".", "t.json"), nullptr);
  const SceneResult r = run_scene(b);
  EXPECT_EQ(r.summary.updates, 2000);
  EXPECT_NEAR(r.summary.contact_hold_mm, 5.08, 0.01);  // §7.1: contact 5.08 mm
  EXPECT_NEAR(r.summary.atom_hold_mm, 1.71, 0.01);     // §7.1: middle atom 1.71 mm
  EXPECT_LT(r.summary.return_ms, 200.0);               // §8.2-12: back within 1e-3 mm in < 200 ms
  EXPECT_LT(r.summary.final_max_disp_mm, 1e-3);
  EXPECT_EQ(r.summary.warnings, 0u);
}

TEST(SceneRun, NonlinearKidneyMovesLessThanLinearAtTheSameForce) {
  const BuiltScene nl = build_scene(parse_scene(kKidney, ".", "t.json"), nullptr);
  const BuiltScene lin =
      build_scene(parse_scene(with("\"kind\": \"hybrid\",", "\"kind\": \"hybrid\", \"nonlinear\": false,"),
                              ".", "t.json"),
                  nullptr);
  EXPECT_LT(run_scene(nl).summary.contact_hold_mm, run_scene(lin).summary.contact_hold_mm);  // §7.1
}

TEST(SceneRun, FramesAreRecordedAtRestEveryNUpdatesAndAtTheKeyTimes) {
  const BuiltScene b =
      build_scene(parse_scene(with("\"duration\": 1000", "\"duration\": 500"), ".", "t.json"), nullptr);
  std::vector<double> times;
  RunHooks hooks;
  hooks.on_frame = [&](const Simulation& sim, const RecordedFrame& f) {
    EXPECT_EQ(f.index, static_cast<Index>(times.size()));
    EXPECT_DOUBLE_EQ(f.time, sim.time());
    times.push_back(f.time);
  };
  const SceneResult r = run_scene(b, hooks);
  // every 100 updates = 50 ms, plus the rest state and the key time 495 ms
  std::vector<double> expected = {0};
  for (int k = 1; k <= 10; ++k) expected.push_back(50.0 * k);
  expected.insert(expected.end() - 1, 495.0);
  EXPECT_EQ(times, expected);
  EXPECT_EQ(r.trace.size(), 1001);  // the rest state + 1000 updates
  EXPECT_EQ(r.trace.node_disp.size(), 1u);
  EXPECT_EQ(r.trace.atom_disp.size(), 1u);
}

TEST(SceneRun, StaticResponseAtFullForceEqualsTheHeldDynamicState) {
  // 480 ms of hold with beta = 0.5/ms damping leaves the dynamic state at the static equilibrium.
  const BuiltScene b = build_scene(parse_scene(kKidney, ".", "t.json"), nullptr);
  const std::vector<StaticPoint> curve = static_response(b, 5);
  ASSERT_EQ(curve.size(), 5u);
  EXPECT_DOUBLE_EQ(curve.front().contact_mm, 0.0);
  EXPECT_DOUBLE_EQ(curve.back().force, 1.0);
  EXPECT_NEAR(curve.back().contact_mm, run_scene(b).summary.contact_hold_mm, 1e-3);
  for (std::size_t k = 1; k < curve.size(); ++k) EXPECT_GT(curve[k].contact_mm, curve[k - 1].contact_mm);
}

TEST(SceneRun, LocalDeformationOnTheVesselDentsByTheReferenceValueOfSection6_6) {
  const BuiltScene b = build_scene(parse_scene(R"({"model": {"kind": "smrm", "source": {"phantom": "vessel"}},
                      "loads": [{"ring": 20, "spoke": 0, "direction": "inward_normal", "magnitude": 0.05,
                                 "t_release": 100}],
                      "duration": 150, "local": {"enabled": true}, "record": {"frames": false}})",
                                               ".", "t.json"),
                                   nullptr);
  const SceneResult r = run_scene(b);
  EXPECT_NEAR(r.summary.local_hold_mm, 39.0 / 172.0 * 0.05 / 0.05, 1e-9);  // §6.6, k_loc = 0.05 N/mm
  EXPECT_TRUE(r.frames.empty());
  EXPECT_DOUBLE_EQ(r.trace.local_contact.back(), 0.0);  // released: U = 0 at once (§6.5)
}

}  // namespace
}  // namespace medspring
