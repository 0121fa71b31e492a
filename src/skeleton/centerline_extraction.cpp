#include "medspring/skeleton/centerline_extraction.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "centerline_stages.hpp"
#include "medspring/core/check.hpp"
#include "medspring/skeleton/distance_transform.hpp"

namespace medspring {

using namespace skeleton_detail;

const char* to_string(EndKind kind) {
  switch (kind) {
    case EndKind::Open:
      return "open";
    case EndKind::Closed:
      return "closed";
    case EndKind::Capped:
      return "capped";
  }
  return "?";
}

Centerline SkeletonResult::centerline() const {
  Centerline c;
  c.points = atoms;
  c.radii = radii;
  c.name = "skeleton";
  return c;
}

SkeletonResult extract_centerline(const MaskVolume& mask, const SkeletonSettings& settings) {
  // ---- validation ----
  require_valid_volume(mask, "mask");
  require(settings.atom_count >= 2, "skeleton: atom_count must be >= 2 (got ", settings.atom_count, ")");
  require(settings.connectivity == 6 || settings.connectivity == 18 || settings.connectivity == 26,
          "skeleton: connectivity must be 6, 18 or 26 (got ", settings.connectivity, ")");
  require_nonnegative(settings.smoothing_sigma, "skeleton: smoothing_sigma");
  require_nonnegative(settings.resampling_step, "skeleton: resampling_step");
  require(settings.min_open_end_voxels >= 1, "skeleton: min_open_end_voxels must be >= 1 (got ",
          settings.min_open_end_voxels, ")");
  require_nonnegative(settings.penalty_lambda, "skeleton: penalty_lambda");
  require_positive(settings.penalty_power, "skeleton: penalty_power");
  for (const auto* ep : {&settings.start, &settings.end})
    if (*ep) {
      require((*ep)->position.allFinite(), "skeleton: user endpoint must be finite");
      require(!(*ep)->cap_normal || ((*ep)->cap_normal->allFinite() && (*ep)->cap_normal->norm() > 0),
              "skeleton: cap_normal must be finite and non-zero");
    }

  SkeletonResult res;
  const Vec3 h = mask.spacing;
  const double h_min = h.minCoeff();
  res.h_min = h_min;
  const double delta = settings.resampling_step > 0 ? settings.resampling_step : 0.5 * h_min;
  const double sigma = settings.smoothing_sigma > 0 ? settings.smoothing_sigma : 2.0 * h_min;
  const std::array<Index, 3> n = mask.dims;
  const Index N = static_cast<Index>(mask.size());

  // ---- §3.1.1 largest connected component ----
  const std::vector<Offset> mask_offsets = make_offsets(settings.connectivity, h, n);
  std::vector<std::int32_t> label(N, 0);
  std::vector<Index> queue;
  Index best_label = 0, best_size = 0, best_first = -1;
  std::int32_t labels = 0;
  for (Index s = 0; s < N; ++s) {
    if (!mask.data[s] || label[s]) continue;
    ++labels;
    label[s] = labels;
    queue.assign(1, s);
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const Index v = queue[q];
      const Index i = v % n[0], j = (v / n[0]) % n[1], k = v / (n[0] * n[1]);
      for (const Offset& o : mask_offsets) {
        const Index a = i + o.di, b = j + o.dj, c = k + o.dk;
        if (a < 0 || b < 0 || c < 0 || a >= n[0] || b >= n[1] || c >= n[2]) continue;
        const Index w = v + o.d;
        if (mask.data[w] && !label[w]) {
          label[w] = labels;
          queue.push_back(w);
        }
      }
    }
    res.object_voxels += static_cast<Index>(queue.size());
    if (static_cast<Index>(queue.size()) > best_size) {
      best_size = static_cast<Index>(queue.size());
      best_label = labels;
      best_first = s;
    }
  }
  if (res.object_voxels == 0) throw InvalidInput("mask: no object voxels");
  res.components = labels;
  res.component_voxels = best_size;
  if (labels > 1)
    res.notes.push_back(cat("used the largest of ", labels, " components (", best_size, " of ",
                            res.object_voxels, " object voxels)"));
  auto in_comp = [&](Index v) { return label[v] == best_label; };

