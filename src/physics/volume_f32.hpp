// The single-precision volume pass (issue 23, docs/volumetric-speed.md "A single-precision volume pass"):
// the pass of the sub-steps without the stable step's bound (add_volume_and_compression_forces: the volume
// terms and the fused compression terms) in float, one tetrahedron at a time with its corners as 4-float
// vectors (x, y, z, 0): 4 loads of 16 bytes per tetrahedron and 4 read-modify-writes of 16 bytes instead of
// 12 of 8. Internal to the physics layer; the double pass (volume_passes.cpp) is the reference.
//
// Precision: the float mirror holds the displacement u = x - x0 (not the position), and each record the rest
// edge vectors E_k = x0_{k+1} - x0_0 rounded to float, so that e_k = E_k + (u_{k+1} - u_0): the rounding of
// an edge is relative to the edge (and to the displacement), not to the coordinates (which on the real kidney
// are ~10-100 edge lengths from the origin). With Diff, 6V - 6V0 is computed from the displacement
// differences D_k = u_{k+1} - u_0 alone, D_0 . (e_1 x e_2) + E_0 . (D_1 x e_2 + E_1 x D_2) (exactly
// e_0 . (e_1 x e_2) - E_0 . (E_1 x E_2)), instead of subtracting two nearly equal volumes: no cancellation at
// small strain. 6V0 (for the compression term's J) is the float kernel's own volume of the rounded rest
// edges, so the rest state is exactly force-free.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "medspring/core/types.hpp"
#include "medspring/physics/parallel.hpp"
#include "medspring/physics/volume_terms.hpp"

