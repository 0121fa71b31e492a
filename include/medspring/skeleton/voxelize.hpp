// Voxelisation of a closed triangle mesh and centerlines of surface meshes, ALGORITHMS.md §3.6.
//
//   MeshCenterline r = centerline_from_mesh(kidney_phantom(), {.atom_count = 42});
//   r.skeleton.atoms, r.skeleton.radii        // world mm
#pragma once

#include <vector>

#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/geometry/volume.hpp"
#include "medspring/skeleton/centerline_extraction.hpp"

namespace medspring {

/// Settings of voxelize (§3.6; defaults of §9).
struct VoxelizeSettings {
  double voxel_size = 0.0;  // mm, h_v; 0 = (smallest bounding-box extent) / divisions
  Index divisions = 48;     // voxels across the smallest bounding-box extent when voxel_size = 0
  Index padding = 2;        // background voxels added around the bounding box on every side
  double jitter = 1e-7;     // scanline offset in y and z, as a fraction of h_v (times sqrt(2), sqrt(3))
};

/// What voxelize did.
struct VoxelizeStats {
  Index rows = 0;           // scanlines (y, z rows)
  Index odd_rows = 0;       // rows with an odd number of crossings, classified by winding number
  Index inside_voxels = 0;  // object voxels
  double voxel_size = 0.0;  // mm
};

/// Binary mask of the voxel centres inside a closed triangle mesh (§3.6): an isotropic grid of
/// spacing h_v over the bounding box padded by `padding` voxels (centred on the box, identity
/// direction); scanline parity along x for every (y, z) row, offset by a tiny irrational jitter;
/// rows with an odd number of crossings (mesh not watertight) are classified voxel by voxel with the
/// generalized winding number (Jacobson et al. 2013), inside if > 0.5 (sign taken from the mesh's
/// orientation). Throws InvalidInput for an empty or non-finite mesh or bad settings.
MaskVolume voxelize(const SurfaceMesh& mesh, const VoxelizeSettings& settings = {},
                    VoxelizeStats* stats = nullptr);

/// Generalized winding number of a mesh at point p: (1/4 pi) * sum of the signed solid angles of the
/// triangles (Van Oosterom & Strackee); 1 inside / 0 outside a closed outward-oriented mesh.
double winding_number(const SurfaceMesh& mesh, const Vec3& p);

/// A cap that closes one boundary loop of an open mesh.
struct BoundaryCap {
  std::vector<Index> loop;       // boundary vertices in loop order (as they bound the existing faces)
  Index center_vertex = -1;      // the added centroid vertex
  Vec3 centroid = Vec3::Zero();  // mm, mean of the loop vertices
  Vec3 normal = Vec3::Zero();    // unit, area-weighted normal of the fan (outward for an outward mesh)
};

/// Closes every boundary loop of `mesh` by a fan of triangles around the loop centroid (§3.6),
/// oriented consistently with the neighbouring faces. Loops are found in the order of their first
/// boundary edge (faces in order, edges 01, 12, 20). Returns one cap per loop (none for a closed
/// mesh). Throws InvalidInput when a boundary vertex has two outgoing boundary edges.
std::vector<BoundaryCap> close_boundary_loops(SurfaceMesh& mesh);

/// Result of centerline_from_mesh.
struct MeshCenterline {
  SkeletonResult skeleton;        // the centerline (world mm)
  MaskVolume mask;                // the voxelised (capped) mesh
  std::vector<BoundaryCap> caps;  // the caps added to close an open tube (empty for a closed mesh)
  VoxelizeStats voxel_stats;
};

/// Centerline of a triangle mesh (§3.6): open boundary loops are closed by fans; the closed mesh is
/// voxelised and extract_centerline runs on the mask (which never touches the volume border, so no
/// end is Open). Throws InvalidInput for an invalid or non-manifold mesh. For an open tube with two
/// loops, the cap centroids become the user endpoints (first loop = start) unless settings already
/// give endpoints; those ends are Capped: trimmed by r, then re-extended linearly along the end
/// tangent to the cap plane (the atoms on the extension take the radius at the junction).
MeshCenterline centerline_from_mesh(const SurfaceMesh& mesh, const SkeletonSettings& settings = {},
                                    const VoxelizeSettings& voxelize_settings = {});

}  // namespace medspring
