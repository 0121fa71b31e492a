// The hybrid mass-spring on the paper's vessel tube (ALGORITHMS.md D-18, the "mass-spring" column of
// Tables I and II): the kidney's hybrid model (§4) applied to the vessel geometry, so that mass-spring
// and SMRM are timed on the same vessel. Model kind "hybrid".
//
//   TubeHybridBody tube({.nonlinear = true});     // 40 x 30 = 1200 surface nodes + 40 atoms
//   Simulation sim(std::make_shared<TubeHybridBody>(tube), settings);
//
// Layout: surface node i*spokes + j (ring i, spoke j; tube(rings, spokes, spacing, radius) of
// geometry/phantoms.hpp), then the atoms, one per ring on the tube's axis (x). Springs: the tube grid's
// edges (k_surf), the centerline between consecutive atoms (k_cl), one spoke from every surface node to
// its ring's atom (k_spoke). The first and last rings and atoms are fixed. Per-node parameters, spring
// constants and the Duffing law are the kidney's (HybridSettings, §9).
#pragma once

#include <vector>

#include "medspring/models/body.hpp"
#include "medspring/models/hybrid_kidney.hpp"

namespace medspring {

struct TubeHybridSettings {
  Index rings = 40, spokes = 30;  // surface grid
  double spacing = 2.5;           // mm between rings (and atoms)
  double radius = 3.0;            // mm
  bool nonlinear = true;          // Duffing springs (else every spring linear)
  HybridSettings hybrid{};        // node parameters, k_surf, k_spoke, k_cl and the Duffing law
};

class TubeHybridBody final : public Body {
 public:
  explicit TubeHybridBody(const TubeHybridSettings& settings = {});

  std::string kind() const override { return "hybrid"; }
  const Model& model() const override { return model_; }
  const MatX3i& faces() const override { return F_; }
  const MatX3& rest_surface() const override { return rest_; }
  void map_to_surface(const State& state, MatX3& surface) const override;
  void transfer_force(Index node, const Vec3& F, MatX3& f_dof) const override;
  GridLayout grid() const override { return {settings_.rings, settings_.spokes}; }
  double local_stiffness() const override { return settings_.hybrid.k_surf; }
  std::vector<std::uint8_t> fixed_surface_nodes() const override { return fixed_surface_; }

  /// DOF index of atom a (atoms follow the surface nodes).
  Index atom_dof(Index a) const { return num_surface_nodes() + a; }
  const TubeHybridSettings& settings() const { return settings_; }

 private:
  TubeHybridSettings settings_;
  Model model_;
  MatX3i F_;
  MatX3 rest_;
  std::vector<std::uint8_t> fixed_surface_;
};

}  // namespace medspring