namespace medspring {

/// The model's springs in single precision, in its spring order (structure of arrays: eight springs load
/// with one vector load per field), for the gather pass's float slots (spring_f32.hpp). As the volume
/// records, each spring is written relative to its rest edge: e = E + (u_j - u_i), so that L - L0 comes
/// from the displacements without cancellation (spring_f32.cpp).
struct SpringsF32 {
  std::vector<std::int32_t> i, j;  // the ends
  std::vector<float> ex, ey, ez;   // the rest edge E = x0_j - x0_i rounded to float (mm)
  std::vector<float> le;           // |E| of the rounded edge, in float (mm)
  std::vector<float> c;          // |x0_j - x0_i| - L0 in double, rounded (mm; 0 for a spring at rest length)
  std::vector<float> k, kp, ik;  // k (N/mm), k' (N/mm^3) and 1/k (0 for k = 0)
  std::size_t size() const { return i.size(); }
};

/// Single-precision rest data of a model's volume terms (and its fused compression terms), built from the
/// finalized VolumeTerms (its `packed` order) and the rest positions.
struct VolumeTermsF32 {
  /// One record per term, 64 bytes: the corners, and the rest edges E_k = x0[n[k+1]] - x0[n[0]] (mm, float),
  /// one 4-float row each, whose fourth floats hold alpha = kv / 36 V0 (1/mm), 6 V0 (mm^3, the float
  /// kernel's volume of the rounded edges) and kc / 6 (0: no compression term).
  struct Record {
    std::int32_t n[4];
    float E[3][4];
  };
  std::vector<Record> rec;
  /// The same records in blocks of eight, lane by lane (the eight-a-vector passes' layout, 64 bytes a record
  /// as `rec`): their corners, and lane d of rest edge k of record j at E[k][d][j], so that those passes load
  /// the edges of eight records with twelve vector loads instead of transposing their rows. rec.size() / 8
  /// blocks: the last records of a partial block are read from `rec`.
  struct alignas(32) Block {
    std::int32_t n[4][8];
    float E[3][4][8];
  };
  std::vector<Block> blk;
  std::vector<float> iG0;  // per record: 1 / G0, the rest curvature's inverse (VolumeTerms::Packed::iG0)
  std::vector<double> x0;  // (3 #N) rest positions, mm: the pass's float mirror holds x - x0
  Index nodes = 0;
  bool comp = false;   // fused compression terms (VolumeTerms::kc not empty)
  SpringsF32 springs;  // the model's springs (set_volume_single_precision; empty from build_volume_f32 alone)
};

/// The records of a pass shared among the threads of a pool (the threaded step, threaded_volume.hpp): thread
/// t takes records [begin[t], begin[t + 1]) into the force mirror mirrors[t] (4 floats a node; mirrors[0] is
/// the pass's own, in its scratch), and the pass sums the mirrors in thread order.
struct ParallelRecords {
  WorkerPool* pool = nullptr;
  const std::size_t* begin = nullptr;  // threads + 1 record bounds, multiples of eight but the last
  float* const* mirrors = nullptr;     // threads mirrors of 4 #N floats
  int threads = 1;
};

/// Builds F from T (finalized; fused compression terms taken when T.kc is set) and the rest positions x0.
void build_volume_f32(const VolumeTerms& T, const MatX3& x0, VolumeTermsF32& F);

/// Floats of scratch per node of add_volume_and_compression_forces_f32 (the displacement and force mirrors).
inline constexpr Index kVolumeF32ScratchPerNode = 8;

/// add_volume_and_compression_forces in single precision: adds the volume terms' (and the fused compression
/// terms') forces at x (flat 3 #N, double) to f (flat 3 #N, double). The forces are accumulated in float per
/// node and added to f once. `scratch`: kVolumeF32ScratchPerNode #N floats (overwritten). With `diff` (the
/// default) 6V - 6V0 from the displacement differences (no cancellation, volume_f32.hpp); without, as the
/// double pass computes it (for the benchmark's A/B and the precision test).
/// With `par` (and diff), its threads share the records, the forces summed in thread order.
void add_volume_and_compression_forces_f32(const VolumeTermsF32& F, const double* x, double* f,
                                           float* scratch, bool diff = true,
                                           const ParallelRecords* par = nullptr);

/// add_volume_and_compression_forces_inc (compression_rows.hpp; add_volume_forces_inc where F has no fused
/// compression terms) in single precision: the pass of a frame's last sub-step, with the stable step's bound.
/// Adds the forces at x to f as add_volume_and_compression_forces_f32 does; writes inc[t] = (s_t - 1)+ per
/// term (#T doubles, the local stiffening's increments, for volume_row_max) and returns the terms' largest
/// curvature growth max(1, s_t), both from the float kernel. With fused compression terms, also writes the
/// traces of their bound's blocks to trows (#N doubles, overwritten), `s`: m_i^-1/2 per node (0 on a fixed
/// node); without, `s` and `trows` are not used. The forces, increments and traces are those of the double
/// pass to float rounding (about 1e-6 relative): far inside the stable step's safety factor (0.8).
/// With `par`, its threads share the records (each thread's largest s_t, the forces and the traces summed
/// in thread order: another thread count rounds the sums differently, float rounding).
double add_volume_and_compression_forces_inc_f32(const VolumeTermsF32& F, const double* x, double* f,
                                                 float* scratch, double* inc, const double* s, double* trows,
                                                 const ParallelRecords* par = nullptr);

/// count_inverted (volume_terms.hpp) of T at x (flat 3 #N), F built from T: the same count, eight records a
/// vector in float where compiled (GCC, AVX) from the displacement mirror (`scratch`: 4 #N floats at least,
/// overwritten). A record whose float 6V is within a rounding band of 0 (64 eps_f times the product of its
/// edges' bounds, far above the float error), or not finite, is decided by count_inverted's own double test;
/// the others' signs are certain. Elsewhere, and for the tail, the double test. For the step's count at the
/// end of each frame (integrators.cpp) with the float volume pass.
/// With `par`, its threads count their records (the same count).
std::uint64_t count_inverted_f32(const VolumeTermsF32& F, const VolumeTerms& T, const double* x,
                                 float* scratch, const ParallelRecords* par = nullptr);

namespace detail {
/// The forces of records [r0, r1) of F (add_volume_and_compression_forces_f32's kernel, displacement
/// differences) added to the force mirror g (4 floats a node), from the displacement mirror u: the threaded
/// sub-step's share of one thread (threaded_volume.hpp).
void add_records_f32(const VolumeTermsF32& F, const float* u, float* g, std::size_t r0, std::size_t r1);
/// count_inverted's test of packed record i of T at X (flat 3 #N): 6V <= 0 or not finite (volume_terms.cpp).
bool packed_record_inverted(const VolumeTerms& T, const double* X, std::size_t i);
/// Whether the pass uses GCC's vector extensions (else the same arithmetic on 4-float structs).
bool volume_f32_vector_compiled();
/// Eight records at a time in 256-bit vectors (GCC, AVX targets; on by default) or one at a time: for the
/// benchmark's A/B. Returns the former setting.
bool set_volume_f32_x8(bool on);
/// The eight-a-vector passes read VolumeTermsF32::blk (on by default) or transpose the rows of `rec` (the
/// layout before the session of 2026-11-28): for the benchmark's A/B and the tests. Returns the former
/// setting.
bool set_volume_f32_blocks(bool on);
}  // namespace detail

}  // namespace medspring
