// The FEM reference of an organ and the spring models under the same supports and loads
// (docs/accuracy.md). Used by `medspring accuracy` / `medspring calibrate` and the Python module.
//
//   fem::OrganReference ref(surface, fem::Material::from_kpa(10, 0.45), support, {.max_volume = 400});
//   fem::ContactLoad load{centre, Vec3(0, 0, -0.5), 8.0};
//   MatX3 u_fem = ref.surface_displacement(load);                 // at the surface nodes, mm
//   MatX3 u_spring = fem::spring_displacement(*body, load);       // static equilibrium, mm
#pragma once

#include <Eigen/SparseCore>
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "medspring/fem/calculix.hpp"
#include "medspring/fem/matching.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/models/body.hpp"

namespace medspring::fem {

/// A load spread uniformly over the contact disk |x - centre| < radius of the surface (same total force
/// and distribution on the FEM boundary and on the spring model's surface).
struct ContactLoad {
  Vec3 centre = Vec3::Zero();  // on the surface, mm
  Vec3 force = Vec3::Zero();   // total force, N
  double radius = 8.0;         // contact disk radius a, mm
};

/// The support region by rule: the surface points within `depth` mm of the extreme point along
/// `direction` (e.g. the posterior-most point of a kidney lying on the abdominal wall). Two optional
/// additions for organs that no single slab holds (a curved vessel, docs/accuracy-volumetric.md "The aorta"):
/// `facing_deg` > 0 also holds every surface point whose outward normal lies within that angle of
/// `direction` (a bed along the whole organ), and `caps` holds further extreme regions (direction,
/// depth), e.g. a vessel's cut cap.
struct SupportRule {
  Vec3 direction = Vec3(0, 0, -1);
  double depth = 5.0;       // mm
  double facing_deg = 0.0;  // 0: off; else in (0, 90]
  std::vector<std::pair<Vec3, double>> caps{};
};

struct OrganMeshSettings {
  int subdivisions = 0;      // midpoint subdivisions of the surface before meshing (refinement levels
                             // 1, 2, 3 = 0, 1, 2): the same polyhedron, 4x the faces each time
  double max_volume = 0.0;   // TetGen volume bound, mm^3 (0: none)
  double radius_edge = 0.0;  // TetGen quality bound (0: none, the fewest elements)
  FemSettings solver{};
};

class OrganReference {
 public:
  /// Meshes the closed surface (refused when open, before meshing), fixes the FEM boundary nodes the
  /// support rule picks, and locates the surface nodes on the FEM boundary.
  OrganReference(const SurfaceMesh& surface, const Material& material, const SupportRule& support,
                 const OrganMeshSettings& settings = {});
  /// FEM displacement (#S x 3, mm) of the surface nodes under `load` (cached by CalculiX input).
  /// disk_mean (optional) gets the mean displacement over the load's disk, (1/A) ∫_disk u dA with the
  /// quadratic faces' own interpolation: sum_i w_i u_i over the FEM nodes with the weights of its nodal
  /// forces (disk_load_quadratic / |F|, summing to 1) — the displacement conjugate to the traction.
  /// `nodal`, when given, gets the displacement of every FEM node (mesh().num_nodes() x 3, mm).
  MatX3 surface_displacement(const ContactLoad& load, double* solve_seconds = nullptr,
                             bool* from_cache = nullptr, Vec3* disk_mean = nullptr,
                             MatX3* nodal = nullptr) const;
  const TetMesh& mesh() const { return problem_.mesh; }
  const std::vector<Index>& fixed_fem_nodes() const { return problem_.fixed; }
  const Material& material() const { return problem_.material; }
  const FemProblem& problem() const { return problem_; }  // mesh, material and supports, no loads

