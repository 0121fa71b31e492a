// Compression stiffening of the volumetric kind (issue 23, physics/compression_terms.hpp, docs/volumetric.md
// "Compression stiffening"), input and output: an inverted tetrahedron counted during a run, never a NaN; the
// coefficient carried by a model package; bad coefficients and terms refused with the defect named.
#include <gtest/gtest.h>

#include <string>

#include "medspring/models/model_package.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/integrators.hpp"
#include "volumetric_fixtures.hpp"

using namespace medspring;
using medspring::testing::irregular_tet;
using medspring::testing::one_tet;

namespace {

TEST(Compression, InversionDuringARunIsCountedNotNaN) {
  for (double nu : {0.2, 0.45}) {
    VolumetricSettings st;
    st.nu = nu;
    st.compression = 4.0;
    st.fixed = {0, 1, 2};
    const MatX3 X = irregular_tet();
    const VolumetricBody body(one_tet(X), st, "tet");
    EXPECT_EQ(body.model().volume.size(), nu < 0.25 ? 0 : 1);
    State s = make_state(body.model());
    const Vec3 c = (X.row(0) + X.row(1) + X.row(2)).transpose() / 3;
    const Vec3 dir = (c - X.row(3).transpose()).normalized();
    body.transfer_force(3, 20.0 * dir, s.f_ext);
    for (int i = 0; i < 400; ++i) step(body.model(), s, {.dt = 0.5});
    EXPECT_TRUE(s.x.allFinite()) << nu;
    EXPECT_GT(s.warnings.inverted_elements, 0u) << nu;
    EXPECT_EQ(s.warnings.nonfinite, 0u) << nu;
  }
}

// A model package carries the coefficient: the rebuilt body has the same terms and fingerprint.
TEST(Compression, ModelPackageCarriesTheCoefficient) {
  VolumetricSettings st;
  st.fixed = {0, 1, 2};
  st.compression = 3.5;
  const VolumetricBody body(one_tet(irregular_tet()), st, "tet");
  const ModelPackage p = decode_model_package(encode_model_package(package_of(body)));
  EXPECT_EQ(p.volumetric.compression, 3.5);
  const BodyPtr again = make_body(p);
  EXPECT_EQ(again->model().compression.size(), 1);
  EXPECT_TRUE(check_fingerprint(p, *again));
  st.compression = 0;
  const VolumetricBody plain(one_tet(irregular_tet()), st, "tet");
  EXPECT_NE(model_fingerprint(plain.model()), model_fingerprint(body.model()));
}

// Bad input: a negative or non-finite coefficient is refused naming it; so is a bad term at the physics
// level.
TEST(Compression, BadInputIsRefused) {
  VolumetricSettings st;
  st.fixed = {0, 1, 2};
  st.compression = -1;
  try {
    const VolumetricBody body(one_tet(irregular_tet()), st, "tet");
    FAIL() << "accepted compression = -1";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("compression must be >= 0"), std::string::npos) << e.what();
  }
  ModelBuilder b("m");
  const MatX3 X = irregular_tet();
  for (Index a = 0; a < 4; ++a) b.add_node(X.row(a).transpose(), 1.0, 0.0, 0.0);
  b.add_compression(0, 2, 1, 3, 1.0);  // inverted orientation
  try {
    b.build();
    FAIL() << "accepted an inverted compression term";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("compression[0]: inverted tetrahedron"), std::string::npos)
        << e.what();
  }
}

}  // namespace
