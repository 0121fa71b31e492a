// The threaded float passes of volumetric models (issue 23, src/physics/threaded_volume.hpp, docs/threads.md
// "Volumetric models"): the thread count a model gets, the shared passes against the serial ones (the same
// kernels over shares of the tetrahedra, the forces summed in another order: float rounding; the increments,
// growth bound and inversion count exactly), the step on two threads against one (float rounding, the same
// sub-steps and warnings), bit-identical reruns, and a failed sub-step that restores the state.
#include "threaded_volume.hpp"  // src/physics

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/parallel.hpp"
#include "medspring/physics/state.hpp"
#include "volume_f32.hpp"  // src/physics
#include "volumetric_fixtures.hpp"

using namespace medspring;
using medspring::testing::squeezed;

namespace {

// The kidney phantom meshed to about 1,000 nodes (about 5,000 tetrahedra: two threads' worth), supports on
// the bottom 20 %, and its top node.
struct Kidney {
  std::shared_ptr<VolumetricBody> body;
  Index top = 0;
  explicit Kidney(Index nodes = 1000) {
    const SurfaceMesh s = kidney_phantom();
    VolumetricSettings vs;
    vs.fixed = medspring::testing::bottom_supports(s);
    body = std::make_shared<VolumetricBody>(fem::volumetric_mesh(s, {.target_nodes = nodes}), vs, "kidney");
    top = medspring::testing::top_node(s);
  }
};

const Kidney& kidney() {
  static const Kidney k;
  return k;
}

}  // namespace

TEST(ThreadedVolume, ThreadCountFollowsTheTetrahedra) {
  const Model& m = kidney().body->model();
  ASSERT_TRUE(m.volume_f32 != nullptr);
  ASSERT_GE(m.volume.size(), 2 * kMinVolumeRecordsPerThread);
  const int two = threads_supported() ? 2 : 1;
  EXPECT_EQ(effective_threads(m, {.threads = 2}), two);
  EXPECT_EQ(effective_threads(m, {.threads = 1}), 1);
  EXPECT_EQ(effective_threads(m, {.integrator = Integrator::ImplicitEuler, .threads = 2}), 1);
  // as many threads as the tetrahedra allow (2,000 each), never more than asked
  const auto most = static_cast<int>(m.volume.size() / kMinVolumeRecordsPerThread);
  EXPECT_EQ(effective_threads(m, {.threads = 64}), threads_supported() ? most : 1);
  // the double volume pass has no threaded path
  Model dbl = m;
  set_volume_single_precision(dbl, false);
  EXPECT_EQ(effective_threads(dbl, {.threads = 2}), 1);
  // a small model runs on one thread
  const VolumetricMesh cube =
      fem::volumetric_mesh(medspring::testing::box_surface(4, 20), {.target_nodes = 300});
  VolumetricSettings vs;
  vs.fixed = {0, 1, 2, 3};
  EXPECT_EQ(effective_threads(VolumetricBody(cube, vs, "cube").model(), {.threads = 2}), 1);
}

// The passes with ParallelRecords (two and three threads, equal shares) against the same passes without: the
// forces within float rounding of the serial sums (each thread sums its share in float, the shares are added
// in double), the per-term increments and the largest growth exactly, the compression traces within float
// rounding, the inversion count exactly.
TEST(ThreadedVolume, SharedPassesMatchTheSerialPasses) {
  const Model& m = kidney().body->model();
  const VolumeTermsF32& F = *m.volume_f32;
  const Index n = m.num_nodes(), nt = m.volume.size();
  const auto nr = F.rec.size();
  VecX s(n);
  for (Index i = 0; i < n; ++i)
    s[i] = m.fixed[static_cast<std::size_t>(i)] ? 0.0 : 1.0 / std::sqrt(m.mass[i]);
  std::mt19937 rng(3);
  std::normal_distribution<double> N(0.0, 0.3);
  for (const int T : {2, 3}) {
    WorkerPool pool(T);
    std::vector<std::vector<float>> extra(static_cast<std::size_t>(T), std::vector<float>(4 * n));
    std::vector<float*> mirrors(static_cast<std::size_t>(T));
    std::vector<std::size_t> begin(static_cast<std::size_t>(T) + 1, nr);
    for (int t = 0; t < T; ++t) {
      mirrors[static_cast<std::size_t>(t)] = extra[static_cast<std::size_t>(t)].data();
      begin[static_cast<std::size_t>(t)] =
          nr * static_cast<std::size_t>(t) / static_cast<std::size_t>(T) / 8 * 8;
    }
    const ParallelRecords par{&pool, begin.data(), mirrors.data(), T};
    for (const double strain : {0.02, 0.3, 0.7, -0.1}) {
      MatX3 x = squeezed(m.x0, strain);
      if (strain == 0.3) x += MatX3::NullaryExpr(n, 3, [&] { return N(rng); });
      const std::string l = std::to_string(T) + " threads, strain " + std::to_string(strain);
      std::vector<float> sa(static_cast<std::size_t>(kVolumeF32ScratchPerNode * n)), sb = sa;
      VecX fa = VecX::Zero(3 * n), fb = VecX::Zero(3 * n);
      add_volume_and_compression_forces_f32(F, x.data(), fa.data(), sa.data());
      add_volume_and_compression_forces_f32(F, x.data(), fb.data(), sb.data(), true, &par);
      const double fmax = fa.cwiseAbs().maxCoeff();
      ASSERT_GT(fmax, 0.0) << l;
      float other = 0.0f;  // the other threads' mirrors got their shares
      for (const float v : extra[static_cast<std::size_t>(T) - 1]) other = std::max(other, std::abs(v));
      EXPECT_GT(other, 0.0f) << l;
      EXPECT_LE((fa - fb).cwiseAbs().maxCoeff(), 1e-5 * fmax) << l;
      VecX ia = VecX::Zero(nt), ib = VecX::Zero(nt), ta = VecX::Zero(n), tb = VecX::Zero(n);
      fa.setZero();
      fb.setZero();
      const double sva = add_volume_and_compression_forces_inc_f32(F, x.data(), fa.data(), sa.data(),
                                                                   ia.data(), s.data(), ta.data());
      const double svb = add_volume_and_compression_forces_inc_f32(F, x.data(), fb.data(), sb.data(),
                                                                   ib.data(), s.data(), tb.data(), &par);
      EXPECT_EQ(sva, svb) << l;
      EXPECT_EQ((ia - ib).cwiseAbs().maxCoeff(), 0.0) << l;  // per term: the same kernel, the same numbers
      EXPECT_LE((fa - fb).cwiseAbs().maxCoeff(), 1e-5 * fa.cwiseAbs().maxCoeff()) << l;
      if (F.comp) {
        EXPECT_LE((ta - tb).cwiseAbs().maxCoeff(), 1e-5 * std::max(1e-30, ta.cwiseAbs().maxCoeff())) << l;
      }
      EXPECT_EQ(count_inverted_f32(F, m.volume, x.data(), sa.data()),
                count_inverted_f32(F, m.volume, x.data(), sb.data(), &par))
          << l;
    }
  }
}

