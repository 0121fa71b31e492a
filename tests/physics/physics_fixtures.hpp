// Small models used by the physics tests (ALGORITHMS.md §8).
#pragma once

#include "medspring/physics/model.hpp"

namespace medspring::testing {

/// Two nodes on the x axis, node 0 fixed, spring (k, k') of rest length L0, no return springs.
inline Model single_spring(double k, double kp, double L0 = 100.0, double mass = 1.0, double damping = 1.0) {
  ModelBuilder b("single_spring");
  b.add_node(Vec3(0, 0, 0), mass, damping, 0.0, true);
  b.add_node(Vec3(L0, 0, 0), mass, damping, 0.0);
  b.add_spring(0, 1, k, kp, L0);
  return b.build();
}

/// Straight chain along x (or z) of n atoms spaced h (§8.0), ends fixed.
inline Model chain(Index n, double k, double kr, double mass, DuffingSettings duffing, double beta = 0.5,
                   double h = 2.5, bool along_z = false) {
  ModelBuilder b("chain");
  for (Index i = 0; i < n; ++i) {
    const Vec3 p = along_z ? Vec3(0, 0, h * i) : Vec3(h * i, 0, 0);
    b.add_node(p, mass, beta * mass, kr, i == 0 || i == n - 1);
  }
  for (Index i = 0; i + 1 < n; ++i) b.add_spring(i, i + 1, k, duffing);
  return b.build();
}

}  // namespace medspring::testing
