// Model packages: exact round trips for the three kinds, every malformed byte string refused, tissue
// parameters applied to the rebuilt model.
#include "medspring/models/model_package.hpp"

#include <gtest/gtest.h>

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
  v[8] = 9;
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