  // bounding box of the component
  std::array<Index, 3> bmin = n, bmax{-1, -1, -1};
  for (Index v = best_first; v < N; ++v) {
    if (!in_comp(v)) continue;
    const std::array<Index, 3> c{v % n[0], (v / n[0]) % n[1], v / (n[0] * n[1])};
    for (int a = 0; a < 3; ++a) {
      bmin[a] = std::min(bmin[a], c[a]);
      bmax[a] = std::max(bmax[a], c[a]);
    }
  }

  // ---- §3.1.2 open ends: component voxels on the volume border, grouped ----
  std::vector<OpenEndGroup> groups;
  {
    auto on_border = [&](Index i, Index j, Index k) {
      return i == 0 || j == 0 || k == 0 || i == n[0] - 1 || j == n[1] - 1 || k == n[2] - 1;
    };
    std::vector<std::uint8_t> seen;
    for (Index k = bmin[2]; k <= bmax[2]; ++k)
      for (Index j = bmin[1]; j <= bmax[1]; ++j)
        for (Index i = bmin[0]; i <= bmax[0]; ++i) {
          if (!on_border(i, j, k)) continue;
          const Index v = static_cast<Index>(mask.index(i, j, k));
          if (!in_comp(v)) continue;
          if (seen.empty()) seen.assign(N, 0);
          if (seen[v]) continue;
          OpenEndGroup grp;
          grp.first = v;
          seen[v] = 1;
          queue.assign(1, v);
          for (std::size_t q = 0; q < queue.size(); ++q) {
            const Index u = queue[q];
            const Index a0 = u % n[0], b0 = (u / n[0]) % n[1], c0 = u / (n[0] * n[1]);
            grp.centroid += h.cwiseProduct(Vec3(a0, b0, c0));
            for (const Offset& o : mask_offsets) {
              const Index a = a0 + o.di, b = b0 + o.dj, c = c0 + o.dk;
              if (a < 0 || b < 0 || c < 0 || a >= n[0] || b >= n[1] || c >= n[2] || !on_border(a, b, c))
                continue;
              const Index w = u + o.d;
              if (in_comp(w) && !seen[w]) {
                seen[w] = 1;
                queue.push_back(w);
              }
            }
          }
          grp.size = static_cast<Index>(queue.size());
          grp.centroid /= static_cast<double>(grp.size);
          grp.voxels = queue;
          std::sort(grp.voxels.begin(), grp.voxels.end());
          if (grp.size >= settings.min_open_end_voxels) groups.push_back(std::move(grp));
        }
    std::stable_sort(groups.begin(), groups.end(),
                     [](const OpenEndGroup& a, const OpenEndGroup& b) { return a.size > b.size; });
  }
  for (const auto& g : groups) res.open_end_sizes.push_back(g.size);
  const bool use_open = settings.end_mode != EndMode::Closed && !groups.empty();
  const bool replicate = settings.end_mode == EndMode::Open || use_open;
  if (settings.end_mode == EndMode::Closed && !groups.empty())
    res.notes.push_back(cat("end mode closed: ", groups.size(), " open end(s) on the volume border ignored"));
  else if (!groups.empty())
    res.notes.push_back(cat(groups.size(), " open end(s) on the volume border (largest ", groups[0].size,
                            " voxels): edge-replicate padding"));

  // ---- D-5 padding and the working grid ----
  auto make_work_mask = [&](const std::array<Index, 3>& P, bool edge_replicate, std::array<Index, 3>& lo) {
    MaskVolume w;
    for (int a = 0; a < 3; ++a) {
      lo[a] = bmin[a] - P[a];
      w.dims[a] = bmax[a] - bmin[a] + 1 + 2 * P[a];
    }
    w.spacing = h;
    w.origin = mask.to_world(Vec3(lo[0], lo[1], lo[2]));
    w.direction = mask.direction;
    w.data.assign(w.size(), 0);
    for (Index k = 0; k < w.dims[2]; ++k)
      for (Index j = 0; j < w.dims[1]; ++j)
        for (Index i = 0; i < w.dims[0]; ++i) {
          Index a = i + lo[0], b = j + lo[1], c = k + lo[2];
          if (edge_replicate) {
            a = std::clamp<Index>(a, 0, n[0] - 1);
            b = std::clamp<Index>(b, 0, n[1] - 1);
            c = std::clamp<Index>(c, 0, n[2] - 1);
          } else if (a < 0 || b < 0 || c < 0 || a >= n[0] || b >= n[1] || c >= n[2]) {
            continue;
          }
          w.at(i, j, k) = in_comp(static_cast<Index>(mask.index(a, b, c))) ? 1 : 0;
        }
    return w;
  };
  std::array<Index, 3> P{2, 2, 2};  // background padding: the DFB is the same for every P >= 1
  if (replicate) {
    // P = ceil(r_max / h) + 2 per axis, r_max from the DFB with the outside as background
    std::array<Index, 3> lo1{};
    const MaskVolume pre = make_work_mask({1, 1, 1}, false, lo1);
    const DistanceField pre_df = distance_from_boundary(pre);
    double r_max = 0.0;
    for (std::size_t i = 0; i < pre.data.size(); ++i)
      if (pre.data[i]) r_max = std::max(r_max, pre_df.dfb.data[i]);
    for (int a = 0; a < 3; ++a) P[a] = static_cast<Index>(std::ceil(r_max / h[a])) + 2;
  }
  Graph g;
  const MaskVolume work = make_work_mask(P, replicate, g.lo);
  g.dims = work.dims;
  g.offsets = make_offsets(settings.connectivity, h, g.dims);

