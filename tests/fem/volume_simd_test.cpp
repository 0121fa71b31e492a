// The volume passes across tetrahedra (issue 23, item 5; src/physics/tet_simd.hpp, volume_passes.cpp):
// several records at a time in vector registers, scattered lane by lane in the records' order, against the
// same passes one record at a time (tet_record, the vector path switched off): forces, local-rule
// increments, compression traces and the stiffening bound equal bit for bit, on a cube from tension to pushed
// through and on the real kidney (kidney_left_hubmap_vhm.obj) meshed by TetGen at about 7,000 nodes, rest and
// squeezed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "compression_rows.hpp"  // add_volume_and_compression_forces_inc, set_volume_simd (src/physics)
#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/compression_terms.hpp"
#include "tet_simd.hpp"  // MEDSPRING_TET_SIMD, kTetLanes (src/physics)
#include "volumetric_fixtures.hpp"
#ifdef MEDSPRING_TEST_HAVE_IO
#include "medspring/io/mesh_io.hpp"
#include "test_support.hpp"
#endif

using namespace medspring;

namespace {

// Bit-for-bit equality of two arrays (NaN never expected: checked separately).
::testing::AssertionResult same_bits(const VecX& a, const VecX& b, const char* what) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << what << ": sizes differ";
  for (Index i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(double)) != 0 || std::isnan(a[i]))
      return ::testing::AssertionFailure()
             << what << "[" << i << "]: " << a[i] << " vs " << b[i] << " (diff " << a[i] - b[i] << ")";
  return ::testing::AssertionSuccess();
}

// Runs each volume pass at x with the vector path on and off (forces added to the same nonzero start, as in
// the step) and compares everything. Returns the number of compressed tetrahedra (J < 1), so the callers can
// check the state exercises the compression terms.
Index compare_paths(const Model& m, const MatX3& x, const std::string& label) {
  const Index n = m.num_nodes(), nt = m.volume.size();
  VecX s(n);
  for (Index i = 0; i < n; ++i)
    s[i] = m.fixed[static_cast<std::size_t>(i)] ? 0.0 : 1.0 / std::sqrt(m.mass[i]);
  struct Out {
    VecX f, inc, t;
    double sv = 0;
  };
  // pass 0: add_volume_and_compression_forces_inc (the last sub-step), 1: add_volume_and_compression_forces
  // (the others), 2: add_volume_forces_inc, 3 and 4: add_volume_forces with and without the stiffening
  auto run = [&](int pass, bool simd) {
    Out o{VecX::LinSpaced(3 * n, -1.0, 1.0), VecX::Constant(nt, -7.0), VecX::Constant(n, 3.0)};
    const bool was = detail::set_volume_simd(simd);
    if (pass == 0)
      o.sv = add_volume_and_compression_forces_inc(m.volume, x.data(), o.f.data(), o.inc.data(), s.data(),
                                                   o.t.data(), n);
    if (pass == 1) add_volume_and_compression_forces(m.volume, x.data(), o.f.data());
    if (pass == 2) o.sv = add_volume_forces_inc(m.volume, x.data(), o.f.data(), o.inc.data());
    if (pass == 3 || pass == 4) o.sv = add_volume_forces(m.volume, x.data(), o.f.data(), pass == 3);
    detail::set_volume_simd(was);
    return o;
  };
  for (int pass = 0; pass < 5; ++pass) {
    const Out a = run(pass, true), b = run(pass, false);
    const std::string l = label + ", pass " + std::to_string(pass);
    EXPECT_TRUE(same_bits(a.f, b.f, "forces")) << l;
    EXPECT_TRUE(same_bits(a.inc, b.inc, "increments")) << l;
    EXPECT_TRUE(same_bits(a.t, b.t, "traces")) << l;
    EXPECT_EQ(std::memcmp(&a.sv, &b.sv, sizeof(double)), 0) << l << ": " << a.sv << " vs " << b.sv;
    EXPECT_TRUE(std::isfinite(a.sv)) << l;
  }
  Index compressed = 0;
  for (Index t = 0; t < nt; ++t) {
    const Index c[4] = {m.volume.a[t], m.volume.b[t], m.volume.c[t], m.volume.d[t]};
    const Vec3 p0 = x.row(c[0]).transpose();
    const double v = (x.row(c[1]).transpose() - p0)
                         .dot((x.row(c[2]).transpose() - p0).cross(x.row(c[3]).transpose() - p0));
    const Vec3 q0 = m.x0.row(c[0]).transpose();
    const double v0 = (m.x0.row(c[1]).transpose() - q0)
                          .dot((m.x0.row(c[2]).transpose() - q0).cross(m.x0.row(c[3]).transpose() - q0));
    compressed += v < v0 ? 1 : 0;
  }
  return compressed;
}

bool simd_compiled() {
  return detail::volume_simd_compiled();
}

}  // namespace

