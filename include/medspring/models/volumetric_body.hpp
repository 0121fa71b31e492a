// The volumetric spring organ (issue 23, docs/volumetric.md): the nodes of a linear tetrahedral mesh of
// the organ (surface nodes first, then interior nodes), one spring per tetrahedron edge and one volume
// term per tetrahedron, both with constants derived from the tissue's Young's modulus E and Poisson
// ratio nu. Model kind "volumetric". The surface nodes are the first DOFs, so the visible surface is the
// organ's surface (identity map): loads, tools, local deformation, output and the viewer work unchanged.
//
//   VolumetricMesh vm = ...;                 // from fem::volumetric_mesh (TetGen) or by hand
//   VolumetricSettings s;  s.E_kPa = 10;  s.nu = 0.45;  s.fixed = support;
//   VolumetricBody body(vm, s);
//
// Stiffness rule (derivation in docs/volumetric.md): with mu = E / 2(1+nu), lambda = E nu / (1+nu)(1-2nu),
// every tetrahedron t of volume V_t adds k = (5/2) mu V_t / L_e^2 to each of its six edge springs (so that
// the isotropic part of its spring stiffness tensor has shear modulus mu and Lame lambda_s = mu, the
// Cauchy relation of central springs), and a volume term of modulus kv = lambda - mu that brings the bulk
// modulus to the exact lambda + 2 mu / 3 for every tetrahedron shape. nu < 1/4 would need kv < 0: there
// kv = 0 and the model's Poisson ratio stays near 1/4 (said in the build warnings).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/models/body.hpp"

