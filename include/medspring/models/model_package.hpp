// Model packages: a built model (the real kidney, the real aorta, a phantom) saved as the inputs its
// engine-layer constructor needs, so that anything linking only the engine (the WebAssembly build, a
// simulator without VTK/CGAL) rebuilds it exactly, and can rebuild it with other tissue parameters.
//
//   // natively, after the VTK/CGAL pipeline built `body`:
//   save_model_package("kidney.msm", package_of(*body, "real kidney", "HuBMAP left kidney, 458 + 42"));
//   // anywhere (wasm included):
//   ModelPackage p = decode_model_package(bytes);        // IoError / InvalidInput naming what is wrong
//   BodyPtr body = make_body(p);
//   TissueParams t = tissue_params(p); t.k *= 2; set_tissue_params(p, t); body = make_body(p);
//
// File (docs/model_packages.md): magic "MSPRMODL", version u32, flags u32, payload size u64, FNV-1a 64 of the
// payload, then the payload (little-endian): name, description, kind, surface (V, F), grid, the kind's
// inputs and settings, and the fingerprint of the model it was saved from.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/models/body.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_tree.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/models/volumetric_body.hpp"

namespace medspring {

inline constexpr char kModelPackageMagic[9] = "MSPRMODL";
inline constexpr std::uint32_t kModelPackageVersion = 10;    // 2: smrm bending mode and wall (issue 17);
                                                             // 3: hybrid settings by declared name (issue 22)
                                                             // 4: volumetric mass_scaling_dt (issue 23)
                                                             // 5: surface and smrm settings by declared
                                                             //    name (issue 22)
                                                             // 6: volumetric compression (issue 23)
                                                             // 7: volumetric thin_tet, q_max (issue 23)
                                                             // 8: volumetric surface_spring_scale (issue 23)
                                                             // 9: volumetric overlay_compliance (issue 23)
                                                             // 10: volumetric volume_precision (issue 23;
                                                             //     earlier packages read double)
inline constexpr std::uint32_t kModelPackageMinVersion = 1;  // version 1 smrm: bending = chain.kb

/// Everything needed to rebuild a Body with the engine layers alone.
struct ModelPackage {
  std::string name;         // shown to users ("real kidney")
  std::string description;  // one line: source data, sizes
  std::string kind;         // Body::kind(): "surface", "hybrid", "smrm" or "smrm_tree"
  SurfaceMesh surface;      // rest surface (mm) and its triangles
  GridLayout grid;          // rings x spokes of a tube grid, if any
  // surface
  SurfaceBodyParams surface_params;
  // hybrid
  MatX3 atoms;  // rest atoms (#A x 3, mm), hybrid and smrm
  HybridSettings hybrid;
  // smrm
  VecX atom_radius;        // (#n) local radius, mm
  SurfaceBinding binding;  // how the surface nodes ride on the atoms
  SmrmSettings smrm;       // smrm and smrm_tree (the tree's SmrmTreeSettings::vessel)
  // smrm_tree: the centerline tree it is built from (SmrmTree resamples it deterministically)
  CenterlineTree tree;
  // volumetric (issue 23): the tetrahedral mesh (its F is surface.F) and the settings (E, nu, ...)
  VolumetricMesh volumetric_mesh;
  VolumetricSettings volumetric;
  /// model_fingerprint() of the model the package was made from (0 = unknown). make_body does not
  /// require a match (another compiler may round the rest lengths differently); check_fingerprint does.
  std::uint64_t fingerprint = 0;
};

/// The package of a built body (SurfaceBody, HybridKidney, SmrmVessel or SmrmTree).
ModelPackage package_of(const Body& body, const std::string& name = "", const std::string& description = "");

/// Rebuilds the body. Throws InvalidInput naming the package and the part at fault.
BodyPtr make_body(const ModelPackage& package);

/// File bytes of a package (header + payload) and the inverse. decode throws IoError "<what>: ..." for
/// truncated, corrupted (checksum), unknown-version or malformed bytes, and InvalidInput for contents
/// that are well-formed but invalid (indices out of range, non-finite coordinates, bad parameters).
std::string encode_model_package(const ModelPackage& package);
ModelPackage decode_model_package(std::string_view bytes, const std::string& what = "model package");

/// Atomic write (temporary file + rename) and read of a package file; errors name the file.
void save_model_package(const std::filesystem::path& path, const ModelPackage& package);
ModelPackage read_model_package(const std::filesystem::path& path);

/// True when the model rebuilt from the package has the stored fingerprint (or none was stored).
bool check_fingerprint(const ModelPackage& package, const Body& rebuilt);

/// The tissue parameters a user tunes at run time, common to the three kinds:
///   k     spring stiffness of the simulated springs, N/mm (surface: k; hybrid: surface springs, the
///         spokes and centerline springs keep their ratio to it; smrm: chain springs k_cl)
///   eta   Duffing strength (k' = eta k / L0^2, D-3); nonlinear = false makes every spring linear
///   kr    return-spring stiffness, N/mm
///   beta  mass-proportional damping, 1/ms
struct TissueParams {
  double k = 0.0, eta = 1.0, kr = 0.0, beta = 0.0;
  bool nonlinear = true;
};
TissueParams tissue_params(const ModelPackage& package);
/// Sets the parameters (validated: k > 0, eta >= 0, kr >= 0, beta >= 0, all finite; InvalidInput
/// naming the parameter otherwise). Rebuild with make_body.
void set_tissue_params(ModelPackage& package, const TissueParams& params);

}  // namespace medspring