  // ---- §3.2 DFB ----
  DistanceField df = distance_from_boundary(work);
  g.gid.assign(work.size(), -1);
  for (Index k = P[2]; k < g.dims[2] - P[2]; ++k)
    for (Index j = P[1]; j < g.dims[1] - P[1]; ++j)
      for (Index i = P[0]; i < g.dims[0] - P[0]; ++i) {
        if (!in_comp(static_cast<Index>(mask.index(i + g.lo[0], j + g.lo[1], k + g.lo[2])))) continue;
        const Index w = static_cast<Index>(work.index(i, j, k));
        g.gid[w] = g.size();
        g.widx.push_back(w);
      }
  const Index V = g.size();
  std::vector<double> dfb(V);
  for (Index v = 0; v < V; ++v) dfb[v] = df.dfb.data[g.widx[v]];
  res.max_dfb = *std::max_element(dfb.begin(), dfb.end());
  require(std::isfinite(res.max_dfb), "mask: the object fills the whole volume (no background voxel)");
  // exact DFB order as dense ranks: the squared integer EDT on isotropic grids, else DFB values merged
  // into levels where consecutive values differ by at most 1e-9 relative (§3.4)
  std::vector<Index> level(V);
  Index levels = 0;
  if (df.isotropic) {
    std::vector<std::int32_t> vals(V);
    for (Index v = 0; v < V; ++v) vals[v] = df.squared_edt.data[g.widx[v]];
    std::vector<std::int32_t> sorted = vals;
    std::sort(sorted.begin(), sorted.end());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    for (Index v = 0; v < V; ++v)
      level[v] = static_cast<Index>(std::lower_bound(sorted.begin(), sorted.end(), vals[v]) - sorted.begin());
    levels = static_cast<Index>(sorted.size());
  } else {
    std::vector<double> vals = dfb;
    std::sort(vals.begin(), vals.end());
    vals.erase(std::unique(vals.begin(), vals.end()), vals.end());
    std::vector<Index> lv(vals.size());
    Index L = 0;
    double start = vals[0];
    for (std::size_t i = 0; i < vals.size(); ++i) {
      if (vals[i] > start * (1.0 + 1e-9)) {
        ++L;
        start = vals[i];
      }
      lv[i] = L;
    }
    for (Index v = 0; v < V; ++v)
      level[v] = lv[std::lower_bound(vals.begin(), vals.end(), dfb[v]) - vals.begin()];
    levels = L + 1;
  }

