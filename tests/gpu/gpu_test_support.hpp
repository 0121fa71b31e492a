// What the GPU tests share: skipping without a device, a pinned tube, a pressing load, relative
// differences (docs/gpu.md).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/gpu/engine.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/physics/model.hpp"

namespace medspring {

inline bool have_device(std::string* why) {
  try {
    gpu::require_device();
    return true;
  } catch (const gpu::GpuError& e) {
    if (why) *why = e.what();
    return false;
  }
}

#define REQUIRE_GPU()                              \
  do {                                             \
    std::string why_;                              \
    if (!have_device(&why_)) GTEST_SKIP() << why_; \
  } while (0)

inline Model tube_model(Index rings, Index spokes, bool soft = false) {
  SurfaceBodyParams p;
  p.duffing.soft = soft;
  for (Index j = 0; j < spokes; ++j) {
    p.fixed.push_back(j);
    p.fixed.push_back((rings - 1) * spokes + j);
  }
  const double radius = std::max(3.0, 2.5 * static_cast<double>(spokes) / (2.0 * 3.141592653589793));
  return make_surface_model(tube(rings, spokes, 2.5, radius), p, "tube");
}

inline std::vector<PointLoad> press(Index node, Vec3 F, double release = 2500.0) {
  PointLoad L;
  L.node = node;
  L.force = F;
  L.t_ramp = 10.0;
  L.t_release = release;
  return {L};
}

inline double rel(const MatX3& a, const MatX3& b) {
  const double scale = std::max(1.0, b.cwiseAbs().maxCoeff());
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

}  // namespace medspring
