// The immutable physics model: nodes, springs, return springs, pins (ALGORITHMS.md §1).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/physics/compression_terms.hpp"
#include "medspring/physics/spring_law.hpp"
#include "medspring/physics/thin_tet_correction.hpp"
#include "medspring/physics/volume_terms.hpp"

namespace medspring {

/// Springs as a struct of arrays; spring s joins nodes i[s] and j[s].
struct Springs {
  std::vector<Index> i, j;  // end nodes (#S)
  std::vector<double> L0;   // rest length (#S), mm
  std::vector<double> k;    // linear stiffness (#S), N/mm, >= 0
  std::vector<double> kp;   // cubic stiffness k' (#S), N/mm^3 (0: linear; > 0 hard; < 0 soft)

  Index size() const { return static_cast<Index>(i.size()); }
  void reserve(Index n);
  /// Appends a spring; returns its index.
  Index add(Index a, Index b, double rest_length, double stiffness, double cubic = 0.0);
};

/// Optional discrete bending springs of a chain (§5.2): E_b = k_b/2 |D_i - D_i^0|^2 with
/// D_i = x_a - 2 x_b + x_c.
struct BendingTerms {
  std::vector<Index> a, b, c;  // (#B) triples, b is the middle node
  VecX kb;                     // (#B) N/mm
  MatX3 D0;                    // (#B x 3) rest second differences, mm
  Index size() const { return static_cast<Index>(a.size()); }
};

/// Each node's spring ends for the gather pass of the serial symplectic step (physics/spring_gather.hpp),
/// derived by finalize(). Slot s is spring s seen from its end i, slot #S + s from its end j, slot 2 #S
/// is zero (padding). Node a's slots, in increasing spring index: the first `width` in
/// row[a * width ...] (padded with 2 #S), the rest in extra[extra_begin[a] .. extra_begin[a + 1]).
/// row and extra hold byte offsets of the slots (slot * 32: four doubles per slot), not slot indices.
/// Empty (width 0) where the gather pass does not apply: more than kSpringGatherMaxSprings springs,
/// soft springs, bending or volume terms.
struct SpringGather {
  int width = 0;
  Index nodes = 0, springs = 0;
  std::vector<Index> row;          // (#N x width)
  std::vector<Index> extra_begin;  // (#N + 1)
  std::vector<Index> extra;
  bool empty() const { return width == 0; }
};
/// Largest model (springs) that gets a SpringGather: its slot buffer (64 bytes per spring, 1 MB here)
/// stays in the core's cache. Measured (docs/performance.md): 22 % faster than the scatter pass at 3.5k
/// to 9k springs, 11 % at 14k, 1.5x slower at 30k and 2-3x slower at 300k springs.
inline constexpr Index kSpringGatherMaxSprings = Index{1} << 14;

/// Everything that does not change while simulating. Build with ModelBuilder or fill the fields and
/// call finalize(), which validates the model and computes the derived quantities.
struct Model {
  std::string name = "model";
  MatX3 x0;                         // rest positions (#N x 3), mm
  VecX mass;                        // (#N) g, > 0
  VecX damping;                     // (#N) absolute damping d_i, g/ms (= N ms/mm), >= 0
  VecX kr;                          // (#N) return-spring stiffness, N/mm, >= 0 (D-2: always linear)
  std::vector<std::uint8_t> fixed;  // (#N) 1 = pinned at x0
  Springs springs;
  BendingTerms bending;
  VolumeTerms volume;  // volumetric spring models (issue 23): one term per tetrahedron
  // their optional compression stiffening (issue 23, compression_terms.hpp), one term per tetrahedron
  CompressionTerms compression;
  // opt-in correction terms on thin tetrahedra (issue 23, thin_tet_correction.hpp; empty by default)
  ThinTetCorrections thin;
  // opt-in single-precision volume pass for the sub-steps without the stable step's bound (issue 23,
  // docs/volumetric-speed.md; set_volume_single_precision): its float rest data, rebuilt by finalize();
  // null (the default): every volume pass in double
  std::shared_ptr<const VolumeTermsF32> volume_f32;

  // Derived by finalize():
  VecX inv_k;  // (#S) 1/k (0 when k = 0), for the run-time stability estimate
  std::vector<Index> free_nodes;
  SpringGather gather;      // the serial symplectic step's gather pass (empty: the scatter pass is used)
  double omega_rest = 0.0;  // power-iteration estimate of omega_max at rest x 1.05 (rad/ms)
  double omega_gershgorin = 0.0;  // Gershgorin bound at rest (rad/ms)
  bool has_soft_springs = false;
  bool finalized = false;

