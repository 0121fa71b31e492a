#include "medspring/builders/organ_source.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <utility>

#include "medspring/core/check.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/io/volume_io.hpp"
#include "medspring/meshing/balloon.hpp"
#include "medspring/meshing/mesh_repair.hpp"

namespace medspring {
namespace {

Index find_root(std::vector<Index>& parent, Index a) {
  while (parent[a] != a) {
    parent[a] = parent[parent[a]];
    a = parent[a];
  }
  return a;
}

/// Splits a mesh into its face-connected components and keeps the one of largest |enclosed volume|
/// (ties: more faces, then the first). Returns the number of components.
Index keep_largest_mesh_component(SurfaceMesh& mesh) {
  const Index nv = mesh.num_vertices(), nf = mesh.num_faces();
  std::vector<Index> parent(static_cast<std::size_t>(nv));
  std::iota(parent.begin(), parent.end(), 0);
  for (Index f = 0; f < nf; ++f)
    for (int c = 1; c < 3; ++c) {
      const Index a = find_root(parent, mesh.F(f, 0)), b = find_root(parent, mesh.F(f, c));
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  std::map<Index, std::vector<Index>> faces_of;  // root -> faces, ordered by the root (first vertex)
  for (Index f = 0; f < nf; ++f) faces_of[find_root(parent, mesh.F(f, 0))].push_back(f);
  const Index count = static_cast<Index>(faces_of.size());
  if (count <= 1) return count;
  const std::vector<Index>* best = nullptr;
  double best_volume = -1.0;
  for (const auto& [root, faces] : faces_of) {
    MatX3i F(static_cast<Index>(faces.size()), 3);
    for (std::size_t q = 0; q < faces.size(); ++q) F.row(static_cast<Index>(q)) = mesh.F.row(faces[q]);
    const double vol = std::abs(signed_volume(mesh.V, F));
    if (best == nullptr || vol > best_volume || (vol == best_volume && faces.size() > best->size())) {
      best = &faces;
      best_volume = vol;
    }
  }
  std::vector<Index> old_to_new(static_cast<std::size_t>(nv), -1);
  Index nv_new = 0;
  for (Index f : *best)
    for (int c = 0; c < 3; ++c)
      if (old_to_new[mesh.F(f, c)] < 0) old_to_new[mesh.F(f, c)] = nv_new++;
  SurfaceMesh out;
  out.V.resize(nv_new, 3);
  out.F.resize(static_cast<Index>(best->size()), 3);
  for (Index v = 0; v < nv; ++v)
    if (old_to_new[v] >= 0) out.V.row(old_to_new[v]) = mesh.V.row(v);
  for (std::size_t q = 0; q < best->size(); ++q)
    for (int c = 0; c < 3; ++c) out.F(static_cast<Index>(q), c) = old_to_new[mesh.F((*best)[q], c)];
  mesh = std::move(out);
  return count;
}

std::string label_list(const std::map<std::int32_t, std::int64_t>& counts) {
  std::string s;
  for (const auto& [label, n] : counts) {
    if (label == 0) continue;
    if (!s.empty()) s += ", ";
    s += cat(label, " (", n, " voxels)");
  }
  return s;
}

double mask_diagonal(const MaskVolume& mask) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (Index k = 0; k < mask.dims[2]; ++k)
    for (Index j = 0; j < mask.dims[1]; ++j)
      for (Index i = 0; i < mask.dims[0]; ++i)
        if (mask.at(i, j, k) != 0) {
          const Vec3 p =
              mask.to_world(Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
          lo = lo.cwiseMin(p);
          hi = hi.cwiseMax(p);
        }
  // voxel centres: add one voxel so that a single voxel has the size of its box
  return (hi - lo + mask.spacing).norm();
}

void load_mesh(const OrganSource& src, const LoadOrganOptions& opt, LoadedOrgan& out) {
  const MeshReadResult read = read_mesh_with_report(src.mesh, {.unit = src.unit});
  SurfaceMesh mesh = read.mesh;
  out.components = keep_largest_mesh_component(mesh);
  if (out.components > 1)
    out.notes.push_back(cat(out.name, ": ", out.components, " components: the largest (", mesh.num_vertices(),
                            " vertices, ", mesh.num_faces(), " faces) is used"));
  if (src.close_holes > 0 && !validate_mesh(mesh).closed()) {
    require(src.close_holes >= 3, out.name, ": close_holes must be >= 3 edges (got ", src.close_holes, ")");
    require_valid_mesh(mesh, out.name, {.closed = false, .manifold = true});
    const HoleFillReport fill = close_small_holes(mesh, src.close_holes);
    out.holes_closed = fill.holes_filled;
    out.notes.push_back(cat(out.name, ": closed ", fill.holes_filled, " of ", fill.holes_found,
                            " holes (up to ", src.close_holes, " edges), ", fill.faces_added,
                            " faces added"));
  }
  if (opt.allow_open_tube) {
    // an open vessel: boundary loops are capped by the skeleton builder (§3.6); the rest must hold
    const ClosedManifoldReport r = check_closed_manifold(mesh);
    require(r.mesh.valid(), out.name, ": invalid surface mesh: ", r.mesh.first_problem);
    require(r.nonmanifold_vertices == 0, out.name, ": surface is not manifold: ", r.nonmanifold_vertices,
            " bow-tie vertices; repair the mesh first");
    require(r.mesh.inconsistent_edges == 0, out.name, ": surface is not consistently oriented (",
            r.mesh.inconsistent_edges, " edges traversed twice in the same direction)");
    if (!r.mesh.closed())
      out.notes.push_back(cat(out.name, ": open surface with ", r.holes, " boundary loops"));
  } else {
    require_closed_manifold(mesh, out.name);
    if (signed_volume(mesh.V, mesh.F) < 0) {
      mesh.F.col(1).swap(mesh.F.col(2));
      out.notes.push_back(cat(out.name, ": triangles turned to face outward"));
    }
  }
  if (std::string w = organ_size_warning(validate_mesh(mesh).bbox_diagonal); !w.empty())
    out.warnings.push_back(cat(out.name, ": ", w));
  out.surface = std::move(mesh);
}

void load_mask(const OrganSource& src, const LoadOrganOptions& opt, LoadedOrgan& out) {
  const LabelVolume labels = read_label_volume(src.mask);
  std::map<std::int32_t, std::int64_t> counts;
  for (std::int32_t v : labels.data) ++counts[v];
  const bool any = std::any_of(counts.begin(), counts.end(), [](const auto& c) { return c.first != 0; });
  require(any, out.name, ": mask is empty (no non-zero voxel in ", labels.dims[0], " x ", labels.dims[1],
          " x ", labels.dims[2], ")");
  if (src.label) {
    require(*src.label != 0, out.name, ": label 0 is the background; labels present: ", label_list(counts));
    require(counts.count(*src.label) > 0, out.name, ": label ", *src.label,
            " not found; labels present: ", label_list(counts));
    out.label = *src.label;
  } else {
    const std::int64_t nonzero =
        std::count_if(counts.begin(), counts.end(), [](const auto& c) { return c.first != 0; });
    require(nonzero == 1, out.name, ": ", nonzero,
            " labels present, choose one with label (--label N): ", label_list(counts));
    for (const auto& c : counts)
      if (c.first != 0) out.label = c.first;
  }
  MaskVolume mask = select_label(labels, out.label);
  const std::int64_t selected = counts[out.label];
  out.mask = largest_component(mask, &out.components);
  if (out.components > 1) {
    const auto kept = std::count(out.mask.data.begin(), out.mask.data.end(), std::uint8_t{1});
    out.notes.push_back(cat(out.name, ": label ", out.label, " has ", out.components,
                            " components (26-connected): the largest (", kept, " of ", selected,
                            " voxels) is used"));
  }
  if (std::string w = organ_size_warning(mask_diagonal(out.mask)); !w.empty())
    out.warnings.push_back(cat(out.name, ": ", w));
  if (opt.surface) out.surface = isosurface(out.mask, opt.isosurface);
}

}  // namespace

LoadedOrgan load_organ(const OrganSource& source, const LoadOrganOptions& options) {
  const bool has_mesh = !source.mesh.empty(), has_mask = !source.mask.empty();
  require(has_mesh != has_mask, "organ source: give exactly one of a mesh and a mask (got ",
          has_mesh ? "both" : "neither", ")");
  LoadedOrgan out;
  out.from_mask = has_mask;
  out.name = (has_mesh ? source.mesh : source.mask).filename().string();
  require(source.close_holes >= 0, out.name, ": close_holes must be >= 0 (got ", source.close_holes, ")");
  require(!has_mask || source.close_holes == 0, out.name, ": close_holes applies to a mesh, not to a mask");
  if (has_mesh)
    load_mesh(source, options, out);
  else
    load_mask(source, options, out);
  return out;
}

bool mask_contains(const MaskVolume& mask, const Vec3& p) {
  const Vec3 q = mask.to_index(p);
  const Index i = static_cast<Index>(std::lround(q.x())), j = static_cast<Index>(std::lround(q.y())),
              k = static_cast<Index>(std::lround(q.z()));
  return mask.inside(i, j, k) && mask.at(i, j, k) != 0;
}

double distance_outside_mask(const MaskVolume& mask, const Vec3& p, Index search_voxels) {
  const Vec3 q = mask.to_index(p);
  const Index ci = static_cast<Index>(std::lround(q.x())), cj = static_cast<Index>(std::lround(q.y())),
              ck = static_cast<Index>(std::lround(q.z()));
  double best = std::numeric_limits<double>::infinity();
  for (Index k = ck - search_voxels; k <= ck + search_voxels; ++k)
    for (Index j = cj - search_voxels; j <= cj + search_voxels; ++j)
      for (Index i = ci - search_voxels; i <= ci + search_voxels; ++i) {
        if (!mask.inside(i, j, k) || mask.at(i, j, k) == 0) continue;
        // distance to the voxel's box (the direction is orthonormal: voxel-frame lengths are world lengths)
        const Vec3 c(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
        Vec3 d;
        for (int a = 0; a < 3; ++a) d[a] = std::max(0.0, std::abs(q[a] - c[a]) - 0.5) * mask.spacing[a];
        best = std::min(best, d.norm());
      }
  return best;
}

MaskVolume largest_component(const MaskVolume& mask, Index* components) {
  MaskVolume out = mask;
  std::fill(out.data.begin(), out.data.end(), std::uint8_t{0});
  const std::size_t n = mask.size();
  require(mask.data.size() == n, "largest_component: mask data holds ", mask.data.size(),
          " values, dims need ", n);
  std::vector<std::int32_t> comp(n, -1);
  std::vector<std::size_t> stack;
  std::vector<std::size_t> sizes;
  const Index nx = mask.dims[0], ny = mask.dims[1], nz = mask.dims[2];
  for (std::size_t s = 0; s < n; ++s) {
    if (mask.data[s] == 0 || comp[s] >= 0) continue;
    const auto id = static_cast<std::int32_t>(sizes.size());
    std::size_t size = 0;
    comp[s] = id;
    stack.push_back(s);
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      ++size;
      const Index i = static_cast<Index>(v % static_cast<std::size_t>(nx));
      const Index j = static_cast<Index>((v / static_cast<std::size_t>(nx)) % static_cast<std::size_t>(ny));
      const Index k = static_cast<Index>(v / (static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny)));
      for (Index dk = -1; dk <= 1; ++dk)
        for (Index dj = -1; dj <= 1; ++dj)
          for (Index di = -1; di <= 1; ++di) {
            const Index a = i + di, b = j + dj, c = k + dk;
            if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
            const std::size_t w = mask.index(a, b, c);
            if (mask.data[w] == 0 || comp[w] >= 0) continue;
            comp[w] = id;
            stack.push_back(w);
          }
    }
    sizes.push_back(size);
  }
  if (components != nullptr) *components = static_cast<Index>(sizes.size());
  if (sizes.empty()) return out;
  const auto best = static_cast<std::int32_t>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
  for (std::size_t s = 0; s < n; ++s) out.data[s] = comp[s] == best ? 1 : 0;
  return out;
}

}  // namespace medspring
