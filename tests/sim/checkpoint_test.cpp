#include "medspring/sim/checkpoint.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <random>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/surface_body.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;

BodyPtr kidney_body() {
  return std::make_shared<HybridKidney>(hybrid_kidney_phantom());
}
BodyPtr tube_body() {
  SurfaceBodyParams p;
  for (Index j = 0; j < 30; ++j) p.fixed.push_back(j);  // first ring pinned
  return std::make_shared<SurfaceBody>(tube(40, 30, 2.5, 3.0), p, "tube", GridLayout{40, 30});
}

// Bitwise equality of two matrices (NaN-safe, -0 != +0).
template <class M>
bool same_bits(const M& a, const M& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}
void write_bytes(const fs::path& p, const std::string& b) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(b.data(), static_cast<std::streamsize>(b.size()));
}

struct ResumeCase {
  const char* name;
  bool kidney;
  Integrator integrator;
  bool local;
};

class CheckpointResume : public ::testing::TestWithParam<ResumeCase> {};

TEST_P(CheckpointResume, ResumedRunIsBitIdenticalToTheUninterruptedRun) {
  const ResumeCase& rc = GetParam();
  SimulationSettings st;
  st.step.integrator = rc.integrator;
  st.local.enabled = rc.local;
  const Index node = rc.kidney ? 223 : 20 * 30 + 7;
  const Vec3 F = rc.kidney ? Vec3(0, 0, -1.0) : Vec3(0, -0.5, 0);
  // two loads; the save falls inside the first ramp, the release inside the resumed part
  const std::vector<PointLoad> loads = {{.node = node, .force = F, .t_ramp = 20, .t_release = 60},
                                        {.node = node + 3, .force = 0.5 * F, .t_on = 5, .t_release = 80}};
  Simulation a(rc.kidney ? kidney_body() : tube_body(), st);
  a.set_loads(loads);
  a.advance(25);  // t = 12.5 ms
  const fs::path file = testing::temp_dir("ckpt") / "run.mscp";
  save_checkpoint(file, a);
  a.advance(50);  // to t = 37.5 ms: under both loads
  const MatX3 a_mid = a.state().x;
  a.advance(150);  // to t = 112.5 ms: release and recovery included

  // resume into a fresh simulation of a freshly built model, with other step settings and no loads
  SimulationSettings other = st;
  other.step.dt = 0.25;
  other.step.integrator =
      rc.integrator == Integrator::ImplicitEuler ? Integrator::SymplecticEuler : Integrator::ImplicitEuler;
  Simulation b(rc.kidney ? kidney_body() : tube_body(), other);
  b.advance(3);
  restore_checkpoint(file, b);
  EXPECT_EQ(b.settings().step.dt, 0.5);
  EXPECT_EQ(b.settings().step.integrator, rc.integrator);
  EXPECT_EQ(b.loads().size(), 2u);
  EXPECT_EQ(b.time(), 12.5);
  b.advance(50);
  EXPECT_TRUE(same_bits(a_mid, b.state().x));
  // the run moved: the comparison is not between two rest states (the linear static response is back at
  // rest exactly once the loads are released)
  EXPECT_GT((a_mid - a.model().x0).norm(), 1e-3);
  b.advance(150);

  EXPECT_TRUE(same_bits(a.state().x, b.state().x));
  EXPECT_TRUE(same_bits(a.state().v, b.state().v));
  EXPECT_TRUE(same_bits(a.surface(), b.surface()));
  EXPECT_TRUE(same_bits(a.normals(), b.normals()));
  EXPECT_EQ(a.time(), b.time());
  EXPECT_EQ(a.state().frames, b.state().frames);
  EXPECT_EQ(a.state().substeps, b.state().substeps);
  EXPECT_EQ(a.state().stiffening, b.state().stiffening);
  EXPECT_EQ(a.state().warnings.total(), b.state().warnings.total());
  if (rc.integrator != Integrator::LinearStatic) {
    EXPECT_GT((a.state().x - a.model().x0).norm(), 1e-3);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Models, CheckpointResume,
    ::testing::Values(ResumeCase{"KidneySymplectic", true, Integrator::SymplecticEuler, true},
                      ResumeCase{"KidneyImplicit", true, Integrator::ImplicitEuler, false},
                      ResumeCase{"TubeSymplectic", false, Integrator::SymplecticEuler, true},
                      ResumeCase{"TubeImplicit", false, Integrator::ImplicitEuler, false},
                      // the quasi-static linear response (docs/linear-response.md): the integrator byte 2
                      ResumeCase{"KidneyLinearStatic", true, Integrator::LinearStatic, true}),
    [](const ::testing::TestParamInfo<ResumeCase>& i) { return std::string(i.param.name); });

TEST(Checkpoint, ImplicitWarmStartIsPartOfTheCheckpoint) {
  SimulationSettings st;
  st.step.integrator = Integrator::ImplicitEuler;
  Simulation a(kidney_body(), st);
  a.set_loads({{.node = 223, .force = Vec3(0, 0, -1), .t_ramp = 20}});
  a.advance(10);
  const Checkpoint c = decode_checkpoint(encode_checkpoint(make_checkpoint(a)));
  ASSERT_EQ(c.state.dv.size(), 3 * a.model().num_nodes());
  EXPECT_TRUE(same_bits(c.state.dv, a.state().dv));
  EXPECT_GT(c.state.dv.norm(), 0.0);
  EXPECT_TRUE(same_bits(c.state.f_ext, a.state().f_ext));
}

TEST(Checkpoint, EncodeDecodeRoundTripsEveryField) {
  Simulation a(tube_body());
  a.set_loads(
      {{.node = 5, .force = Vec3(1, 2, 3), .t_on = 1, .t_ramp = 2, .t_release = 9, .ramp_down = true}});
  a.advance(4);
  a.state().warnings.rollbacks = 7;
  a.state().warnings.failed = 3;
  const Checkpoint c = decode_checkpoint(encode_checkpoint(make_checkpoint(a)));
  EXPECT_EQ(c.fingerprint, model_fingerprint(a.model()));
  EXPECT_EQ(c.model_name, "tube");
  EXPECT_EQ(c.body_kind, "surface");
  EXPECT_EQ(c.state.frames, 4u);
  EXPECT_EQ(c.state.warnings.rollbacks, 7u);
  EXPECT_EQ(c.state.warnings.failed, 3u);
  ASSERT_EQ(c.loads.size(), 1u);
  EXPECT_EQ(c.loads[0].node, 5);
  EXPECT_EQ(c.loads[0].force, Vec3(1, 2, 3));
  EXPECT_EQ(c.loads[0].t_release, 9.0);
  EXPECT_TRUE(c.loads[0].ramp_down);
  // an infinite release time survives
  a.set_loads({{.node = 5, .force = Vec3(1, 0, 0)}});
  EXPECT_TRUE(std::isinf(decode_checkpoint(encode_checkpoint(make_checkpoint(a))).loads[0].t_release));
}

class CheckpointRefusal : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::temp_dir("ckpt-bad");
    sim_ = std::make_unique<Simulation>(kidney_body());
    sim_->set_loads({{.node = 223, .force = Vec3(0, 0, -1)}});
    sim_->advance(20);
    good_ = dir_ / "good.mscp";
    save_checkpoint(good_, *sim_);
    bytes_ = read_bytes(good_);
  }
  // Restoring `bytes` into a fresh kidney simulation throws E with a message naming the file and
  // containing `words`; the simulation is left untouched.
  template <class E>
  void expect_refused(const std::string& bytes, const std::string& words) {
    const fs::path p = dir_ / "bad.mscp";
    write_bytes(p, bytes);
    Simulation fresh(kidney_body());
    fresh.advance(2);
    const MatX3 x = fresh.state().x;
    try {
      restore_checkpoint(p, fresh);
      ADD_FAILURE() << "accepted a bad checkpoint (" << words << ")";
    } catch (const E& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
      EXPECT_NE(msg.find(words), std::string::npos) << msg;
    }
    EXPECT_TRUE(same_bits(fresh.state().x, x));
    EXPECT_EQ(fresh.time(), 1.0);
  }
  fs::path dir_, good_;
  std::unique_ptr<Simulation> sim_;
  std::string bytes_;
};

