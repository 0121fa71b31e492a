// `medspring accuracy --quick` end to end (docs/accuracy.md): the FEM validation at level 1, the kidney
// phantom against CalculiX at two sites, calibration, the report, JSON and figures; bad input refused.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;

int run(const std::string& args, std::string* err = nullptr) {
  const fs::path dir = medspring::testing::temp_dir("accuracy-cli-io");
  // a private FEM cache: the test solves with CalculiX and leaves the user's cache alone
  const std::string cmd = "MEDSPRING_FEM_CACHE='" + (dir / "fem-cache").string() + "' '" +
                          std::string(MEDSPRING_EXE) + "' " + args + " > '" + (dir / "out").string() +
                          "' 2> '" + (dir / "err").string() + "'";
  const int status = std::system(cmd.c_str());
  if (err) {
    std::ifstream in(dir / "err");
    std::stringstream ss;
    ss << in.rdbuf();
    *err = ss.str();
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TEST(CliAccuracy, QuickRunWritesTablesJsonAndFiguresWithValidatedFem) {
  const fs::path out = medspring::testing::temp_dir("accuracy-quick") / "acc";
  ASSERT_EQ(run("accuracy --quick --quiet --out '" + out.string() + "'", nullptr), 0);
  for (const char* f : {"accuracy.md", "accuracy.json", "figures/speed_accuracy.png"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  std::ifstream in(out / "accuracy.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  for (const auto& v : j["validation"]) EXPECT_LT(v["rel_error"].get<double>(), 0.05) << v.dump();
  ASSERT_EQ(j["organs"].size(), 1u);
  const auto& o = j["organs"][0];
  EXPECT_GT(o["fem"]["nodes"].get<int>(), 1000);
  // the strain the FEM reaches, per solved case (docs/accuracy-nonlinear.md, "Large strain"): nominal =
  // contact displacement / thickness; the peak element strain lies above it
  ASSERT_EQ(o["fem"]["strain"].size(), 2u);  // --quick: 2 sites at 0.5 N
  for (const auto& c : o["fem"]["strain"]) {
    const double nominal = c["nominal_strain_pct"].get<double>();
    EXPECT_NEAR(nominal, 100 * c["contact_mm"].get<double>() / o["fem"]["thickness_mm"].get<double>(), 1e-9);
    EXPECT_GT(nominal, 0.0);
    EXPECT_GT(c["peak_compressive_strain_pct"].get<double>(), nominal) << c.dump();
  }
  ASSERT_EQ(o["models"].size(), 16u);  // 8 kinds (6 + volumetric linear, Duffing) x (default, calibrated)
  for (const auto& m : o["models"]) {
    EXPECT_GT(m["update_us"].get<double>(), 0.0);
    for (const auto& c : m["cases"]) {
      if (c.contains("error")) {  // a model with no static equilibrium is reported, never a hybrid one here
        EXPECT_EQ(m["base"], "surface") << c.dump();
        continue;
      }
      EXPECT_TRUE(std::isfinite(c["rms_mm"].get<double>()));
      EXPECT_GT(c["contact_fem_mm"].get<double>(), 0.0);
      // the disk-mean read-out (docs/accuracy-nonlinear.md, "The load site"): every scored case has one
      const double dm = c.value("disk_mean_error_pct", -1.0);
      EXPECT_TRUE(std::isfinite(dm) && dm >= 0.0 && dm < 1000.0) << c.dump();
    }
  }
  // calibration lowers the training error of the hybrid model (the fit minimises it)
  double train_default = -1, train_cal = -1;
  for (const auto& m : o["models"])
    if (m["kind"] == "hybrid (Duffing)")
      for (const auto& c : m["cases"])
        if (c["train"].get<bool>())
          (m["calibrated"].get<bool>() ? train_cal : train_default) = c["rms_mm"].get<double>();
  EXPECT_GT(train_default, 0.0);
  EXPECT_LT(train_cal, train_default);

  // the vessel: the SMRM centerline against the FEM wall (a 12-atom straight phantom in --quick)
  ASSERT_EQ(j["vessels"].size(), 1u);
  const auto& v = j["vessels"][0];
  EXPECT_EQ(v["atoms"].get<int>(), 12);
  EXPECT_EQ(v["fem_failed"].size(), 0u);
  ASSERT_EQ(v["models"].size(), 6u);  // linear, Duffing x (default, material, calibrated)
  double v_default = -1, v_cal = -1;
  for (const auto& m : v["models"])
    for (const auto& c : m["cases"]) {
      ASSERT_FALSE(c.contains("error")) << c.dump();
      EXPECT_GT(c["loaded_fem_mm"].get<double>(), 0.0);
      EXPECT_TRUE(std::isfinite(c["rms_mm"].get<double>()));
      EXPECT_GE(c["max_mm"].get<double>(), c["rms_mm"].get<double>());
      if (c["train"].get<bool>() && m["kind"] == "SMRM (linear)") {
        if (m["params"] == "material") v_default = c["rms_mm"].get<double>();
        if (m["params"] == "calibrated") v_cal = c["rms_mm"].get<double>();
      }
    }
  EXPECT_GT(v_default, 0.0);
  EXPECT_LT(v_cal, v_default);  // the fit lowers its own training error
}

TEST(CliAccuracy, ImpossibleMaterialIsRefusedWithOneLineAndNothingWritten) {
  const fs::path out = medspring::testing::temp_dir("accuracy-bad") / "acc";
  std::string err;
  EXPECT_NE(run("accuracy --quick --nu 0.5 --out '" + out.string() + "'", &err), 0);
  EXPECT_NE(err.find("nu must be in (-1, 0.5)"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_NE(run("accuracy --quick --E-kPa -3 --out '" + out.string() + "'", &err), 0);
  EXPECT_NE(err.find("E must be > 0"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
  // the calibration's site read-out and training loads (docs/accuracy-calibration.md), refused before a solve
  EXPECT_NE(run("accuracy --quick --site-readout centre --out '" + out.string() + "'", &err), 0);
  EXPECT_NE(err.find("--site-readout must be node or disk-mean (got 'centre')"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_NE(run("calibrate --organ phantom --kind volumetric --train-force 0.5,x", &err), 0);
  EXPECT_NE(err.find("--train-force must be > 0 N or a list of such (got 'x')"), std::string::npos) << err;
  EXPECT_NE(run("calibrate --organ phantom --kind volumetric --train-sites 0,4", &err), 0);
  EXPECT_NE(err.find("calibrate: --train-sites: '4' is not a site index in [0, 3]"), std::string::npos)
      << err;
  EXPECT_NE(run("calibrate --organ phantom --kind volumetric --train-sites 1,1", &err), 0);
  EXPECT_NE(err.find("calibrate: --train-sites: site 1 is listed twice"), std::string::npos) << err;
  EXPECT_NE(run("accuracy --quick --train-sites 2 --out '" + out.string() + "'", &err), 0);
  EXPECT_NE(err.find("accuracy: --train-sites: '2' is not a site index in [0, 1]"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
  // the local overlay as a site family (docs/accuracy-calibration.md): the volumetric linear kind only
  EXPECT_NE(run("calibrate --organ phantom --kind surface --linear --local", &err), 0);
  EXPECT_NE(err.find("calibrate: --local needs --kind volumetric --linear (got --kind surface)"),
            std::string::npos)
      << err;
  EXPECT_NE(run("calibrate --organ phantom --kind volumetric --local", &err), 0);
  EXPECT_NE(err.find("(got --kind volumetric without --linear)"), std::string::npos) << err;
  EXPECT_NE(run("accuracy --quick --kinds volumetric-locale --out '" + out.string() + "'", &err), 0);
  EXPECT_NE(err.find("unknown kind 'volumetric-locale'"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
  // the thin-tetrahedron term's options, read through VolumetricSettings' declaration
  // (docs/volumetric-mesh.md)
  EXPECT_NE(run("calibrate --organ phantom --kind volumetric --thin-tet on", &err), 0);
  EXPECT_NE(err.find("calibrate: --thin-tet: thin_tet: "), std::string::npos) << err;
  EXPECT_NE(run("accuracy --quick --thin-tet-q-max 2 --out '" + out.string() + "'", &err), 0);
  EXPECT_NE(err.find("accuracy: --thin-tet-q-max: thin_tet_q_max: must be in (0, 1] (got 2)"),
            std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(out));
}

// The aorta as a solid organ (issue 23, docs/accuracy-volumetric.md "The aorta as a solid organ"): surface
// and volumetric kinds only (no skeleton for the hybrid kind), held by the facing bed + cut cap rule; the
// volumetric kind from E and nu alone within the 10 % RMS on the held-out site.
TEST(CliAccuracy, QuickAortaRunScoresTheVolumetricKindUnderItsSupportRule) {
  const fs::path out = medspring::testing::temp_dir("accuracy-aorta") / "acc";
  std::string err;
  ASSERT_EQ(
      run("accuracy --quick --quiet --organs aorta --kinds volumetric,volumetric-static,hybrid --nodes 1000 "
          "--no-validation "
          "--no-vessel --volume-term-variants --train-sites 1 --out '" +
              out.string() + "'",
          &err),
      0)
      << err;
  std::ifstream in(out / "accuracy.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  if (j["organs"].empty()) GTEST_SKIP() << "the aorta data file is not here: " << j["notes"].dump();
  const auto& o = j["organs"][0];
  EXPECT_EQ(o["organ"], "real aorta (solid)");
  EXPECT_EQ(o["support_rule"]["facing_deg"].get<double>(), 60.0);
  EXPECT_EQ(o["support_rule"]["caps"].size(), 1u);
  EXPECT_GT(o["support_nodes"].get<int>(), 50);
  EXPECT_LT(o["support_nodes"].get<int>(), 800 / 2);  // a bed, not the whole vessel
  EXPECT_NE(o["notes"].dump().find("hybrid kind left out"), std::string::npos) << o["notes"].dump();
  // volumetric (linear) and (linear static), default and calibrated; no hybrid row
  ASSERT_EQ(o["models"].size(), 4u);
  // --train-sites 1: the fit trains on the second site alone, the first is held out
  EXPECT_EQ(o["train_sites"], nlohmann::json::array({1}));
  for (const auto& m : o["models"]) {
    EXPECT_EQ(m["base"], "volumetric");
    for (const auto& c : m["cases"]) {
      if (c.contains("train")) {
        EXPECT_EQ(c["train"].get<bool>(), c["site"].get<int>() == 1) << c.dump();
      }
    }
    if (m["calibrated"].get<bool>()) continue;
    EXPECT_GT(m["held_out_mean_rms_pct"].get<double>(), 0.0);
    EXPECT_LT(m["held_out_mean_rms_pct"].get<double>(), 10.0);
  }
  // --volume-term-variants (docs/volumetric-mesh.md, "Locking and the nodal volume term"): the springs with
  // the per-tetrahedron term (beta = 1) and P1 are the small-strain diagnostic's own rows, solved again; the
  // nodal form (beta = 0) stores no more energy than the per-tetrahedron one, so it moves at least as far
  const auto& ss = o["volumetric"]["small_strain"];
  // the linear static kind (docs/linear-response.md) from E and nu is the small-strain diagnostic's springs
  int static_rows = 0;
  for (const auto& m : o["models"])
    if (m["kind"] == "volumetric (linear static)") {
      ++static_rows;
      if (!m["calibrated"].get<bool>()) {
        EXPECT_NEAR(m["held_out_mean_rms_pct"].get<double>(),
                    ss["held_out_mean_springs_linear_rms_pct"].get<double>(), 1e-6);
      }
    }
  EXPECT_EQ(static_rows, 2);
  const auto& vt = o["volumetric"]["volume_term_variants"]["variants"];
  ASSERT_EQ(vt.size(), 7u) << o["volumetric"].dump();
  EXPECT_EQ(vt[0]["model"], "springs");
  EXPECT_EQ(vt[0]["beta"].get<double>(), 1.0);
  EXPECT_NEAR(vt[0]["from_E_nu"]["rms_pct"].get<double>(),
              ss["held_out_mean_springs_linear_rms_pct"].get<double>(), 1e-6);
  EXPECT_NEAR(vt[0]["from_E_nu"]["disk_mean_pct"].get<double>(),
              ss["held_out_mean_springs_linear_disk_mean_pct"].get<double>(), 1e-6);
  EXPECT_EQ(vt[5]["model"], "P1");
  EXPECT_NEAR(vt[5]["from_E_nu"]["contact_pct"].get<double>(),
              ss["held_out_mean_p1_contact_pct"].get<double>(), 1e-6);
  EXPECT_EQ(vt[4]["beta"].get<double>(), 0.0);
  EXPECT_GE(vt[4]["from_E_nu"]["disk_mean_ratio"].get<double>(),
            vt[0]["from_E_nu"]["disk_mean_ratio"].get<double>() - 1e-9);
  for (const auto& v : vt) {
    EXPECT_FALSE(v.contains("error")) << v.dump();
    EXPECT_TRUE(v.contains("fit_node") && v.contains("fit_disk_mean")) << v.dump();
  }
  // an unknown organ is refused with the name, nothing written
  const fs::path bad = medspring::testing::temp_dir("accuracy-aorta-bad") / "acc";
  EXPECT_NE(run("accuracy --quick --organs aorta,liver --out '" + bad.string() + "'", &err), 0);
  EXPECT_NE(err.find("unknown organ 'liver'"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(bad));
  // the hybrid kind needs a skeleton: `calibrate` refuses it on the aorta before any solve
  EXPECT_NE(run("calibrate --organ aorta --kind hybrid", &err), 0);
  EXPECT_NE(err.find("no medial skeleton"), std::string::npos) << err;
}
