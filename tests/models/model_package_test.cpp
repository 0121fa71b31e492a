// Model packages: exact round trips for the three kinds, every malformed byte string refused, tissue
// parameters applied to the rebuilt model.
#include "medspring/models/model_package.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <random>

#include "medspring/core/binary.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring {
namespace {

BodyPtr surface_tube() {
  SurfaceBodyParams p;
  p.fixed = {0, 1, 2};
  return std::make_shared<SurfaceBody>(tube(8, 10, 2.5, 3.0), p, "tube", GridLayout{8, 10});
}
BodyPtr kidney() {
  return std::make_shared<HybridKidney>(hybrid_kidney_phantom());
}
BodyPtr vessel() {
  return std::make_shared<SmrmVessel>(smrm_phantom(VesselPath::Arc, CrossSectionShape::NonPlanar));
}
// A Y-shaped vessel tree (issue 17): trunk 0-1-2-3, branches 3-4-5-6 and 3-7-8-9, radii tapering.
BodyPtr vessel_tree() {
  MatX3 X(10, 3);
  X << 0, 0, 0, 5, 0, 0, 10, 0, 0, 15, 0, 0, 20, 3, 0, 25, 6, 0, 30, 9, 0, 20, -3, 1, 25, -6, 2, 30, -9, 3;
  VecX r(10);
  r << 2.0, 2.0, 1.9, 1.8, 1.5, 1.4, 1.3, 1.2, 1.1, 1.0;
  return std::make_shared<SmrmTree>(tree_from_parents(X, {-1, 0, 1, 2, 3, 4, 5, 3, 7, 8}, r),
                                    SmrmTreeSettings{.vessel = {.atoms = 9, .spokes = 12}});
}

// The small models of the committed version-4 packages (tests/models/data/*_v4.msm, written by the
// field-by-field writer before the settings went through their declarations): every setting away from
// its default, so that a field read into the wrong place shows.
SurfaceBodyParams v4_surface_params() {
  SurfaceBodyParams p;
  p.node = {0.4, 0.6, 0.03};
  p.k = 0.07;
  p.duffing = {DuffingMode::Absolute, 1.5, 12.0, true};
  p.fixed = {0, 2, 5};
  return p;
}
BodyPtr v4_surface() {
  return std::make_shared<SurfaceBody>(tube(4, 6, 2.5, 3.0), v4_surface_params(), "v4 tube",
                                       GridLayout{4, 6});
}
SmrmSettings v4_smrm_settings() {
  SmrmSettings s;
  s.atoms = 5;
  s.spokes = 6;
  s.frames.mode = FrameMode::RMF;
  s.frames.anchor = FrameAnchor::OneEnd;
  s.chain.k = 0.25;
  s.chain.kr = 0.03;
  s.chain.mass = 0.6;
  s.chain.beta = 0.4;
  s.chain.nonlinear = !s.chain.nonlinear;
  s.chain.duffing = {DuffingMode::Absolute, 1.5, 12.0, false};
  s.chain.fix_first = true;
  s.chain.fix_last = false;
  s.chain.kb = 0.01;
  s.k_loc = 0.07;
  s.dedup_tolerance = 2e-3;
  s.max_radius_factor = 2.5;
  s.bending = BendingMode::Constant;
  s.wall = {0.9, 0.2};
  return s;
}
BodyPtr v4_vessel() {
  return std::make_shared<SmrmVessel>(
      smrm_phantom(VesselPath::Arc, CrossSectionShape::Elliptical, v4_smrm_settings()));
}

// 200 updates with a force on node 5 ramped in and released: the final surface.
MatX3 run(const BodyPtr& body) {
  Simulation sim(body);
  PointLoad L;
  L.node = 5;
  L.force = Vec3(0.0, 0.0, -0.3);
  L.t_ramp = 10;
  L.t_release = 60;
  sim.set_loads({L});
  for (int k = 0; k < 200; ++k) sim.update();
  return sim.surface();
}

class RoundTrip : public ::testing::TestWithParam<int> {
 protected:
  BodyPtr body() const {
    switch (GetParam()) {
      case 0:
        return surface_tube();
      case 1:
        return kidney();
      case 2:
        return vessel();
      default:
        return vessel_tree();
    }
  }
};

TEST_P(RoundTrip, RebuildsTheSameModelBitForBit) {
  const BodyPtr a = body();
  const ModelPackage p = package_of(*a, "name", "one line");
  const std::string bytes = encode_model_package(p);
  const ModelPackage q = decode_model_package(bytes);
  EXPECT_EQ(q.name, "name");
  EXPECT_EQ(q.description, "one line");
  EXPECT_EQ(q.kind, a->kind());
  const BodyPtr b = make_body(q);
  EXPECT_EQ(b->kind(), a->kind());
  EXPECT_TRUE(check_fingerprint(q, *b));
  EXPECT_EQ(model_fingerprint(b->model()), model_fingerprint(a->model()));
  EXPECT_EQ(b->rest_surface(), a->rest_surface());
  EXPECT_EQ(b->faces(), a->faces());
  EXPECT_EQ(b->grid().rings, a->grid().rings);
  EXPECT_EQ(run(b), run(a));                  // exact: same model, same arithmetic
  EXPECT_EQ(encode_model_package(q), bytes);  // decode . encode is the identity
}

std::string kind_name(const ::testing::TestParamInfo<int>& p) {
  return p.param == 0 ? "surface" : p.param == 1 ? "hybrid" : p.param == 2 ? "smrm" : "smrm_tree";
}
INSTANTIATE_TEST_SUITE_P(Kinds, RoundTrip, ::testing::Values(0, 1, 2, 3), kind_name);

TEST(ModelPackage, VesselTreeKeepsItsBranchesAndRefusesABadOne) {
  const BodyPtr a = vessel_tree();
  ModelPackage p = package_of(*a, "Y");
  ASSERT_EQ(p.tree.branches.size(), 3u);
  EXPECT_EQ(p.tree.branches[2].parent, 0);
  EXPECT_EQ(p.smrm.atoms, 9);
  const BodyPtr rebuilt = make_body(decode_model_package(encode_model_package(p)));
  const auto& tree = dynamic_cast<const SmrmTree&>(*rebuilt);
  EXPECT_EQ(tree.num_branches(), 3);
  EXPECT_EQ(tree.num_junctions(), 1);
  // Tissue parameters act on the tree's chain like on a vessel's.
  TissueParams t = tissue_params(p);
  EXPECT_EQ(t.k, p.smrm.chain.k);
  t.k *= 3;
  set_tissue_params(p, t);
  EXPECT_EQ(make_body(p)->model().springs.k[0], 3 * a->model().springs.k[0]);
  EXPECT_EQ(p.fingerprint, 0u);  // no longer the model it was saved from
  // A branch whose parent is not an earlier branch is refused while decoding, naming it.
  p.tree.branches[1].parent = 2;
  try {
    decode_model_package(encode_model_package(p), "Y.msm");
    ADD_FAILURE() << "accepted a forward parent";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("tree branch 1: parent 2"), std::string::npos) << e.what();
  }
  // Branches that do not meet: decoded, then refused by the constructor, naming the package.
  p.tree.branches[1].parent = 0;
  p.tree.branches[1].line.points(0, 1) += 1.0;
  try {
    make_body(decode_model_package(encode_model_package(p), "Y.msm"));
    ADD_FAILURE() << "accepted branches that do not meet";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("model package 'Y'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("branch 1"), std::string::npos) << e.what();
  }
}

TEST(ModelPackage, FileIsWrittenAtomicallyAndReadBack) {
  const auto path = std::filesystem::temp_directory_path() / "medspring_package_test.msm";
  const ModelPackage p = package_of(*kidney(), "kidney");
  save_model_package(path, p);
  const ModelPackage q = read_model_package(path);
  EXPECT_EQ(encode_model_package(q), encode_model_package(p));
  std::filesystem::remove(path);
  EXPECT_THROW(read_model_package(path), IoError);
}

TEST(ModelPackage, EveryTruncationIsRefusedWithIoError) {
  for (const BodyPtr& body : {vessel(), vessel_tree()}) {
    const std::string bytes = encode_model_package(package_of(*body));
    for (std::size_t n = 0; n < bytes.size(); n += 1 + n / 7) {
      try {
        decode_model_package(std::string_view(bytes).substr(0, n), "pkg");
        ADD_FAILURE() << "accepted " << n << " of " << bytes.size() << " bytes";
      } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("pkg: "), std::string::npos) << e.what();
      }
    }
  }
}