TEST_F(CheckpointRefusal, TruncatedFilesAreRefused) {
  for (std::size_t n : {std::size_t{0}, std::size_t{7}, std::size_t{31}, std::size_t{32}, bytes_.size() / 2,
                        bytes_.size() - 1})
    expect_refused<IoError>(bytes_.substr(0, n), "truncated");
}

TEST_F(CheckpointRefusal, FlippedPayloadBitsFailTheChecksum) {
  for (std::size_t at : {std::size_t{32}, std::size_t{100}, bytes_.size() / 2, bytes_.size() - 1}) {
    std::string b = bytes_;
    b[at] = static_cast<char>(b[at] ^ 0x10);
    expect_refused<IoError>(b, "checksum");
  }
}

TEST_F(CheckpointRefusal, WrongVersionMagicAndTrailingBytesAreRefused) {
  std::string v = bytes_;
  v[8] = 3;  // version 3
  expect_refused<IoError>(v, "unsupported checkpoint version 3");
  std::string m = bytes_;
  m[0] = 'X';
  expect_refused<IoError>(m, "bad magic");
  expect_refused<IoError>(bytes_ + "xyz", "3 bytes after the payload");
}

TEST_F(CheckpointRefusal, AnotherModelIsRefused) {
  // a tube's checkpoint into the kidney
  Simulation tube_sim(tube_body());
  tube_sim.advance(2);
  const fs::path tp = dir_ / "tube.mscp";
  save_checkpoint(tp, tube_sim);
  expect_refused<InvalidInput>(read_bytes(tp), "saved from another model");
  // the same kidney with one stiffness changed: same node count, other fingerprint
  HybridSettings hs;
  hs.k_surf = 0.06;
  Simulation stiffer(std::make_shared<HybridKidney>(hybrid_kidney_phantom(hs)));
  EXPECT_NE(model_fingerprint(stiffer.model()), model_fingerprint(sim_->model()));
  EXPECT_THROW(restore_checkpoint(good_, stiffer), InvalidInput);
  EXPECT_EQ(stiffer.time(), 0.0);
}

