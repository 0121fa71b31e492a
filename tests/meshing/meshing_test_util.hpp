// Helpers shared by the meshing tests.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <initializer_list>
#include <string>

#include "medspring/core/error.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/meshing/mesh_repair.hpp"

namespace medspring::testing {

/// Closed, edge- and vertex-manifold, consistently oriented, one component, Euler characteristic 2.
inline void expect_closed_genus0(const SurfaceMesh& m) {
  const ClosedManifoldReport r = check_closed_manifold(m);
  EXPECT_TRUE(r.ok()) << r.mesh.summary() << "; " << r.nonmanifold_vertices << " non-manifold vertices; "
                      << r.mesh.first_problem;
  EXPECT_EQ(r.mesh.components, 1);
  EXPECT_EQ(r.mesh.euler_characteristic, 2);
}

/// Runs `f`, expecting an InvalidInput whose one-line message contains every needle.
inline std::string expect_invalid_input_naming(const std::function<void()>& f,
                                               std::initializer_list<std::string> needles) {
  std::string message;
  bool thrown = false;
  try {
    f();
  } catch (const InvalidInput& e) {
    message = e.what();
    thrown = true;
  }
  EXPECT_TRUE(thrown) << "no InvalidInput thrown";
  for (const auto& needle : needles)
    EXPECT_NE(message.find(needle), std::string::npos) << "message: " << message << "\nexpected: " << needle;
  EXPECT_EQ(message.find('\n'), std::string::npos) << "message is not one line: " << message;
  return message;
}

}  // namespace medspring::testing