namespace medspring {

using MatX4i = Eigen::Matrix<Index, Eigen::Dynamic, 4, Eigen::RowMajor>;

/// A linear tetrahedral mesh whose first `surface_nodes` nodes are the vertices of the surface triangles F
/// (mm). Tetrahedra may have either orientation (they are reoriented).
struct VolumetricMesh {
  MatX3 X;   // nodes (#N x 3), surface nodes first
  MatX4i T;  // tetrahedra (#T x 4)
  MatX3i F;  // surface triangles over nodes [0, surface_nodes), outward
  Index surface_nodes = 0;
};

/// VolumetricSettings::compression by default (docs/accuracy-nonlinear.md, "Compression stiffening").
inline constexpr double kDefaultVolumetricCompression = 32.0;

/// How a build sizes the interior of the tetrahedral mesh (fem::volumetric_mesh, docs/volumetric-mesh.md).
/// volume: one TetGen volume bound everywhere, rescaled until the node count is near the target (the interior
/// can be much finer than the surface). surface: TetGen's sizing function (-m): the size at each surface
/// vertex is the mean length of its surface edges, growing inwards with depth, so no tetrahedron at the
/// surface is smaller than its edges and the interior is coarser; the node target is then an upper bound.
enum class MeshSizing { Volume, Surface };
const char* to_string(MeshSizing s);
/// "volume" | "surface"; InvalidInput naming the text otherwise.
MeshSizing parse_mesh_sizing(const std::string& text);
inline MeshSizing parse_enum(const std::string& text, MeshSizing*) {
  return parse_mesh_sizing(text);
}

/// The opt-in correction term on thin tetrahedra (physics/thin_tet_correction.hpp, docs/volumetric-mesh.md,
/// "A correction term for thin tetrahedra"). off (default); scale_springs: each flagged tetrahedron's share
/// of its six springs is scaled down and the term supplies the rest of P1's stiffness (rule + term = P1 at
/// rest); clip: the positive part of P1 minus the rule, springs unchanged.
enum class ThinTetMode { Off, ScaleSprings, Clip };
const char* to_string(ThinTetMode m);
/// "off" | "scale_springs" | "clip"; InvalidInput naming the text otherwise.
ThinTetMode parse_thin_tet_mode(const std::string& text);
inline ThinTetMode parse_enum(const std::string& text, ThinTetMode*) {
  return parse_thin_tet_mode(text);
}
/// Precision of the volume passes of the symplectic sub-steps (issue 23, docs/volumetric-speed.md "A
/// single-precision volume pass"; physics/model.hpp set_volume_single_precision): float (the default since
/// issue 23, h23b: the volume and compression terms' forces in single precision, and since the session of
/// 2026-11-27 evening also the frame's last sub-step with the stable step's bound; since the session of
/// 2026-11-27 night the springs of every sub-step too, docs/volumetric-speed.md "Float springs"; the
/// inversion count, energies, Hessians and static solves stay double) or double.
/// Model packages store it from version 10 (earlier packages read double, what they were run with).
enum class VolumePrecision { Double, Float };
const char* to_string(VolumePrecision p);
/// "double" | "float"; InvalidInput naming the text otherwise.
VolumePrecision parse_volume_precision(const std::string& text);
inline VolumePrecision parse_enum(const std::string& text, VolumePrecision*) {
  return parse_volume_precision(text);
}
/// VolumetricSettings::thin_tet_q_max by default: tetrahedra with h_min / L_max below it get the term.
inline constexpr double kDefaultThinTetQMax = 0.3;

struct VolumetricSettings {
  double E_kPa = 10.0;             // Young's modulus, kPa (> 0)
  double nu = 0.45;                // Poisson ratio, (-1, 0.5)
  double density = 1.05e-3;        // g/mm^3 (lumped: a quarter of each tetrahedron's mass per corner)
  double beta = 0.5;               // mass-proportional damping d = beta m, 1/ms
  double min_mass_fraction = 0.5;  // mass scaling: every node weighs at least this fraction of the mean node
                                   // mass (small elements would otherwise set a tiny stable step; statics
                                   // unaffected)
  double mass_scaling_dt = 0.0;    // ms: selective mass scaling for this sub-step (0 = off, the default). A
                                 // node whose block-Gershgorin row at rest would need a smaller step gets the
                                 // mass for it (slivers; statics unaffected, the added mass is in stats)
  std::optional<double> return_k;  // N/mm per surface node; default: 0 with supports, else 0.02
  double spring_scale = 1.0;       // calibration multipliers of the spring and volume families
  double volume_scale = 1.0;
  // Opt-in surface-layer family (docs/accuracy-calibration.md, "A surface-layer spring family"): a further
  // multiplier of the springs whose two ends are both surface nodes (the edges of the organ's surface and any
  // chord between two surface nodes), on top of spring_scale. 1 (the default) leaves every spring as it was.
  double surface_spring_scale = 1.0;
  // The compliance multiplier a of the local overlay (eq. 6, docs/local-deformation.md, "The volumetric kind:
  // the calibrated disk overlay"): the patch springs get k_loc / a, k_loc = local_stiffness() (or the scene's
  // local.k_loc); a = 0 turns the overlay off. Fitted by `medspring calibrate --kind volumetric --linear
  // --local` (docs/accuracy-calibration.md). The default is 0, off: the volumetric body resolves the contact
  // with its own interior, and the uncalibrated overlay (a = 1) left the load site far too soft (held-out
  // site error 68-172 % against 4-19 % without it, docs/accuracy-calibration.md). Packages before version 9
  // read 1, the overlay they were written and run with.
  double overlay_compliance = 0.0;
  // Opt-in (off by default): measure the mesh's effective moduli (models/volumetric_moduli.hpp) and multiply
  // spring_scale and volume_scale so that they match (mu, lambda). The body then stores the corrected scales
  // and this flag off (settings()), so a model package rebuilds the same model. ~1 s per 2,000 nodes.
  bool moduli_correction = false;
  // Compression stiffening (physics/compression_terms.hpp, docs/volumetric.md): a term kc V0 h(J) per
  // tetrahedron with kc = compression * mu * spring_scale, zero with its first two derivatives at rest (the
  // small-strain moduli are unchanged) and stiffening as the tetrahedron is squeezed, like the Neo-Hookean
  // solid. Dimensionless, >= 0 (0 = off); the default is the measured choice of docs/accuracy.md.
  double compression = kDefaultVolumetricCompression;
  DuffingSettings duffing{DuffingMode::Linear};  // Duffing term of the springs (off by default)
  std::vector<Index> fixed;                      // pinned surface nodes
  Index mesh_nodes = 2000;  // node count aimed at when a scene build tetrahedralises the surface (TetGen)
  MeshSizing mesh_sizing = MeshSizing::Volume;  // how that build sizes the interior
  ThinTetMode thin_tet = ThinTetMode::Off;      // correction term on thin tetrahedra (opt-in)
  double thin_tet_q_max = kDefaultThinTetQMax;  // ... on those with h_min / L_max below this, (0, 1]
  VolumePrecision volume_precision = VolumePrecision::Float;  // the sub-steps' volume and spring passes
};

/// The declaration of VolumetricSettings (core/params.hpp): the "parameters" of a volumetric model in a
/// scene, their checks, `run --set model.parameters.NAME=VALUE`, the table in docs/parameters.md. E and nu
/// come from the model's "material".
template <ParamOf<VolumetricSettings> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"nodes", "", "node count aimed at when the surface is tetrahedralised (TetGen)"}.at_least(10),
    s.mesh_nodes);
  v(ParamSpec{"mesh_sizing", "",
              "interior of that mesh: volume (one volume bound, about `nodes`) or surface (no finer than the "
              "surface's edges, coarser inside; `nodes` at most; docs/volumetric-mesh.md)"},
    s.mesh_sizing);
  v(ParamSpec{"density", "g/mm^3", "tissue density (lumped: a quarter of each tetrahedron per corner)"}
        .positive(),
    s.density);
  v(ParamSpec{"beta", "1/ms", "mass-proportional damping, d = beta m"}.nonnegative(), s.beta);
  v(ParamSpec{"return_k", "N/mm", "return spring per surface node; null: 0 with fixed nodes, else 0.02"}
        .nonnegative()
        .json_key("k_r"),
    s.return_k);
  v(ParamSpec{"spring_scale", "", "calibration multiplier of the edge springs"}.positive(), s.spring_scale);
  v(ParamSpec{"volume_scale", "", "calibration multiplier of the volume terms"}.nonnegative(),
    s.volume_scale);
  v(
      ParamSpec{
          "surface_spring_scale", "",
          "further multiplier of the springs whose two ends are surface nodes (docs/accuracy-calibration.md)"}
          .positive(),
      s.surface_spring_scale);
  v(ParamSpec{"overlay_compliance", "",
              "compliance multiplier a of the local overlay: patch springs k_loc / a; 0 = overlay off, the "
              "default: the interior carries the contact (docs/local-deformation.md)"}
        .nonnegative(),
    s.overlay_compliance);
  v(ParamSpec{"compression", "", "compression stiffening c: kc = c mu spring_scale per tetrahedron (0 = off)"}
        .nonnegative(),
    s.compression);
  v(ParamSpec{"mass_scaling_dt", "ms", "selective mass scaling for this sub-step (0 = off)"}.nonnegative(),
    s.mass_scaling_dt);
  v(ParamSpec{"min_mass_fraction", "", "every node weighs at least this fraction of the mean node mass"}
        .nonnegative(),
    s.min_mass_fraction);
  v(
      ParamSpec{
          "moduli_correction", "",
          "scale springs and volume terms so the mesh's measured moduli match E and nu (~1 s / 2,000 nodes)"},
      s.moduli_correction);
  v(ParamSpec{"duffing", "", "Duffing law of the edge springs (linear unless the model is nonlinear)"},
    s.duffing);
  v(ParamSpec{"thin_tet", "",
              "correction term on thin tetrahedra: off, scale_springs (rule + term = P1 at rest) or clip "
              "(docs/volumetric-mesh.md)"},
    s.thin_tet);
  v(ParamSpec{"thin_tet_q_max", "", "the term on tetrahedra with h_min / L_max below this"}
        .positive()
        .at_most(1),
    s.thin_tet_q_max);
  v(ParamSpec{"volume_precision", "",
              "volume and spring passes of the sub-steps, the stable step's bound included: float, or "
              "double (the former default; docs/volumetric-speed.md)"},
    s.volume_precision);
  v(ParamSpec{"fixed", "", "pinned surface nodes"}, s.fixed);
  v(ParamSpec{"E_kPa", "kPa", "Young's modulus, from model.material"}.positive().set_by_program(), s.E_kPa);
  v(ParamSpec{"nu", "", "Poisson ratio, from model.material"}
        .greater_than(-1)
        .at_most(0.5, true)
        .set_by_program(),
    s.nu);
}