 private:
  FemProblem problem_;
  MatX6i boundary_;
  BoundarySample sample_;
  OrganMeshSettings settings_;
};

/// The surface with every triangle split into 4 at its edge midpoints (the same polyhedron).
SurfaceMesh subdivide_midpoint(const SurfaceMesh& surface);

/// Surface nodes of `surface` picked by the rule (the spring model's pinned nodes). The MatX3 form refuses
/// a rule with facing_deg > 0 (it needs the surface's normals: pass the mesh).
std::vector<Index> support_nodes(const MatX3& surface, const SupportRule& rule);
std::vector<Index> support_nodes(const SurfaceMesh& surface, const SupportRule& rule);

/// The rule applied to points P with outward unit normals N (#P x 3; may be empty when facing_deg == 0),
/// among `candidates` (all when empty): the sorted union of the extreme slab, the facing points and the
/// caps. InvalidInput for a zero direction, a negative depth or facing_deg outside [0, 90].
std::vector<Index> apply_support_rule(const MatX3& P, const MatX3& N, const SupportRule& rule,
                                      const std::vector<Index>& candidates = {});

/// Static equilibrium of a spring model (built with the support nodes pinned) under the disk load, as
/// displacement of its surface nodes (#S x 3, mm). The disk load becomes nodal forces on the surface
/// (disk_load_linear) that travel the body's force map. Throws SolverError when there is no equilibrium.
MatX3 spring_displacement(const Body& body, const ContactLoad& load);

/// The mean displacement over the load's disk, (1/A) ∫_disk u dA, of a field u (#V x 3) on the linear
/// triangles (V, F): sum_i w_i u_i with the weights of disk_load_linear (its forces / |F|, summing to 1),
/// the same read-out as OrganReference's disk_mean on the FEM side (docs/accuracy-nonlinear.md, "The load
/// site").
Vec3 disk_mean_linear(const MatX3& V, const MatX3i& F, const ContactLoad& load, const MatX3& u);

/// The DOFs of the model's free nodes: map[3 a + d] is the index of node a's component d among them (-1
/// for pinned nodes); `free` gets their count.
std::vector<Index> free_dof_map(const Model& m, Index& free);
/// K (3 #N x 3 #N) restricted to the free DOFs of `map` (free_dof_map): pinned nodes' rows and columns
/// dropped.
Eigen::SparseMatrix<double> restrict_to_free(const Eigen::SparseMatrix<double>& K,
                                             const std::vector<Index>& map, Index free);

/// The small-strain response: the surface displacement (#S x 3, mm) under each load of the model linearised
/// at rest, K(x0) u = f over the free nodes, with one factorisation of K(x0) for all loads (the static
/// solve factors the tangent at every Newton iteration of every load). Throws SolverError when K(x0) is
/// not positive definite (a mechanism the supports leave free).
std::vector<MatX3> spring_displacement_linear(const Body& body, const std::vector<ContactLoad>& loads);

/// The same plus the local-deformation overlay (§6, eq. 6) of the whole contact force on the surface
/// node nearest the disk centre (BFS patch of 25 nodes; k_loc = body.local_stiffness() when k_loc <= 0).
MatX3 spring_displacement_local(const Body& body, const ContactLoad& load, double k_loc = 0.0);

/// Errors of a spring displacement against the FEM one, over the surface nodes.
struct SurfaceError {
  double contact_fem = 0, contact_model = 0;  // |u| at the contact node, mm
  double contact_error = 0;                   // |u_model - u_fem| at the contact node, mm
  double rms = 0, max = 0;                    // over all surface nodes, mm
  double rel(double v) const { return contact_fem > 0 ? v / contact_fem : 0.0; }
};
SurfaceError compare(const MatX3& u_model, const MatX3& u_fem, Index contact);

/// The weight w of the calibration's site term (CalibrationCase::site_weight; CLI --site-weight W, Python
/// site_weight=W; docs/accuracy-calibration.md, "The site weight"), declared once: default 1 (the cost as it
/// was, bit for bit), each value finite and >= 0 (0: the surface term alone). InvalidInput "must be a
/// number >= 0 (got 'TEXT')" otherwise; the text form reads one number.
inline constexpr double kDefaultSiteWeight = 1.0;
double checked_site_weight(double w);
double parse_site_weight(const std::string& text);

/// Calibration (docs/accuracy.md): multipliers m (one per stiffness family of the model) fitted in log
/// space by coordinate descent (golden section per family over [1e-3, 1e3], then a second sweep within
/// a factor 10) to minimise, over the training loads, the mean squared surface error plus the squared
/// site error (CalibrationCase), both relative to the largest FEM displacement of the load. response(m, load)
/// is the model's surface displacement (#S x 3) with its families scaled by m; a SolverError counts as an
/// infinite cost. Returns the multipliers.
///
/// The site term reads the contact node by default. With `mean_weights` it reads the disk mean instead
/// (docs/accuracy-calibration.md): the model's mean displacement over the loaded disk, sum_i w_i u_i over
/// the response's rows, against the FEM's (`fem_mean`, OrganReference's disk_mean), as the FEM's own
/// read-out is. The response may have more rows than u_fem (a refined model surface, the FEM-sampled nodes
/// first): the surface and node terms use its first u_fem.rows() rows, the disk mean all of them.
struct CalibrationCase {
  ContactLoad load;
  MatX3 u_fem;                                           // FEM displacement of the surface nodes
  Index contact = 0;                                     // surface node nearest the disk centre
  std::vector<std::pair<Index, double>> mean_weights{};  // (response row, weight): the disk mean; empty: node
  Vec3 fem_mean = Vec3::Zero();                          // the FEM's disk mean (with mean_weights)
  double site_weight = kDefaultSiteWeight;               // w on the site term (checked_site_weight)
};

/// The disk-mean weights of `load` on the linear triangles (V, F): the nonzero (vertex, w_i) of
/// disk_load_linear / |F|, summing to 1 (disk_mean_linear's weights), for CalibrationCase::mean_weights.
std::vector<std::pair<Index, double>> disk_mean_weights(const MatX3& V, const MatX3i& F,
                                                        const ContactLoad& load);

/// The case's site read-out of a response u: the contact node's displacement, or the disk mean when the case
/// has mean_weights; and the FEM's (u_fem at the contact node, or fem_mean).
Vec3 site_readout(const CalibrationCase& c, const MatX3& u);
Vec3 fem_site_readout(const CalibrationCase& c);

/// The calibration's site term (docs/accuracy-calibration.md), one declaration for `medspring accuracy` /
/// `calibrate` (--site-readout) and Python's medspring.calibrate (site_readout=): the node under the disk
/// centre, or the mean displacement over the loaded disk (CalibrationCase::mean_weights, the FEM's read-out).
enum class SiteReadout { Node, DiskMean };
/// "node", "disk-mean".
std::string_view to_string(SiteReadout r);
/// The text's read-out; InvalidInput "must be node or disk-mean (got 'TEXT')" otherwise.
SiteReadout parse_enum(const std::string& text, SiteReadout*);

/// The training forces of a calibration (N; CLI --train-force F[,F...], Python train_forces=[...]), checked
/// once for both: at least one, each finite and > 0. InvalidInput "must be > 0 N or a list of such (got
/// 'ITEM')" or "must list at least one force". The text form reads a comma list ("0.2,1").
std::vector<double> checked_train_forces(const std::vector<double>& forces);
std::vector<double> parse_train_forces(const std::string& text);
using Response = std::function<MatX3(const VecX& multipliers, const ContactLoad& load)>;
VecX calibrate_multipliers(const Response& response, Index families,
                           const std::vector<CalibrationCase>& training, int sweeps = 2);

/// Calibration of a model with two stiffness families whose common scale c divides its small-strain
/// displacement (the volumetric kind: springs, volume terms; docs/volumetric.md): a golden-section search
/// over the log ratio r = m1 / m0 in [1e-2, 1e2] (`evaluations` responses) with c in closed form, the
/// least-squares fit of u / c in the cost of calibrate_multipliers. response(m, loads) returns the
/// displacement under every training load at once (e.g. spring_displacement_linear: one factorisation per
/// ratio). Returns (c, c r).
using BatchResponse =
    std::function<std::vector<MatX3>(const VecX& multipliers, const std::vector<ContactLoad>& loads)>;
VecX calibrate_scale_and_ratio(const BatchResponse& response, const std::vector<CalibrationCase>& training,
                               int evaluations = 18);

/// The cost calibrate_multipliers minimises, of multipliers m over the training loads (mean squared surface
/// error plus the squared site error times the case's site_weight, contact node or disk mean as the case
/// reads it, each relative to the load's largest FEM displacement);
/// infinite where the response throws SolverError.
double calibration_cost(const Response& response, const VecX& m,
                        const std::vector<CalibrationCase>& training);

/// Refinement of multipliers on the full (nonlinear) response, from a start such as the small-strain fit of
/// calibrate_scale_and_ratio (docs/accuracy-nonlinear.md, "Calibration of the nonlinear response").
/// Coordinate descent in log space, the families in order of their span (widest first), each by a
/// golden-section search within a factor spans[f] of its current value (spans[f] <= 1: held), `probes`
/// responses per family and sweep, each later sweep within the square root of the span. Only a probe that
/// lowers the cost is taken, so the cost never rises above the start's. Families the start lacks
/// (start.size() < spans.size()) start at 1.
struct RefineResult {
  VecX m;                 // the multipliers
  double start_cost = 0;  // calibration_cost at the start
  double cost = 0;        // at m
  int evaluations = 0;    // calls of calibration_cost (each: one response per training load)
};
RefineResult refine_multipliers(const Response& response, const VecX& start, const std::vector<double>& spans,
                                const std::vector<CalibrationCase>& training, int probes = 8, int sweeps = 1);

/// The volumetric kind's calibration on the full response (docs/accuracy-nonlinear.md, "Calibration of the
/// nonlinear response"): the multipliers (springs, volume terms, compression coefficient c) that response(m,
/// load) takes, fitted over (overall scale s, volume / spring ratio r, c multiplier), m = (s, s r, c). Two
/// starts: the small-strain fit (calibrate_scale_and_ratio, c multiplier 1) and the closed forms (1, 1, 1).
/// From each, c alone within a factor 32 (refine_multipliers, `probes` responses); then from the better of
/// the two, all three for `sweeps` sweeps within factors 1.5 (s), 4 (r) and 4 (c). The small-strain fit alone
/// is biased wherever the training loads compress beyond the linear range (it buys the missing stiffening
/// with a larger volume multiplier), hence the second start.
inline constexpr double kVolumetricRefineSpans[3] = {1.5, 4.0, 32.0};  // s, r and c, c first
struct VolumetricFit {
  VecX m;                                               // springs, volume terms, c multiplier
  RefineResult refine;                                  // over (s, r, c)
  bool from_small_strain = false;                       // the start taken
  double small_strain_cost = 0, closed_forms_cost = 0;  // calibration_cost of the two starts
};
VolumetricFit calibrate_volumetric_nonlinear(const Response& response, const VecX& small_strain,
                                             const std::vector<CalibrationCase>& training, int probes = 8,
                                             int sweeps = 2);

/// The opt-in surface-layer family of the volumetric calibration (docs/accuracy-calibration.md, "A
/// surface-layer spring family"; CLI --fit-surface-springs): from a VolumetricFit's multipliers (springs,
/// volume terms, c) and q = 1, all four (overall scale s, ratio r, c, q) refined on the full response for
/// `sweeps` sweeps within factors 1.5 (s), 4 (r), 4 (c) and kSurfaceSpringSpan (q, first).
/// response(m, load) takes m = (springs, volume terms, c multiplier, surface springs) with q =
/// VolumetricSettings::surface_spring_scale, appended after the existing multipliers. Returns the four
/// multipliers and the refinement (its start_cost: the fit's own cost).
inline constexpr double kSurfaceSpringSpan = 8.0;
struct SurfaceSpringFit {
  VecX m;  // springs, volume terms, c multiplier, surface springs
  RefineResult refine;
};
SurfaceSpringFit refine_surface_springs(const Response& response, const VecX& fit,
                                        const std::vector<CalibrationCase>& training, int probes = 8,
                                        int sweeps = 2);

}  // namespace medspring::fem
