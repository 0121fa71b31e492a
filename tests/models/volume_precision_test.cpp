// The volumetric kind's volume_precision across files (issue 23, docs/volumetric-speed.md "Float as the
// default"): float is the default since h23b; a model package written before (version 9 and earlier, which
// did not store the setting) reads double, as it was run, and a checkpoint resumes only with the precision it
// was saved with (the model fingerprint covers it), bit for bit.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>

#include "medspring/core/binary.hpp"
#include "medspring/core/error.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/sim/checkpoint.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring {
namespace {

// tests/models/data/volumetric_v9.msm: written by the version-9 writer (main 85eae49, double the default,
// volume_precision not stored) from tests/models/data/ball_v9.json (a 42-vertex ball of radius 10 mm,
// `nodes` 60): `medspring export ball_v9.json --out DIR`. 42 surface nodes, 60 nodes.
ModelPackage v9_package() {
  const std::filesystem::path file = MEDSPRING_SOURCE_DIR "/tests/models/data/volumetric_v9.msm";
  const std::string bytes = read_file_bytes(file, "model package");
  EXPECT_EQ(static_cast<unsigned char>(bytes[8]), 9u) << "the fixture is a version-9 package";
  return decode_model_package(bytes, file.string());
}

BodyPtr with_precision(ModelPackage p, VolumePrecision precision) {
  p.volumetric.volume_precision = precision;
  p.fingerprint = 0;
  return make_body(p);
}

template <class M>
bool same_bits(const M& a, const M& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

// 2 ms frames (several sub-steps each, so the float pass serves all but the last), 0.05 N on a surface node.
SimulationSettings run_settings() {
  SimulationSettings st;
  st.step.dt = 2.0;
  return st;
}
std::vector<PointLoad> run_loads() {
  return {{.node = 5, .force = Vec3(0, 0, -0.05), .t_ramp = 10}};
}

TEST(VolumePrecision, FloatIsTheDefaultAndDoubleStaysSelectable) {
  EXPECT_EQ(VolumetricSettings{}.volume_precision, VolumePrecision::Float);
  const ModelPackage p = v9_package();
  EXPECT_TRUE(with_precision(p, VolumePrecision::Float)->model().volume_f32 != nullptr);
  EXPECT_TRUE(with_precision(p, VolumePrecision::Double)->model().volume_f32 == nullptr);
}

TEST(VolumePrecision, Version9PackageStillReadsDoubleAsItWasRun) {
  const ModelPackage p = v9_package();
  ASSERT_EQ(p.kind, "volumetric");
  ASSERT_EQ(p.volumetric_mesh.X.rows(), 60);
  EXPECT_EQ(p.volumetric.volume_precision, VolumePrecision::Double);  // not the new default
  const BodyPtr body = make_body(p);
  EXPECT_TRUE(body->model().volume_f32 == nullptr);
  // The fixture's stored fingerprint is a hash of the model's bits as the writer's build (g++ -O3) computed
  // them; another compiler or flags (the sanitized clang -O1 tree) can round the rest lengths differently,
  // so the fingerprint is checked on a version-9 package written here: the version-10 payload of the double
  // model without its precision (the i64 before the trailing fingerprint), framed as version 9.
  const std::string v10 = encode_model_package(package_of(*body, "ball"));
  std::string payload(unframe_payload(v10, kModelPackageMagic, kModelPackageMinVersion, kModelPackageVersion,
                                      "model package", "test"));
  payload.erase(payload.size() - 16, 8);
  const ModelPackage p9 = decode_model_package(frame_payload(kModelPackageMagic, 9, payload), "ball_v9.msm");
  EXPECT_EQ(p9.volumetric.volume_precision, VolumePrecision::Double);
  EXPECT_TRUE(check_fingerprint(p9, *make_body(p9)));  // the model it was written from
  // the same package read as the new default would be another model: the fingerprint says so
  EXPECT_FALSE(check_fingerprint(p9, *with_precision(p9, VolumePrecision::Float)));
  // written again, it is a version-10 package that still says double
  const std::string again = encode_model_package(p);
  EXPECT_EQ(static_cast<unsigned char>(again[8]), kModelPackageVersion);
  EXPECT_EQ(decode_model_package(again).volumetric.volume_precision, VolumePrecision::Double);
}

TEST(VolumePrecision, Version10PackageStoresEitherPrecision) {
  const ModelPackage old = v9_package();
  for (const VolumePrecision prec : {VolumePrecision::Float, VolumePrecision::Double}) {
    SCOPED_TRACE(to_string(prec));
    const BodyPtr body = with_precision(old, prec);
    const ModelPackage p = decode_model_package(encode_model_package(package_of(*body, "ball")), "test");
    EXPECT_EQ(p.volumetric.volume_precision, prec);
    const BodyPtr again = make_body(p);
    EXPECT_EQ(again->model().volume_f32 != nullptr, prec == VolumePrecision::Float);
    EXPECT_TRUE(check_fingerprint(p, *again));
  }
  // a stored value that is neither is refused by name
  std::string bytes = encode_model_package(package_of(*with_precision(old, VolumePrecision::Float), "ball"));
  const std::string_view payload = unframe_payload(bytes, kModelPackageMagic, kModelPackageMinVersion,
                                                   kModelPackageVersion, "model package", "test");
  std::string edited(payload);
  const std::size_t at = edited.size() - 16;  // the precision (i64) sits before the fingerprint (u64)
  ASSERT_EQ(edited[at], 1);                   // float
  edited[at] = 7;
  try {
    decode_model_package(frame_payload(kModelPackageMagic, kModelPackageVersion, edited), "edited");
    FAIL() << "no exception";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("volume_precision: 7"), std::string::npos) << e.what();
  }
}

// A checkpoint resumes with the precision it was saved with: into a simulation of the same mesh and settings
// in the other precision it is refused, naming volume_precision (the two runs differ: the float pass ran);
// into its own precision, the resumed run equals the uninterrupted one bit for bit.
TEST(VolumePrecision, CheckpointResumesOnlyWithItsOwnPrecisionBitForBit) {
  const ModelPackage p = v9_package();
  const VolumePrecision both[] = {VolumePrecision::Double, VolumePrecision::Float};
  Simulation runs[2] = {Simulation(with_precision(p, both[0]), run_settings()),
                        Simulation(with_precision(p, both[1]), run_settings())};
  for (Simulation& s : runs) {
    s.set_loads(run_loads());
    s.advance(10);
  }
  ASSERT_GT(runs[1].state().substeps, 2 * runs[1].state().frames);  // the float pass served sub-steps
  EXPECT_GT((runs[0].state().x - runs[1].state().x).cwiseAbs().maxCoeff(), 0.0);  // and changed the run
  for (int k = 0; k < 2; ++k) {
    SCOPED_TRACE(to_string(both[k]));
    const Checkpoint c = decode_checkpoint(encode_checkpoint(make_checkpoint(runs[k])));
    runs[k].advance(20);
    Simulation other(with_precision(p, both[1 - k]), run_settings());
    try {
      apply_checkpoint(c, other);
      FAIL() << "resumed in the other precision";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("volume_precision"), std::string::npos) << e.what();
    }
    Simulation same(with_precision(p, both[k]), run_settings());
    apply_checkpoint(c, same);
    same.advance(20);
    EXPECT_TRUE(same_bits(same.state().x, runs[k].state().x));
    EXPECT_TRUE(same_bits(same.state().v, runs[k].state().v));
    EXPECT_EQ(same.state().substeps, runs[k].state().substeps);
    EXPECT_GT((same.state().x - same.model().x0).norm(), 1e-3);  // the run moved
  }
}

}  // namespace
}  // namespace medspring
