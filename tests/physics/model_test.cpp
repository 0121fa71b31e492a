// Model validation: bad input is rejected with a message naming the element.
#include "medspring/physics/model.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "medspring/core/error.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/physics/stability.hpp"
#include "medspring/physics/state.hpp"

namespace medspring {
namespace {

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "";
}

TEST(Model, RejectsBadParametersNamingTheElement) {
  auto base = [] {
    ModelBuilder b("m");
    b.add_node(Vec3(0, 0, 0), 1.0, 0.5, 0.02);
    b.add_node(Vec3(1, 0, 0), 1.0, 0.5, 0.02);
    return b;
  };
  EXPECT_NE(error_of([&] {
              auto b = base();
              b.add_spring(0, 1, -1.0, 0.0, 1.0);
              b.build();
            }).find("springs[0].k"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              auto b = base();
              b.add_node(Vec3(2, 0, 0), 0.0, 0, 0);
              b.build();
            }).find("nodes[2].mass"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              auto b = base();
              b.add_node(Vec3(2, 0, 0), 1, -1, 0);
              b.build();
            }).find("nodes[2].damping"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              auto b = base();
              b.add_spring(0, 5, 1.0, 0.0, 1.0);
              b.build();
            }).find("springs[0].j"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              auto b = base();
              b.add_spring(1, 1, 1.0, 0.0, 1.0);
              b.build();
            }).find("itself"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              auto b = base();
              b.add_spring(0, 1, 1.0, 0.0, 0.0);
              b.build();
            }).find("zero-length"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              auto b = base();
              b.add_spring(0, 1, 1.0, std::nan(""), 1.0);
              b.build();
            }).find("springs[0].kp"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              auto b = base();
              b.add_node(Vec3(std::nan(""), 0, 0), 1, 0, 0);
              b.build();
            }).find("x0[2]"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              auto b = base();
              b.set_fixed(9);
            }).find("fixed node"),
            std::string::npos);
}

TEST(Model, SurfaceModelOfTheTubeHas3540Springs) {
  const Model m = make_surface_model(tube(40, 30, 2.5, 3.0), {});
  EXPECT_EQ(m.num_nodes(), 1200);
  EXPECT_EQ(m.num_springs(), 3540);
  EXPECT_TRUE(m.finalized);
  EXPECT_DOUBLE_EQ(m.damping[0], 0.5 * 0.3);
  EXPECT_THROW(make_surface_model(tube(4, 8), {.fixed = {100}}), InvalidInput);
  SurfaceMesh bad = tube(4, 8);
  bad.F(0, 0) = 99;
  EXPECT_THROW(make_surface_model(bad, {}), InvalidInput);
}

TEST(Model, StableStepOfTheKidneyPhantomSurface) {
  const Model m = make_surface_model(kidney_phantom(), {});
  EXPECT_GT(m.omega_rest, 0);
  EXPECT_LE(m.omega_rest, 1.05 * m.omega_gershgorin + 1e-12);
  EXPECT_GT(m.dt_safe_rest(), 0.5);  // the default dt = 0.5 ms needs no substeps at rest
  EXPECT_NEAR(dt_safe(m, 4.0), m.dt_safe_rest() / 2, 1e-15);
  EXPECT_THROW(make_state(Model{}), InvalidInput);
}

}  // namespace
}  // namespace medspring