TEST(ModelPackage, FlippedBytesAreCaughtByTheChecksum) {
  const std::string bytes = encode_model_package(package_of(*surface_tube()));
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::string b = bytes;
    const std::size_t at = kFrameHeaderSize + rng() % (b.size() - kFrameHeaderSize);
    b[at] = static_cast<char>(b[at] ^ (1 + rng() % 255));
    EXPECT_THROW(decode_model_package(b), IoError) << "byte " << at;
  }
}

TEST(ModelPackage, BadMagicVersionAndTrailingBytes) {
  std::string b = encode_model_package(package_of(*surface_tube()));
  std::string m = b;
  m[0] = 'X';
  try {
    decode_model_package(m, "f.msm");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("bad magic"), std::string::npos);
  }
  std::string v = b;
  v[8] = static_cast<char>(kModelPackageVersion + 1);  // a newer writer's version
  EXPECT_THROW(decode_model_package(v), IoError);
  EXPECT_THROW(decode_model_package(b + "x"), IoError);
}

TEST(ModelPackage, OutOfRangeFaceIndexNamesTheFace) {
  ModelPackage p = package_of(*surface_tube());
  p.surface.F(3, 1) = 10000;
  const std::string bytes = encode_model_package(p);
  try {
    decode_model_package(bytes, "t.msm");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("face 3"), std::string::npos) << e.what();
  }
}

