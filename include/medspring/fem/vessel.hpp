// The FEM reference of a vessel (docs/accuracy.md, "The vessel"): the vessel wall as a thick-walled tube of
// quadratic tetrahedra around the SMRM's own rest geometry (its atoms and lumen rings), ends clamped, and
// the SMRM centerline against the centroid of the FEM wall's mid-surface under the same load.
//
//   fem::VesselReference ref(vessel, fem::Material::from_kpa(65, 0.45), {.thickness_ratio = 0.1});
//   fem::VesselFemResult r = ref.solve(20, Vec3(0, 0, -0.05));   // 0.05 N on the band around atom 20
//   MatX3 u_smrm = fem::smrm_centerline_displacement(vessel.model(), 20, Vec3(0, 0, -0.05));
//   fem::CenterlineError e = fem::compare_centerline(u_smrm, r.centerline, 20);
//
// The load: the SMRM carries a force on any node of ring a to atom a (D-14), i.e. it models a load on the
// whole cross-section; the FEM gets the same total force as a uniform traction (fixed direction) over the
// outer wall of the band of the tube within half an atom spacing of atom a (at least one axial cell on each
// side), so that the wall is loaded as a beam, not dented. Units: mm, N, MPa.
#pragma once

#include <vector>

#include "medspring/fem/calculix.hpp"
#include "medspring/fem/matching.hpp"
#include "medspring/models/smrm_vessel.hpp"

namespace medspring::fem {

/// A structured tube of quadratic tetrahedra and where its nodes lie.
struct TubeMesh {
  TetMesh mesh;
  VecX axial;   // per node: position along the tube in atom units (ring i of the input = i)
  VecX radial;  // per node: 0 on the lumen, 1 on the outer wall
  Index rings = 0, spokes = 0;
};

/// Tube between the lumen rings P (#n*M x 3, node i*M + j = spoke j of ring i, rings around the atoms C,
/// #n x 3) and the outer wall C_i + (1 + thickness_ratio) (P_ij - C_i): every axial interval split into
/// `axial_subdivisions` (rings and atoms interpolated linearly), `layers` through the wall, every cell
/// split into 6 tetrahedra (conforming, periodic around), made quadratic. Throws InvalidInput for bad
/// sizes or settings and naming the ring for an element turned inside out (the rings of a sharp bend
/// crossing inside the wall).
TubeMesh tube_mesh(const MatX3& C, const MatX3& P, Index spokes, double thickness_ratio,
                   int axial_subdivisions, int layers = 1);

struct VesselMeshSettings {
  double thickness_ratio = 0.1;  // wall thickness / lumen radius (the SMRM's WallSettings default)
  Index spoke_stride = 2;        // every stride-th spoke of the SMRM ring becomes a FEM node (30 -> 15)
  int axial_subdivisions = 2;    // FEM rings per atom interval
  int layers = 1;                // tetrahedra through the wall: 1 or 2
  FemSettings solver{};
};

/// FEM result of one load.
struct VesselFemResult {
  MatX3 centerline;  // (#atoms x 3) displacement of the centroid of the wall's mid-surface ring, mm
  MatX3 lumen;       // (#S x 3) displacement of the SMRM's rest surface (lumen) nodes, mm
  double solve_seconds = 0;
  bool from_cache = false;
};

class VesselReference {
 public:
  /// Meshes the wall around a structured SMRM vessel (grid layout, rest rings), clamps both end rings.
  VesselReference(const SmrmVessel& vessel, const Material& material,
                  const VesselMeshSettings& settings = {});
  /// The band load of `force` (N) around `atom` (an interior atom).
  VesselFemResult solve(Index atom, const Vec3& force) const;
  const TubeMesh& tube() const { return tube_; }
  const std::vector<Index>& fixed_fem_nodes() const { return problem_.fixed; }
  Index num_atoms() const { return atoms_; }

 private:
  TubeMesh tube_;
  FemProblem problem_;
  MatX6i boundary_;
  BoundarySample lumen_;
  VesselMeshSettings settings_;
  Index atoms_ = 0, sub_ = 1;
};

/// Static equilibrium of a chain model (an SMRM's model()) under `force` on atom `atom`: the atoms'
/// displacements (#n x 3, mm). Throws SolverError when there is no equilibrium.
MatX3 smrm_centerline_displacement(const Model& chain, Index atom, const Vec3& force);

/// Centerline errors: at the loaded atom, RMS and max over the atoms (mm); relative to the FEM
/// displacement of the loaded atom.
struct CenterlineError {
  double loaded_fem = 0, loaded_model = 0;  // |u| at the loaded atom, mm
  double loaded_error = 0;                  // |u_model - u_fem| at the loaded atom, mm
  double rms = 0, max = 0;                  // over all atoms, mm
  double rel(double v) const { return loaded_fem > 0 ? v / loaded_fem : 0.0; }
};
CenterlineError compare_centerline(const MatX3& u_model, const MatX3& u_fem, Index atom);

}  // namespace medspring::fem