  // ---- §3.3 D-6 endpoints ----
  auto local_of = [&](Index v) {
    const auto c = g.ijk(v);
    return Vec3(h[0] * c[0], h[1] * c[1], h[2] * c[2]);
  };
  auto snap = [&](const Vec3& p) {  // nearest node, ties: smallest id
    Index best = 0;
    double bd = kInf;
    for (Index v = 0; v < V; ++v) {
      const double d = (local_of(v) - p).squaredNorm();
      if (d < bd) {
        bd = d;
        best = v;
      }
    }
    return best;
  };
  auto group_of = [&](Index v) {  // open-end group index of node v, or -1
    const auto c = g.ijk(v);
    const Index lin = static_cast<Index>(mask.index(c[0], c[1], c[2]));
    for (std::size_t q = 0; q < groups.size(); ++q)
      if (std::binary_search(groups[q].voxels.begin(), groups[q].voxels.end(), lin))
        return static_cast<int>(q);
    return -1;
  };
  auto to_local = [&](const Vec3& world) -> Vec3 {
    return mask.direction.transpose() * (world - mask.origin);
  };
  auto user_kind = [&](const UserEndpoint& u, Index v) {
    if (u.cap_normal) return EndKind::Capped;
    if (settings.end_mode == EndMode::Open) return EndKind::Open;
    if (settings.end_mode == EndMode::Auto && group_of(v) >= 0) return EndKind::Open;
    return EndKind::Closed;
  };
  const EndKind default_kind = settings.end_mode == EndMode::Open ? EndKind::Open : EndKind::Closed;
  std::vector<double> dfs;
  Index R = -1, E = -1;
  EndKind kind_R = default_kind, kind_E = default_kind;
  if (settings.start) {
    R = snap(to_local(settings.start->position));
    kind_R = user_kind(*settings.start, R);
  } else if (use_open) {
    R = snap(groups[0].centroid);
    kind_R = EndKind::Open;
  } else {
    dijkstra(g, 0, dfs);  // s0 = first object voxel in raster order: double sweep
    R = argmax(dfs);
  }
  dijkstra(g, R, dfs);  // DFS_R
  if (settings.end) {
    E = snap(to_local(settings.end->position));
    kind_E = user_kind(*settings.end, E);
  } else if (use_open && groups.size() >= 2) {
    E = snap(groups[1].centroid);
    kind_E = EndKind::Open;
  } else {
    E = argmax(dfs);
  }
  require(R != E, "mask: the centerline endpoints coincide at voxel ", ijk_text(g.ijk(R)),
          " (object too small or identical user endpoints)");

  // ---- §3.4 path ----
  const std::vector<Index> path =
      settings.path_method == PathMethod::MaximumSpanningTree
          ? prim_path(g, level, levels, dfs, R, E)
          : penalized_path(g, dfb, res.max_dfb, settings.penalty_lambda, settings.penalty_power, R, E);

  auto world_of_local = [&](const Vec3& p) -> Vec3 { return mask.origin + mask.direction * p; };
  auto dfb_at = [&](const Vec3& p) {  // trilinear DFB at a local physical point
    const Vec3 ijk = p.cwiseQuotient(h) - Vec3(g.lo[0], g.lo[1], g.lo[2]);
    return trilinear(df.dfb, ijk);
  };
  auto to_mat = [&](const Curve& C) {
    MatX3 M(static_cast<Index>(C.size()), 3);
    for (std::size_t i = 0; i < C.size(); ++i)
      M.row(static_cast<Index>(i)) = world_of_local(C[i]).transpose();
    return M;
  };

  Curve raw(path.size());
  res.path_voxels.resize(path.size());
  for (std::size_t i = 0; i < path.size(); ++i) {
    raw[i] = local_of(path[i]);
    const auto c = g.ijk(path[i]);
    res.path_voxels[i] = static_cast<Index>(mask.index(c[0], c[1], c[2]));
  }
  res.raw_path = to_mat(raw);
  res.ends[0].voxel = res.path_voxels.front();
  res.ends[1].voxel = res.path_voxels.back();
  res.ends[0].position = world_of_local(raw.front());
  res.ends[1].position = world_of_local(raw.back());
  res.ends[0].kind = kind_R;
  res.ends[1].kind = kind_E;

  // ---- §3.5.1-2 resampling and smoothing ----
  double step = 0.0;
  const Curve Q = smooth_gaussian(resample_uniform(raw, delta, step), step, sigma);
  res.smoothed = to_mat(Q);
  const std::vector<double> S = cumulative_length(Q);
  const double LQ = S.back();
  const Index m = static_cast<Index>(Q.size()) - 1;