TEST(ModelPackage, OutOfRangeFixedNodeAndUnknownParameterAreNamed) {
  ModelPackage p = package_of(*surface_tube());
  p.surface_params.fixed = {0, 1, 100000};
  try {
    decode_model_package(encode_model_package(p), "t.msm");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("fixed[2]: index 100000 out of range"), std::string::npos)
        << e.what();
  }
  // a field this build does not declare (a newer writer's): refused by name. The first declared
  // surface field is "mass"; rename it in the payload and re-frame.
  const std::string bytes = encode_model_package(package_of(*surface_tube()));
  std::string payload = bytes.substr(kFrameHeaderSize);
  const std::string key = std::string("\x04\0\0\0", 4) + "mass";
  const std::size_t at = payload.find(key);
  ASSERT_NE(at, std::string::npos);
  payload.replace(at + 4, 4, "mast");
  try {
    decode_model_package(frame_payload(kModelPackageMagic, kModelPackageVersion, payload), "n.msm");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown parameter 'mast'"), std::string::npos) << e.what();
  }
}

/// Every declared field of p as "name=value" lines.
template <ParamStruct T>
std::string settings_text(const T& p) {
  std::string out;
  for_each_field(p, [&](const ParamSpec& s, const auto& f) {
    using F = std::remove_cvref_t<decltype(f)>;
    if constexpr (ParamStruct<F>)
      out += cat(s.name, ".{", settings_text(f), "}\n");
    else
      out += cat(s.name, "=", param_value_text(f), "\n");
  });
  return out;
}

TEST(ModelPackage, Version4PackagesStillRead) {
  // tests/models/data/*_v4.msm: written by the version-4 writer (the surface and SMRM settings field by
  // field, in a fixed order) from v4_surface() and v4_vessel() above.
  const std::filesystem::path dir = MEDSPRING_SOURCE_DIR "/tests/models/data";
  struct Case {
    const char* file;
    BodyPtr body;
  };
  for (const Case& c : {Case{"surface_v4.msm", v4_surface()}, Case{"smrm_v4.msm", v4_vessel()}}) {
    SCOPED_TRACE(c.file);
    const std::string bytes = read_file_bytes(dir / c.file, "model package");
    ASSERT_EQ(static_cast<unsigned char>(bytes[8]), 4u) << "the fixture is a version-4 package";
    const ModelPackage old = decode_model_package(bytes, c.file);
    const ModelPackage now = package_of(*c.body);
    EXPECT_EQ(old.kind, now.kind);
    EXPECT_EQ(settings_text(old.surface_params), settings_text(now.surface_params));
    EXPECT_EQ(settings_text(old.smrm), settings_text(now.smrm));
    EXPECT_EQ(old.smrm.atoms, now.smrm.atoms);
    EXPECT_EQ(old.smrm.chain.nonlinear, now.smrm.chain.nonlinear);
    const BodyPtr rebuilt = make_body(old);
    EXPECT_EQ(model_fingerprint(rebuilt->model()), model_fingerprint(c.body->model()));
    EXPECT_EQ(run(rebuilt), run(c.body));
    // written again, it is a version-5 package with the same settings
    const std::string again = encode_model_package(old);
    EXPECT_EQ(static_cast<unsigned char>(again[8]), kModelPackageVersion);
    const ModelPackage back = decode_model_package(again);
    EXPECT_EQ(settings_text(back.surface_params), settings_text(now.surface_params));
    EXPECT_EQ(settings_text(back.smrm), settings_text(now.smrm));
  }
  // the fixtures' settings are not the defaults (a field read into the wrong place would show)
  EXPECT_NE(settings_text(v4_surface_params()), settings_text(SurfaceBodyParams{}));
  EXPECT_NE(settings_text(v4_smrm_settings()), settings_text(SmrmSettings{}));
}