TEST(VolumeSimd, CubeFromTensionToPushedThroughEqualsTheScalarPass) {
  if (!simd_compiled())
    GTEST_SKIP()
        << "no vector pass in this build (no AVX2 target, or not GCC): the scalar pass is the only one";
  const VolumetricMesh vm =
      fem::volumetric_mesh(medspring::testing::box_surface(4, 20), {.target_nodes = 300});
  VolumetricSettings st;
  st.nu = 0.45;
  st.return_k = 0.0;
  st.compression = 32.0;
  st.fixed = {0, 1, 2, 3};
  const VolumetricBody body(vm, st, "cube");
  const Model& m = body.model();
  ASSERT_EQ(m.volume.kc.size(), static_cast<std::size_t>(m.volume.size()));  // fused compression terms
  ASSERT_GT(m.volume.size(), 4 * 8);
  std::mt19937 rng(5);
  std::normal_distribution<double> N(0.0, 1.0);
  const Index n = m.num_nodes();
  for (int trial = 0; trial < 6; ++trial) {
    MatX3 x = m.x0;
    const double sz = 1.1 - 0.25 * trial;  // 1.1 .. -0.15: tension to pushed through (J < J_min, inverted)
    for (Index a = 0; a < n; ++a) x(a, 2) *= x(a, 0) > 10 ? sz : 1.0;
    x += (0.6 * trial) * MatX3::NullaryExpr(n, 3, [&] { return N(rng); });
    const Index c = compare_paths(m, x, "cube, trial " + std::to_string(trial));
    if (trial > 0) {
      EXPECT_GT(c, 0) << "trial " << trial;
    }
  }
}

// Fewer records than a lane group, and a count that leaves a tail: the scalar kernel's share.
TEST(VolumeSimd, TailRecordsEqualTheScalarPass) {
  if (!simd_compiled())
    GTEST_SKIP()
        << "no vector pass in this build (no AVX2 target, or not GCC): the scalar pass is the only one";
  int tails = 0;
  MatX3 X(4, 3);
  X << 0, 0, 0, 4.2, 0.3, -0.2, 0.7, 3.6, 0.4, 1.1, 0.9, 3.3;
  const VolumetricMesh meshes[] = {
      medspring::testing::one_tet(X),  // one record: the scalar kernel alone
      fem::volumetric_mesh(medspring::testing::box_surface(2, 10), {.target_nodes = 30}),
      fem::volumetric_mesh(medspring::testing::box_surface(3, 10), {.target_nodes = 60}),
      fem::volumetric_mesh(medspring::testing::box_surface(3, 12), {.target_nodes = 90})};
  for (const VolumetricMesh& vm : meshes) {
    VolumetricSettings st;
    st.compression = 32.0;
    const VolumetricBody body(vm, st, "small cube");
    const Model& m = body.model();
    MatX3 x = m.x0;
    x.col(2) *= 0.7;
    EXPECT_GT(compare_paths(m, x, "small cube, " + std::to_string(m.volume.size()) + " tetrahedra"), 0);
#if defined(MEDSPRING_TET_SIMD)
    tails += m.volume.size() % detail::kTetLanes != 0 ? 1 : 0;
#endif
  }
  EXPECT_GT(tails, 0);  // at least one mesh leaves records to the scalar kernel
}

#ifdef MEDSPRING_TEST_HAVE_IO
// The real kidney (Visible Human, metres) meshed inside at about 7,000 nodes (its surface has 5,002 vertices;
// the speed benchmark meshes the 458-node phantom at 2,000): at rest, squeezed 2 % (the benchmark's state)
// and 30 % with noise.
TEST(VolumeSimd, RealKidneyEqualsTheScalarPass) {
  if (!simd_compiled())
    GTEST_SKIP()
        << "no vector pass in this build (no AVX2 target, or not GCC): the scalar pass is the only one";
  const SurfaceMesh s = read_mesh(medspring::testing::require_data_file("kidney_left_hubmap_vhm.obj"),
                                  {.unit = LengthUnit::Metre});
  const VolumetricMesh vm = fem::volumetric_mesh(s, {.target_nodes = 7000});
  const double zmin = s.V.col(2).minCoeff(), zmax = s.V.col(2).maxCoeff();
  VolumetricSettings st;
  st.fixed = fem::support_nodes(s.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
  const VolumetricBody body(vm, st, "real kidney");
  const Model& m = body.model();
  ASSERT_EQ(m.volume.kc.size(), static_cast<std::size_t>(m.volume.size()));
  ASSERT_GT(m.volume.size(), 5000);
  compare_paths(m, m.x0, "real kidney at rest");
  MatX3 x = m.x0;
  x.col(2) *= 0.98;
  EXPECT_GT(compare_paths(m, x, "real kidney squeezed 2 %"), 0);
  std::mt19937 rng(11);
  std::normal_distribution<double> N(0.0, 0.3);
  x = m.x0;
  x.col(2) *= 0.7;
  x += MatX3::NullaryExpr(m.num_nodes(), 3, [&] { return N(rng); });
  EXPECT_GT(compare_paths(m, x, "real kidney squeezed 30 % with noise"), 0);
}
#endif