// 200 frames of 0.5 N on the top node, one thread against two: the same sub-steps and warnings, positions
// within 1e-6 of the peak displacement (float sums in another order); two reruns on two threads
// bit-identical.
TEST(ThreadedVolume, TwoThreadsStayWithinFloatRoundingOfOneAndRerunBitIdentically) {
  if (!threads_supported()) GTEST_SKIP() << "this build runs one thread";
  const Kidney& k = kidney();
  const Model& m = k.body->model();
  State a = make_state(m), b = make_state(m, {.threads = 2}), c = make_state(m, {.threads = 2});
  k.body->transfer_force(k.top, Vec3(0, 0, -0.5), a.f_ext);
  b.f_ext = c.f_ext = a.f_ext;
  double disp = 0, dev = 0;
  for (int i = 0; i < 200; ++i) {
    step(m, a, {.dt = 0.5});
    step(m, b, {.dt = 0.5, .threads = 2});
    step(m, c, {.dt = 0.5, .threads = 2});
    ASSERT_EQ(a.substeps, b.substeps) << "frame " << i;
    ASSERT_TRUE(b.x.allFinite()) << "frame " << i;
    disp = std::max(disp, (a.x - m.x0).cwiseAbs().maxCoeff());
    dev = std::max(dev, (a.x - b.x).cwiseAbs().maxCoeff());
  }
  std::cout << "200 frames, 0.5 N, " << m.num_nodes() << " nodes: peak displacement " << disp
            << " mm, two threads - one at most " << dev << " mm (" << dev / disp << " of it)\n";
  EXPECT_GT(disp, 1.0);
  EXPECT_GT(dev, 0.0);  // the threaded passes ran (another summation order)
  EXPECT_LE(dev, 1e-6 * disp);
  EXPECT_EQ(a.warnings.total(), b.warnings.total());
  EXPECT_EQ(a.warnings.inverted_elements, b.warnings.inverted_elements);
  EXPECT_TRUE(b.x == c.x && b.v == c.v);  // bit-identical reruns
}

// A frame whose velocities exceed v_max: the threaded sub-steps fail and roll back like the serial ones, and
// a frame that cannot be advanced leaves the positions where the last valid sub-step put them (here: where
// the frame started, to the rounding of the undo).
TEST(ThreadedVolume, AFailedSubStepRestoresTheState) {
  if (!threads_supported()) GTEST_SKIP() << "this build runs one thread";
  const Kidney& k = kidney();
  const Model& m = k.body->model();
  State a = make_state(m), b = make_state(m, {.threads = 2});
  k.body->transfer_force(k.top, Vec3(0, 0, -0.5), a.f_ext);
  b.f_ext = a.f_ext;
  for (int i = 0; i < 5; ++i) {
    step(m, a, {.dt = 0.5});
    step(m, b, {.dt = 0.5, .threads = 2});
  }
  const double vmax = b.v.rowwise().norm().maxCoeff();
  ASSERT_GT(vmax, 0.0);
  const MatX3 xa = a.x, xb = b.x;
  // a limit far below the speeds: every sub-step fails, the frame is dropped
  const StepStatus ra = step(m, a, {.dt = 0.5, .v_max = 1e-3 * vmax});
  const StepStatus rb = step(m, b, {.dt = 0.5, .v_max = 1e-3 * vmax, .threads = 2});
  EXPECT_EQ(ra.code, StepCode::Failed);
  EXPECT_EQ(rb.code, StepCode::Failed);
  EXPECT_EQ(a.warnings.rollbacks, b.warnings.rollbacks);
  EXPECT_EQ(a.warnings.failed, b.warnings.failed);
  const double scale = (xb - m.x0).cwiseAbs().maxCoeff();
  EXPECT_LE((b.x - xb).cwiseAbs().maxCoeff(), 1e-9 * scale);
  EXPECT_LE((a.x - b.x).cwiseAbs().maxCoeff(), 1e-6 * scale);
  EXPECT_EQ(b.v.cwiseAbs().maxCoeff(), 0.0);
}