TEST(ModelPackage, InvalidContentsAreRefusedByMakeBody) {
  ModelPackage p = package_of(*kidney(), "k");
  p.hybrid.k_surf = -1;
  const ModelPackage q = decode_model_package(encode_model_package(p));
  try {
    make_body(q);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("model package 'k'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("k_surf"), std::string::npos) << e.what();
  }
  ModelPackage nan = package_of(*vessel(), "v");
  nan.atoms(4, 1) = std::nan("");
  EXPECT_THROW(make_body(decode_model_package(encode_model_package(nan))), InvalidInput);
  // a NaN surface offset (found by fuzz_model_package: the node reconstructed as NaN at rest)
  ModelPackage offset = package_of(*vessel(), "v");
  offset.binding.offset(40, 1) = std::nan("");
  try {
    make_body(decode_model_package(encode_model_package(offset)));
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("binding offset of surface node[40]"), std::string::npos)
        << e.what();
  }
}

TEST(TissueParams, ScaleTheSpringsAndSwitchTheLaw) {
  for (const BodyPtr& body : {surface_tube(), kidney(), vessel()}) {
    ModelPackage p = package_of(*body);
    const TissueParams t0 = tissue_params(p);
    EXPECT_GT(t0.k, 0.0);
    EXPECT_TRUE(t0.nonlinear);
    TissueParams t = t0;
    t.k *= 2;
    t.kr = 0.05;
    t.beta = 0.25;
    set_tissue_params(p, t);
    const BodyPtr stiff = make_body(p);
    const Springs& S0 = body->model().springs;
    const Springs& S1 = stiff->model().springs;
    ASSERT_EQ(S0.size(), S1.size());
    for (std::size_t s = 0; s < S0.k.size(); ++s) {
      EXPECT_NEAR(S1.k[s], 2 * S0.k[s], 1e-15) << body->kind() << " spring " << s;
      EXPECT_NEAR(S1.kp[s], 2 * S0.kp[s], 1e-12 * std::abs(S0.kp[s]) + 1e-300);
    }
    const Model& m = stiff->model();
    for (Index i = 0; i < m.num_nodes(); ++i) {
      EXPECT_DOUBLE_EQ(m.kr[i], 0.05);
      EXPECT_NEAR(m.damping[i], 0.25 * m.mass[i], 1e-15);
    }
    EXPECT_FALSE(check_fingerprint(p, *stiff) && p.fingerprint != 0);
    t.nonlinear = false;
    set_tissue_params(p, t);
    const BodyPtr linear = make_body(p);  // held: a range-for over make_body(p)->... would dangle
    for (double kp : linear->model().springs.kp) EXPECT_EQ(kp, 0.0);
    t.nonlinear = true;
    set_tissue_params(p, t);
    const BodyPtr nonlinear = make_body(p);
    for (std::size_t s = 0; s < S0.kp.size(); ++s)
      EXPECT_NEAR(nonlinear->model().springs.kp[s], 2 * S0.kp[s], 1e-12 * std::abs(S0.kp[s]) + 1e-300);
  }
}

TEST(TissueParams, InvalidValuesAreRefusedByName) {
  ModelPackage p = package_of(*surface_tube());
  TissueParams t = tissue_params(p);
  t.k = -1;
  EXPECT_THROW(set_tissue_params(p, t), InvalidInput);
  t = tissue_params(p);
  t.beta = std::nan("");
  try {
    set_tissue_params(p, t);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("beta"), std::string::npos);
  }
}

}  // namespace
}  // namespace medspring
