// The opt-in surface-layer spring family of the volumetric kind (issue 23, VolumetricSettings::
// surface_spring_scale, docs/accuracy-calibration.md "A surface-layer spring family"): it scales exactly the
// springs whose two ends are surface nodes and no other, its default leaves the model bit for bit as it
// was, a model package rebuilds it, and bad values are refused with the parameter named.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <utility>

#include "medspring/core/params.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/tet_mesh.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "volumetric_box.hpp"

using namespace medspring;
using medspring::testing::box;

namespace {

// A 20 x 20 x 10 mm box of 4 x 4 x 2 cells (75 nodes, 9 of them interior), held on its base.
VolumetricMesh small_box() {
  return box(fem::graded(0, 20, 4), fem::graded(0, 20, 4), fem::graded(0, 10, 2));
}

VolumetricSettings held(const VolumetricMesh& vm, double q) {
  VolumetricSettings s;
  s.E_kPa = 10;
  s.nu = 0.45;
  for (Index i = 0; i < vm.surface_nodes; ++i)
    if (vm.X(i, 2) < 1e-9) s.fixed.push_back(i);
  s.surface_spring_scale = q;
  return s;
}

}  // namespace

// Against the same mesh at q = 1: every spring between two surface nodes is q times as stiff (to 1 ulp),
// every other spring is unchanged bit for bit, and their count is the number of distinct tetrahedron edges
// with both ends below surface_nodes (counted here from the tetrahedra). q = 1 is the default model, bit for
// bit (same springs, same fingerprint).
TEST(SurfaceSprings, TheFamilyScalesOnlyTheSpringsBetweenSurfaceNodes) {
  const VolumetricMesh vm = small_box();
  const Index ns = vm.surface_nodes;
  ASSERT_LT(ns, vm.X.rows()) << "the box needs interior nodes";
  VolumetricSettings plain = held(vm, 1.0);
  plain.surface_spring_scale = VolumetricSettings{}.surface_spring_scale;  // the default
  const VolumetricBody base(vm, plain, "box"), one(vm, held(vm, 1.0), "box"), q(vm, held(vm, 2.5), "box");
  EXPECT_EQ(model_fingerprint(one.model()), model_fingerprint(base.model()));
  EXPECT_EQ(one.model().springs.k, base.model().springs.k);

  std::set<std::pair<Index, Index>> surface_edges;  // distinct edges with both ends on the surface
  for (Index t = 0; t < vm.T.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        if (vm.T(t, a) < ns && vm.T(t, b) < ns) surface_edges.insert(std::minmax(vm.T(t, a), vm.T(t, b)));
  const Springs& s0 = base.model().springs;
  const Springs& s1 = q.model().springs;
  ASSERT_EQ(s1.size(), s0.size());
  Index scaled = 0, interior = 0;
  for (Index e = 0; e < s0.size(); ++e) {
    const auto u = static_cast<std::size_t>(e);
    ASSERT_EQ(s1.i[u], s0.i[u]);
    ASSERT_EQ(s1.j[u], s0.j[u]);
    EXPECT_EQ(s1.L0[u], s0.L0[u]);
    if (s0.i[u] < ns && s0.j[u] < ns) {
      EXPECT_NEAR(s1.k[u], 2.5 * s0.k[u], 1e-15 * s1.k[u]) << "spring " << e;
      ++scaled;
    } else {
      EXPECT_EQ(s1.k[u], s0.k[u]) << "spring " << e;
      ++interior;
    }
  }
  EXPECT_EQ(scaled, static_cast<Index>(surface_edges.size()));
  EXPECT_EQ(q.stats().surface_springs, scaled);
  EXPECT_EQ(base.stats().surface_springs, scaled);
  EXPECT_GT(interior, 0);
  // the volume terms and the compression terms are not the family's
  EXPECT_EQ(q.stats().kv, base.stats().kv);
  EXPECT_EQ(q.stats().kc, base.stats().kc);
}

// The physics: a softer surface layer lets a disk load on the top sink further (small-strain response), a
// stiffer one less; the displacement moves monotonically with q.
TEST(SurfaceSprings, ASofterSurfaceLayerLetsTheLoadedDiskSinkFurther) {
  const VolumetricMesh vm = small_box();
  const fem::ContactLoad load{Vec3(10, 10, 10), Vec3(0, 0, -0.1), 5.0};
  double last = 0;
  for (double q : {2.0, 1.0, 0.5}) {
    const VolumetricBody b(vm, held(vm, q), "box");
    const MatX3 u = fem::spring_displacement_linear(b, {load})[0];
    const Vec3 mean = fem::disk_mean_linear(vm.X.topRows(vm.surface_nodes), vm.F, load, u);
    EXPECT_LT(mean(2), 0.0);
    EXPECT_GT(-mean(2), 1.02 * last) << "q = " << q;
    last = -mean(2);
  }
}

// A model package stores the scale (version 8) and rebuilds the same model; bad values are refused by the
// body and by the declaration with the parameter named.
TEST(SurfaceSprings, PackageRoundTripAndBadValuesAreRefusedWithTheParameterNamed) {
  const VolumetricMesh vm = small_box();
  const VolumetricBody q(vm, held(vm, 0.6), "box");
  const ModelPackage p = decode_model_package(encode_model_package(package_of(q, "box")), "box.msm");
  EXPECT_EQ(p.volumetric.surface_spring_scale, 0.6);
  const BodyPtr again = make_body(p);
  EXPECT_TRUE(check_fingerprint(p, *again));
  EXPECT_EQ(model_fingerprint(again->model()), model_fingerprint(q.model()));
  for (double bad : {0.0, -1.0, std::nan("")}) {
    try {
      const VolumetricBody b(vm, held(vm, bad), "box");
      ADD_FAILURE() << "surface_spring_scale " << bad << " not refused";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("box: surface_spring_scale must be > 0"), std::string::npos)
          << e.what();
    }
  }
  VolumetricSettings s;
  try {
    set_param(s, "surface_spring_scale", "0");
    ADD_FAILURE() << "surface_spring_scale 0 not refused by the declaration";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("surface_spring_scale"), std::string::npos) << e.what();
  }
  set_param(s, "surface_spring_scale", "0.75");
  EXPECT_EQ(s.surface_spring_scale, 0.75);
}
