// Tissue materials: presets, refusal of bad materials with the JSON path, calibrated stiffnesses scaled
// by the shear modulus, and the scene "material" block (models/tissue.hpp, scene/scene.hpp).
#include "medspring/models/tissue.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "medspring/core/error.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/scene.hpp"

namespace medspring {
namespace {

std::string tissue_error(const TissueMaterial& t) {
  try {
    check_tissue(t, "model.material");
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "";
}

std::string scene_with(const std::string& model_extra, const std::string& kind = "hybrid",
                       const std::string& phantom = "kidney") {
  return R"({"model": {"kind": ")" + kind + R"(", "source": {"phantom": ")" + phantom + "\"}" + model_extra +
         R"(}, "loads": [], "duration": 10})";
}

std::string parse_error(const std::string& text) {
  try {
    parse_scene(text, ".", "t.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Tissue, PresetsAreTheDocumentedLiteratureValues) {
  EXPECT_DOUBLE_EQ(tissue_preset("kidney").E_kPa, 10.0);
  EXPECT_DOUBLE_EQ(tissue_preset("kidney").nu, 0.45);
  EXPECT_DOUBLE_EQ(tissue_preset("aorta").E_kPa, 65.0);
  EXPECT_THROW(tissue_preset("liver"), InvalidInput);
}

TEST(Tissue, BadMaterialIsRefusedNamingTheKey) {
  EXPECT_NE(tissue_error({10.0, 0.5, ""}).find("model.material.nu"), std::string::npos);
  EXPECT_NE(tissue_error({10.0, 0.7, ""}).find("model.material.nu"), std::string::npos);
  EXPECT_NE(tissue_error({0.0, 0.45, ""}).find("model.material.E_kPa"), std::string::npos);
  EXPECT_NE(tissue_error({-3.0, 0.45, ""}).find("model.material.E_kPa"), std::string::npos);
  EXPECT_EQ(tissue_error({10.0, 0.49, ""}), "");
}

TEST(Tissue, ReferenceMaterialGivesTheCalibratedPhantomStiffnesses) {
  // `medspring calibrate --organ phantom --E-kPa 10 --nu 0.45` (docs/accuracy.md): k_surf 0.0118,
  // k_spoke 0.0088, k_cl 9.14, k_r 0.0221 N/mm (Duffing hybrid).
  HybridSettings s;
  apply_tissue(tissue_preset("kidney"), TissueOrgan::Phantom, s);
  EXPECT_NEAR(s.k_surf, 0.0118, 5e-5);
  EXPECT_NEAR(s.k_spoke, 0.0088, 5e-5);
  EXPECT_NEAR(s.k_cl, 9.14, 5e-3);
  EXPECT_NEAR(s.surface_node.return_k, 0.0221, 5e-5);
  EXPECT_DOUBLE_EQ(s.atom_node.return_k, s.surface_node.return_k);
}

TEST(Tissue, StiffnessesScaleWithTheShearModulus) {
  HybridSettings a, b;
  apply_tissue({10.0, 0.45, ""}, TissueOrgan::RealKidney, a);
  apply_tissue({25.0, 0.45, ""}, TissueOrgan::RealKidney, b);
  EXPECT_NEAR(b.k_surf / a.k_surf, 2.5, 1e-12);
  EXPECT_NEAR(b.k_cl / a.k_cl, 2.5, 1e-12);
  EXPECT_NEAR(b.surface_node.return_k / a.surface_node.return_k, 2.5, 1e-12);
  // nu 0.3 at the same E: mu = E / (2 (1 + nu)) is larger by 1.45 / 1.3.
  SurfaceBodyParams p, q;
  apply_tissue({10.0, 0.45, ""}, TissueOrgan::Phantom, p);
  apply_tissue({10.0, 0.3, ""}, TissueOrgan::Phantom, q);
  EXPECT_NEAR(q.k / p.k, 1.45 / 1.3, 1e-12);
  // The linear and Duffing calibrations are different fits.
  SurfaceBodyParams lin;
  lin.duffing.mode = DuffingMode::Linear;
  apply_tissue({10.0, 0.45, ""}, TissueOrgan::Phantom, lin);
  EXPECT_GT(std::abs(lin.k - p.k), 1.0);
}

TEST(Tissue, SmrmGetsTheWallModulus) {
  SmrmSettings s;
  apply_tissue(tissue_preset("aorta"), s);
  EXPECT_DOUBLE_EQ(s.wall.E, 0.065);  // MPa
}

TEST(SceneMaterial, PresetAndValuesResolveToTheCalibration) {
  HybridSettings expect;
  apply_tissue(tissue_preset("kidney"), TissueOrgan::Phantom, expect);
  const Scene a = parse_scene(scene_with(R"(, "material": "kidney")"), ".", "t.json");
  ASSERT_TRUE(a.model.material.has_value());
  EXPECT_DOUBLE_EQ(a.model.hybrid.k_surf, expect.k_surf);
  EXPECT_DOUBLE_EQ(a.model.hybrid.k_cl, expect.k_cl);
  const Scene b = parse_scene(scene_with(R"(, "material": {"E_kPa": 20, "nu": 0.45})"), ".", "t.json");
  EXPECT_NEAR(b.model.hybrid.k_surf / a.model.hybrid.k_surf, 2.0, 1e-12);
  // "parameters" override the material's values.
  const Scene c =
      parse_scene(scene_with(R"(, "material": "kidney", "parameters": {"k_surf": 0.07})"), ".", "t.json");
  EXPECT_DOUBLE_EQ(c.model.hybrid.k_surf, 0.07);
  EXPECT_DOUBLE_EQ(c.model.hybrid.k_cl, expect.k_cl);
  // SMRM: the aorta preset sets the wall modulus.
  const Scene v =
      parse_scene(scene_with(R"(, "material": {"preset": "aorta"})", "smrm", "vessel"), ".", "t.json");
  EXPECT_DOUBLE_EQ(v.model.smrm.wall.E, 0.065);
  // What was run round-trips.
  const Scene again = parse_scene(scene_to_json(b), ".", "again.json");
  EXPECT_DOUBLE_EQ(again.model.hybrid.k_surf, b.model.hybrid.k_surf);
  ASSERT_TRUE(again.model.material.has_value());
  EXPECT_DOUBLE_EQ(again.model.material->E_kPa, 20.0);
}

TEST(SceneMaterial, StifferMaterialBuildsAStifferBody) {
  const BuiltScene soft =
      build_scene(parse_scene(scene_with(R"(, "material": "kidney")"), ".", "t.json"), nullptr);
  const BuiltScene hard =
      build_scene(parse_scene(scene_with(R"(, "material": {"E_kPa": 30})"), ".", "t.json"), nullptr);
  ASSERT_EQ(soft.body->model().num_nodes(), hard.body->model().num_nodes());
  const Springs& a = soft.body->model().springs;
  const Springs& b = hard.body->model().springs;
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 0);
  for (std::size_t i = 0; i < a.k.size(); ++i) {
    EXPECT_NEAR(b.k[i] / a.k[i], 3.0, 1e-9);
    EXPECT_NEAR(b.kp[i] / a.kp[i], 3.0, 1e-9);  // Duffing k' = k eta / L0^2 scales with k
  }
}

TEST(SceneMaterial, BadMaterialIsRefusedWithItsPath) {
  EXPECT_NE(parse_error(scene_with(R"(, "material": {"E_kPa": 10, "nu": 0.5})")).find("model.material.nu"),
            std::string::npos);
  EXPECT_NE(parse_error(scene_with(R"(, "material": {"E_kPa": 0})")).find("model.material.E_kPa"),
            std::string::npos);
  EXPECT_NE(parse_error(scene_with(R"(, "material": {"E_kPa": -5, "nu": 0.4})")).find("must be > 0"),
            std::string::npos);
  EXPECT_NE(parse_error(scene_with(R"(, "material": {"nu": 0.4})")).find("model.material.E_kPa: is required"),
            std::string::npos);
  EXPECT_NE(parse_error(scene_with(R"(, "material": "liver")")).find("model.material"), std::string::npos);
  EXPECT_NE(parse_error(scene_with(R"(, "material": {"E_kPa": 10, "G": 3})")).find("model.material.G"),
            std::string::npos);
}

}  // namespace
}  // namespace medspring
