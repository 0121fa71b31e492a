// The held-out error split by surface region (fem/error_regions.hpp, docs/accuracy-calibration.md, "Where the
// held-out error sits").
#include "medspring/fem/error_regions.hpp"

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

#include "medspring/core/error.hpp"

using namespace medspring;

namespace {

// A flat 31 x 31 grid, 2 mm apart (x, y in [0, 60] mm), held along the edge x = 0.
struct Grid {
  MatX3 V;
  std::vector<Index> support;
  Grid() : V(31 * 31, 3) {
    for (int j = 0; j < 31; ++j)
      for (int i = 0; i < 31; ++i) {
        V.row(j * 31 + i) << 2.0 * i, 2.0 * j, 0.0;
        if (i == 0) support.push_back(j * 31 + i);
      }
  }
};

}  // namespace

// The regions by hand: a 5 mm disk at (30, 30) holds the 21 grid points with dx^2 + dy^2 <= 25 (dx, dy in
// {0, +-2, +-4}); the supports region is the columns x = 0, 2, 4 (93 nodes, all > 15 mm from the load);
// near (5 < d <= 15 mm) and far are the rest. An error of 0.1 mm along the FEM displacement on the disk and
// of 0.05 mm across it on the supports' nodes gives, to 1e-12: the disk's and supports' RMS, shares of
// 21 * 0.01 and 93 * 0.0025 over their sum, along = +0.1 mm on the disk and 0 on the supports, and nothing
// elsewhere.
TEST(ErrorRegions, SplitsTheSquaredErrorByDistanceToTheLoadAndTheSupports) {
  const Grid g;
  const fem::ContactLoad load{Vec3(30, 30, 0), Vec3(0, 0, -1), 5.0};
  const std::vector<fem::ErrorRegion> r = fem::error_regions(g.V, load, g.support);
  std::array<Index, 4> count{};
  for (const auto x : r) count[static_cast<std::size_t>(x)] += 1;
  EXPECT_EQ(count[0], 21);
  EXPECT_EQ(count[2], 93);
  EXPECT_EQ(count[0] + count[1] + count[2] + count[3], 961);
  EXPECT_GT(count[1], 0);
  EXPECT_GT(count[3], 0);

  MatX3 u_fem = MatX3::Zero(961, 3);
  u_fem.col(2).setConstant(-1.0);  // everything moves 1 mm down
  MatX3 u_model = u_fem;
  for (Index i = 0; i < 961; ++i) {
    if (r[i] == fem::ErrorRegion::Disk) u_model(i, 2) -= 0.1;       // 0.1 mm further along the FEM's -z
    if (r[i] == fem::ErrorRegion::Supports) u_model(i, 0) += 0.05;  // across it
  }
  const auto e = fem::error_by_region(g.V, u_model, u_fem, load, g.support);
  const double sd = 21 * 0.01, ss = 93 * 0.0025;
  EXPECT_NEAR(e[0].rms, 0.1, 1e-12);
  EXPECT_NEAR(e[2].rms, 0.05, 1e-12);
  EXPECT_NEAR(e[1].rms, 0.0, 1e-12);
  EXPECT_NEAR(e[3].rms, 0.0, 1e-12);
  EXPECT_NEAR(e[0].share, sd / (sd + ss), 1e-12);
  EXPECT_NEAR(e[2].share, ss / (sd + ss), 1e-12);
  EXPECT_NEAR(e[0].share + e[1].share + e[2].share + e[3].share, 1.0, 1e-12);
  EXPECT_NEAR(e[0].along, 0.1, 1e-12);
  EXPECT_NEAR(e[2].along, 0.0, 1e-12);
  // a model that moves too little under the disk reads a negative along
  for (Index i = 0; i < 961; ++i)
    if (r[i] == fem::ErrorRegion::Disk) u_model(i, 2) = -0.8;
  EXPECT_NEAR(fem::error_by_region(g.V, u_model, u_fem, load, g.support)[0].along, -0.2, 1e-12);
  // equal displacements: no error anywhere, shares 0
  for (const auto& x : fem::error_by_region(g.V, u_fem, u_fem, load, g.support)) {
    EXPECT_EQ(x.rms, 0.0);
    EXPECT_EQ(x.share, 0.0);
  }
}

TEST(ErrorRegions, BadInputIsRefusedWithWhatIsWrong) {
  const Grid g;
  const MatX3 u = MatX3::Zero(961, 3);
  auto msg = [&](const MatX3& um, const fem::ContactLoad& l, const std::vector<Index>& s) {
    try {
      fem::error_by_region(g.V, um, u, l, s);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  const fem::ContactLoad ok{Vec3(30, 30, 0), Vec3(0, 0, -1), 5.0};
  EXPECT_NE(msg(MatX3::Zero(960, 3), ok, g.support).find("961 surface nodes but displacements of 960"),
            std::string::npos);
  EXPECT_NE(msg(u, {Vec3(30, 30, 0), Vec3(0, 0, -1), 0.0}, g.support).find("load radius must be > 0"),
            std::string::npos);
  EXPECT_NE(msg(u, ok, {0, 961}).find("support node 961 is not one of the 961"), std::string::npos);
}