TEST_F(CheckpointRefusal, MissingFileIsAnIoErrorNamingIt) {
  try {
    restore_checkpoint(dir_ / "none.mscp", *sim_);
    ADD_FAILURE() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("none.mscp"), std::string::npos);
  }
}

TEST_F(CheckpointRefusal, SaveIsAtomicAndLeavesNoTemporaryFiles) {
  // overwrite: the new file replaces the old one, nothing else appears in the folder
  sim_->advance(5);
  save_checkpoint(good_, *sim_);
  EXPECT_EQ(read_checkpoint(good_).state.frames, 25u);
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir_)) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1u);
  // a target that cannot be replaced (a non-empty folder): IoError, the folder and no temp file remain
  const fs::path blocked = dir_ / "blocked";
  fs::create_directories(blocked / "inside");
  EXPECT_THROW(save_checkpoint(blocked, *sim_), IoError);
  EXPECT_TRUE(fs::is_directory(blocked / "inside"));
  // a folder that does not exist
  EXPECT_THROW(save_checkpoint(dir_ / "missing" / "x.mscp", *sim_), IoError);
  files = 0;
  for (const auto& e : fs::directory_iterator(dir_)) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1u);
  EXPECT_EQ(read_checkpoint(good_).state.frames, 25u);
}

// Deterministic fuzz-lite: random byte changes and cuts in a valid file, with the header's size and
// checksum rewritten so that the payload parser itself is exercised. Only IoError / InvalidInput may
// come out (run under the sanitizers by scripts/sanitize.sh).
TEST(Checkpoint, MutatedPayloadsWithValidChecksumsAreRefusedCleanly) {
  Simulation sim(tube_body());
  sim.set_loads({{.node = 5, .force = Vec3(1, 0, 0), .t_release = 30}, {.node = 9, .force = Vec3(0, 1, 0)}});
  sim.advance(3);
  const std::string good = encode_checkpoint(make_checkpoint(sim));
  auto reseal = [](std::string b) {  // rewrite payload size and checksum (bytes 16..31)
    const std::uint64_t n = b.size() - 32, h = fnv1a64(b.data() + 32, n);
    for (int k = 0; k < 8; ++k) {
      b[16 + k] = static_cast<char>((n >> (8 * k)) & 0xFF);
      b[24 + k] = static_cast<char>((h >> (8 * k)) & 0xFF);
    }
    return b;
  };
  ASSERT_EQ(reseal(good), good);
  std::mt19937 rng(12345);
  Simulation target(tube_body());
  int accepted = 0, refused = 0;
  const std::size_t tail = good.size() - 2 * (4 + 6 * 8 + 1) - 8;  // the load records
  for (int it = 0; it < 3000; ++it) {
    std::string b = good;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      // mostly the structured parts: names, settings, counts (first 200 bytes) and the loads
      const std::size_t at = (rng() % 2 == 0) ? 32 + rng() % 200 : tail + rng() % (good.size() - tail);
      b[at] = static_cast<char>(rng() & 0xFF);
    }
    if (it % 5 == 0) b.resize(32 + rng() % (b.size() - 32));  // a cut payload
    b = reseal(std::move(b));
    try {
      const Checkpoint c = decode_checkpoint(b, "mutant");
      apply_checkpoint(c, target, "mutant");
      EXPECT_TRUE(target.state().x.allFinite());
      ++accepted;
    } catch (const IoError&) {
      ++refused;
    } catch (const InvalidInput&) {
      ++refused;
    }
  }
  EXPECT_GT(refused, 1000);
  EXPECT_EQ(accepted + refused, 3000);
}

TEST(Checkpoint, NonFiniteStateInsideAValidFileIsRefused) {
  Simulation a(tube_body());
  Checkpoint c = make_checkpoint(a);
  c.state.x(3, 1) = std::numeric_limits<double>::quiet_NaN();
  const Checkpoint d = decode_checkpoint(encode_checkpoint(c), "mem");
  EXPECT_THROW(apply_checkpoint(d, a, "mem"), InvalidInput);
  c = make_checkpoint(a);
  c.loads = {{.node = 5000}};
  EXPECT_THROW(apply_checkpoint(decode_checkpoint(encode_checkpoint(c)), a), InvalidInput);
  EXPECT_EQ(a.loads().size(), 0u);
}

}  // namespace
}  // namespace medspring