  Index num_nodes() const { return static_cast<Index>(x0.rows()); }
  Index num_springs() const { return springs.size(); }
  /// 0.8 * 2 / omega_rest: the stable step at rest (ms). See stability.hpp for the run-time bound.
  double dt_safe_rest(double safety = 0.8) const { return safety * 2.0 / omega_rest; }
};

/// Validates every field (sizes, finiteness, signs, index ranges, self-springs, zero rest lengths)
/// and computes the derived quantities. Throws InvalidInput naming the model and the element,
/// e.g. "kidney: springs[12].k: must be >= 0 (got -1)".
void finalize(Model& model);

/// The opt-in single-precision volume pass (issue 23, docs/volumetric-speed.md "A single-precision volume
/// pass"): with `on`, builds model.volume_f32 from the finalized volume terms (and their fused compression
/// terms), so that the symplectic step's sub-steps evaluate them in float, the frame's last with the stable
/// step's bound (the inversion count, the energies, Hessians and static solves stay double); off clears it.
/// Throws InvalidInput naming the model when `on` and it has no finalized volume terms.
void set_volume_single_precision(Model& model, bool on);

/// Per-node parameters used by builders.
struct NodeParams {
  double mass = 0.3;       // g
  double beta = 0.5;       // mass-proportional damping, d = beta m (1/ms)
  double return_k = 0.02;  // N/mm
};

/// Incremental construction of a Model.
class ModelBuilder {
 public:
  explicit ModelBuilder(std::string name = "model");
  /// Adds a node at rest position p; returns its index.
  Index add_node(const Vec3& p, const NodeParams& params);
  Index add_node(const Vec3& p, double mass, double damping, double return_k, bool fixed = false);
  /// Adds a spring between existing nodes with rest length = rest distance and k' from the Duffing settings.
  Index add_spring(Index a, Index b, double k, const DuffingSettings& duffing);
  /// Adds a spring with explicit rest length and k'.
  Index add_spring(Index a, Index b, double k, double kp, double rest_length);
  void set_fixed(Index node, bool fixed = true);
  void reserve_springs(Index n) { springs_.reserve(n); }
  void add_bending(Index a, Index b, Index c, double kb);
  /// Adds a volume term on the tetrahedron (a, b, c, d) (positive rest volume) of modulus kv (N/mm^2).
  void add_volume(Index a, Index b, Index c, Index d, double kv) { volume_.add(a, b, c, d, kv); }
  /// Adds a compression-stiffening term (compression_terms.hpp) of modulus kc (N/mm^2) on the tetrahedron.
  void add_compression(Index a, Index b, Index c, Index d, double kc) { compression_.add(a, b, c, d, kc); }
  /// Sets the thin-tetrahedron correction terms (thin_tet_correction.hpp; checked by build()).
  void set_thin_tet(ThinTetCorrections terms) { thin_ = std::move(terms); }
  Index num_nodes() const { return static_cast<Index>(nodes_.size()); }
  const Vec3& position(Index i) const { return nodes_[i]; }
  /// Validates and returns the finished model.
  Model build();

 private:
  std::string name_;
  std::vector<Vec3> nodes_;
  std::vector<double> mass_, damping_, kr_;
  std::vector<std::uint8_t> fixed_;
  Springs springs_;
  BendingTerms bending_;
  VolumeTerms volume_;
  CompressionTerms compression_;
  ThinTetCorrections thin_;
};

/// A surface mass-spring body from a triangle mesh: one spring per unique edge (D-1), uniform nodes.
struct SurfaceBodyParams {
  NodeParams node{};          // kidney defaults of §9: 0.3 g, beta 0.5, k_r 0.02
  double k = 0.05;            // surface spring stiffness, N/mm
  DuffingSettings duffing{};  // Strain (D-3) by default
  std::vector<Index> fixed;   // pinned nodes
};
/// The declaration of SurfaceBodyParams (core/params.hpp): the "parameters" of a surface model in a
/// scene, the Python properties and keywords, `run --set model.parameters.NAME=VALUE`, the table in
/// docs/parameters.md. The node parameters are flat here ("mass", not "node.mass").
template <ParamOf<SurfaceBodyParams> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"mass", "g", "mass of a node"}.positive(), s.node.mass);
  v(ParamSpec{"beta", "1/ms", "mass-proportional damping of a node, d = beta m"}.nonnegative(), s.node.beta);
  v(ParamSpec{"k_r", "N/mm", "return spring of a node to its rest position"}.nonnegative(), s.node.return_k);
  v(ParamSpec{"k", "N/mm", "surface springs (one per mesh edge, D-1)"}.positive(), s.k);
  v(ParamSpec{"duffing", "", "Duffing law of every spring (D-3)"}, s.duffing);
  v(ParamSpec{"fixed", "", "pinned nodes"}, s.fixed);
}
/// Refused up front (InvalidInput naming the node count and the memory) when kModelBuildBytesPerNode
/// per node exceeds the machine's memory (core/memory.hpp).
Model make_surface_model(const SurfaceMesh& mesh, const SurfaceBodyParams& params,
                         const std::string& name = "surface");

/// Peak bytes per node of building a surface model and simulating it (mesh, builder arrays, model,
/// explicit state, with margin), for the memory check of make_surface_model and the model builders.
inline constexpr double kModelBuildBytesPerNode = 1000.0;

/// Fingerprint of a model: FNV-1a 64 over the node count, rest positions, masses, damping, return
/// springs, fixed flags, springs (ends, rest lengths, k, k') and bending terms (bit patterns of the
/// doubles). Two models with the same fingerprint simulate identically.
std::uint64_t model_fingerprint(const Model& model);

/// How far a state may stray before it is refused: positions within kStateReach x (1 + model size) mm
/// of their rest positions, velocities under kStateReach x (1 + model size) mm/ms, where the model size
/// is the diagonal of the rest bounding box. Far beyond anything the guarded integrator produces; a
/// state outside (e.g. 1e300 mm from a checkpoint file) would overflow the surface map and the normals.
inline constexpr double kStateReach = 1e6;

/// InvalidInput "<what>: state.x: node i is D mm from its rest position (…)" when x or v is not finite,
/// has the wrong size, or is outside the reach above.
void require_state_in_reach(const Model& model, const MatX3& x, const MatX3& v, const std::string& what);

}  // namespace medspring