  // ---- §3.5.3 D-8 trimming ----
  double trim_a = 0.0, trim_b = 0.0;
  std::vector<double> r(Q.size());
  for (std::size_t i = 0; i < Q.size(); ++i) r[i] = dfb_at(Q[i]) - 0.5 * h_min;  // inscribed radius
  // Length to cut at one end: every point of the end's half of the curve with s_end < r(p(s)) goes
  // (the part need not be contiguous when the raw path hugs the surface near a tip), so the cut lies
  // at the crossing of g(s) = s_end - r(p(s)) after the innermost negative sample, interpolated
  // linearly. ok = false when even the midpoint violates it.
  auto trimmed_end = [&](bool from_start, bool& ok) {
    auto s_end = [&](Index i) { return from_start ? S[i] : LQ - S[i]; };
    auto at = [&](Index t) { return from_start ? t : m - t; };  // t-th sample walking inwards
    Index last_bad = -1;
    for (Index t = 0; t <= m && s_end(at(t)) <= 0.5 * LQ; ++t)
      if (s_end(at(t)) - r[at(t)] < 0) last_bad = t;
    ok = last_bad < m && s_end(at(last_bad + 1)) <= 0.5 * LQ;
    if (last_bad < 0 || !ok) return 0.0;
    const Index ib = at(last_bad), ig = at(last_bad + 1);
    const double gb = s_end(ib) - r[ib], gg = s_end(ig) - r[ig];
    const double lam = -gb / (gg - gb);
    return s_end(ib) + lam * (s_end(ig) - s_end(ib));
  };
  auto trims = [&](EndKind k) { return settings.trim_closed_ends && k != EndKind::Open; };
  if (trims(kind_R) || trims(kind_E)) {
    bool ok_a = true, ok_b = true;
    const double a = trims(kind_R) ? trimmed_end(true, ok_a) : 0.0;
    const double b = trims(kind_E) ? trimmed_end(false, ok_b) : 0.0;
    if (ok_a && ok_b && LQ - a - b >= 4.0 * delta) {
      trim_a = a;
      trim_b = b;
    } else {
      res.notes.push_back(cat("trimming skipped: less than 4 delta = ", 4.0 * delta, " mm of the ", LQ,
                              " mm curve would remain"));
    }
  }
  Curve C = (trim_a > 0 || trim_b > 0) ? sub_curve(Q, S, trim_a, LQ - trim_b) : Q;
  res.ends[0].trimmed = trim_a;
  res.ends[1].trimmed = trim_b;

  // ---- §3.6 capped ends: re-extend linearly along the end tangent to the cap plane ----
  double ext[2] = {0.0, 0.0};
  double r_join[2] = {0.0, 0.0};
  for (int e = 0; e < 2; ++e) {
    const auto& user = e == 0 ? settings.start : settings.end;
    if (!user || !user->cap_normal) continue;
    const std::vector<double> SC = cumulative_length(C);
    const double Lc = SC.back();
    std::size_t seg = 0;
    const Vec3 q = e == 0 ? C.front() : C.back();
    const Vec3 inner = point_at(C, SC, e == 0 ? std::min(sigma, Lc) : Lc - std::min(sigma, Lc), seg);
    const Vec3 t = (q - inner).normalized();
    const Vec3 nrm = mask.direction.transpose() * user->cap_normal->normalized();  // local frame
    const Vec3 c = to_local(user->position);
    const double denom = nrm.dot(t);
    r_join[e] = std::max(dfb_at(q) - 0.5 * h_min, 0.5 * h_min);
    if (std::abs(denom) < 1e-6) {
      res.notes.push_back(
          cat(e == 0 ? "start" : "end", " cap: end tangent parallel to the cap plane, not extended"));
      continue;
    }
    const double len = nrm.dot(c - q) / denom;
    if (!(len > 0)) continue;
    ext[e] = len;
    if (e == 0)
      C.insert(C.begin(), q + len * t);
    else
      C.push_back(q + len * t);
  }
  res.ends[0].extended = ext[0];
  res.ends[1].extended = ext[1];
  res.curve = to_mat(C);

  // ---- §3.5.4-5 atoms and radii ----
  const std::vector<double> SC = cumulative_length(C);
  const double Lc = SC.back();
  const Index na = settings.atom_count;
  res.atoms.resize(na, 3);
  res.radii.resize(na);
  res.atom_arc_length.resize(na);
  std::size_t seg = 0;
  for (Index k = 0; k < na; ++k) {
    const double s = k + 1 == na ? Lc : Lc * static_cast<double>(k) / static_cast<double>(na - 1);
    const Vec3 p = point_at(C, SC, s, seg);
    res.atoms.row(k) = world_of_local(p).transpose();
    res.atom_arc_length[k] = s;
    if (ext[0] > 0 && s < ext[0])
      res.radii[k] = r_join[0];
    else if (ext[1] > 0 && s > Lc - ext[1])
      res.radii[k] = r_join[1];
    else
      res.radii[k] = std::max(dfb_at(p) - 0.5 * h_min, 0.5 * h_min);
  }

  if (settings.keep_distance_field) res.dfb = std::move(df.dfb);
  return res;
}

}  // namespace medspring
