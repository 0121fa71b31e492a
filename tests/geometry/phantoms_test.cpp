#include "medspring/geometry/phantoms.hpp"

#include <gtest/gtest.h>

#include "medspring/core/error.hpp"
#include "medspring/geometry/topology.hpp"

namespace medspring {
namespace {

TEST(Phantoms, PaperTubeHas1200NodesAnd3540Springs) {
  const SurfaceMesh m = tube(40, 30, 2.5, 3.0);
  EXPECT_EQ(m.num_vertices(), 1200);
  EXPECT_EQ(m.num_faces(), 2340);
  EXPECT_EQ(unique_edges(m.F).rows(), 3540);
  const MeshReport r = validate_mesh(m);
  EXPECT_TRUE(r.valid()) << r.first_problem;
  EXPECT_EQ(r.boundary_edges, 60);  // two end rings
  EXPECT_EQ(r.inconsistent_edges, 0);
  const auto h = valence_histogram(vertex_adjacency(m.num_vertices(), unique_edges(m.F)));
  EXPECT_EQ(h[6], 1140);
  EXPECT_EQ(h[4], 60);
}

TEST(Phantoms, TubeFacesPointOutward) {
  const SurfaceMesh m = tube(5, 12, 2.0, 3.0);
  const MatX3 N = face_normals(m.V, m.F);
  for (Index f = 0; f < m.num_faces(); ++f) {
    Vec3 c = (m.V.row(m.F(f, 0)) + m.V.row(m.F(f, 1)) + m.V.row(m.F(f, 2))) / 3.0;
    c.x() = 0;
    EXPECT_GT(N.row(f).dot(c), 0) << "face " << f;
  }
}

TEST(Phantoms, KidneyPhantomCountsAndValences) {
  const SurfaceMesh m = kidney_phantom();
  EXPECT_EQ(m.num_vertices(), 458);
  EXPECT_EQ(m.num_faces(), 912);
  const MatX2i E = unique_edges(m.F);
  EXPECT_EQ(E.rows(), 1368);
  const MeshReport r = validate_mesh(m);
  EXPECT_TRUE(r.valid()) << r.first_problem;
  EXPECT_TRUE(r.closed());
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_EQ(r.inconsistent_edges, 0);
  EXPECT_GT(r.signed_volume, 0);
  const auto h = valence_histogram(vertex_adjacency(458, E));
  ASSERT_GE(h.size(), 25u);
  EXPECT_EQ(h[6], 408);
  EXPECT_EQ(h[5], 48);
  EXPECT_EQ(h[24], 2);
  // node order: pole (-a) = 0, ring node 1 + 24k + j, pole (+a) = 457
  EXPECT_NEAR((m.V.row(0) - kidney_bend(Vec3(-55, 0, 0)).transpose()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((m.V.row(457) - kidney_bend(Vec3(55, 0, 0)).transpose()).norm(), 0.0, 1e-12);
}

TEST(Phantoms, KidneyVolumeCloseToEllipsoid) {
  // The bend map preserves volume to first order; a 458-node polyhedron underestimates a bit.
  const SurfaceMesh m = kidney_phantom();
  const double ellipsoid = 4.0 / 3.0 * 3.14159265358979 * 55 * 28 * 18;
  EXPECT_NEAR(signed_volume(m.V, m.F) / ellipsoid, 1.0, 0.06);
}

TEST(Phantoms, IcosphereIsClosedGenusZero) {
  for (int s = 0; s <= 3; ++s) {
    const SurfaceMesh m = icosphere(s, 5.0);
    const MeshReport r = validate_mesh(m);
    EXPECT_EQ(m.num_vertices(), 10 * (1 << (2 * s)) + 2);
    EXPECT_TRUE(r.valid() && r.closed());
    EXPECT_EQ(r.euler_characteristic, 2);
    EXPECT_GT(r.signed_volume, 0);
    for (Index i = 0; i < m.num_vertices(); ++i) EXPECT_NEAR(m.V.row(i).norm(), 5.0, 1e-12);
  }
}

TEST(Phantoms, RejectsBadSizes) {
  EXPECT_THROW(tube(1, 30), InvalidInput);
  EXPECT_THROW(tube(40, 2), InvalidInput);
  EXPECT_THROW(tube(40, 30, -1.0), InvalidInput);
  EXPECT_THROW(icosphere(2, 0.0), InvalidInput);
}

}  // namespace
}  // namespace medspring