struct VolumetricStats {
  Index nodes = 0, surface_nodes = 0, interior_nodes = 0, tetrahedra = 0, springs = 0;
  double volume_mm3 = 0, mu = 0, lambda = 0, kv = 0;  // moduli in N/mm^2
  // compression-stiffening modulus (N/mm^2; 0: off)
  double kc = 0;
  double min_tet_volume = 0;
  double mass_g = 0;               // total mass of the nodes, after the floor and the mass scaling
  double added_mass_fraction = 0;  // mass added by min_mass_fraction and mass_scaling_dt / lumped mass
  Index scaled_nodes = 0;          // nodes whose mass mass_scaling_dt raised
  // moduli_correction: the multipliers applied and the effective mu, K of the mesh / target before them
  double spring_correction = 1, volume_correction = 1, mu_ratio_before = 0, K_ratio_before = 0;
  // surface_spring_scale: the springs whose two ends are surface nodes (the ones it scales)
  Index surface_springs = 0;
  // thin_tet: tetrahedra with a term, and the mean factor on their spring share (1 with clip)
  Index thin_tets = 0;
  double thin_spring_factor = 1;
};

class VolumetricBody final : public Body {
 public:
  /// Validates and builds: E <= 0, nu outside (-1, 0.5), inverted or degenerate tetrahedra, a surface
  /// that is not the mesh's boundary, an interior node outside the surface, and supports (fixed nodes,
  /// no return springs) that leave a rigid motion free are refused with InvalidInput naming the defect.
  VolumetricBody(const VolumetricMesh& mesh, const VolumetricSettings& settings = {},
                 std::string name = "volumetric");
  std::string kind() const override { return "volumetric"; }
  const Model& model() const override { return model_; }
  const MatX3i& faces() const override { return F_; }
  const MatX3& rest_surface() const override { return rest_surface_; }
  void map_to_surface(const State& state, MatX3& surface) const override;
  void transfer_force(Index node, const Vec3& F, MatX3& f_dof) const override;
  double local_stiffness() const override { return k_local_; }
  double local_compliance() const override { return settings_.overlay_compliance; }
  bool distributed_local() const override { return true; }
  std::vector<std::uint8_t> fixed_surface_nodes() const override;
  const VolumetricSettings& settings() const { return settings_; }
  const VolumetricMesh& mesh() const { return mesh_; }
  const VolumetricStats& stats() const { return stats_; }
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  Model model_;
  VolumetricMesh mesh_;
  MatX3i F_;
  MatX3 rest_surface_;
  VolumetricSettings settings_;
  VolumetricStats stats_;
  double k_local_ = 0.05;
  std::vector<std::string> warnings_;
};

/// Lame parameters (N/mm^2) from E (kPa) and nu; throws InvalidInput naming `where` for E <= 0 or nu
/// outside (-1, 0.5).
void lame_parameters(double E_kPa, double nu, double& mu, double& lambda, const std::string& where);

/// Generalised winding number of the closed surface (V, F) at p: ~1 inside, ~0 outside.
double winding_number(const MatX3& V, const MatX3i& F, const Vec3& p);

}  // namespace medspring
