// A vessel's rebuilt surface against its input away from the cut ends (docs/vessels.md, "Distance to the
// input"); internal to the builders.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

#include "medspring/core/check.hpp"
#include "medspring/medial/reconstruction.hpp"
#include "medspring/meshing/mesh_union.hpp"
#include "medspring/meshing/surface_distance.hpp"
#include "vessel_tree_march.hpp"

namespace medspring::builders_detail {

namespace {

struct AxisPoint {
  Index branch = 0, atom = 0;                                 // the nearer atom of the closest segment
  double from_cut = std::numeric_limits<double>::infinity();  // arc to the nearest cut end of its branch
  bool near_cut = false;
};

// The closest point of the atom polylines of every branch to p, and whether it lies within one end radius
// of arc of a cut end.
AxisPoint nearest_axis(const std::vector<Centerline>& lines, const std::vector<VecX>& arc,
                       const std::vector<CutEnd>& cuts, const Vec3& p) {
  AxisPoint r;
  double best = std::numeric_limits<double>::infinity();
  double s = 0.0;
  for (std::size_t b = 0; b < lines.size(); ++b) {
    const PolylinePoint q = closest_point_on_polyline(lines[b].points, p);
    if (q.distance >= best) continue;
    best = q.distance;
    const VecX& a = arc[b];
    const Index i = std::min<Index>(q.segment, static_cast<Index>(a.size()) - 2);
    const double lam = q.segment > i ? 1.0 : q.lambda;
    r.branch = static_cast<Index>(b);
    r.atom = i + (lam > 0.5 ? 1 : 0);
    s = a[i] + lam * (a[i + 1] - a[i]);
  }
  const VecX& a = arc[static_cast<std::size_t>(r.branch)];
  const Centerline& c = lines[static_cast<std::size_t>(r.branch)];
  for (const CutEnd& e : cuts) {
    if (e.branch != r.branch) continue;
    const double d = e.at_end ? a[a.size() - 1] - s : s;
    const double radius = e.at_end ? c.radii[c.size() - 1] : c.radii[0];
    r.from_cut = std::min(r.from_cut, d);
    r.near_cut = r.near_cut || d < radius;
  }
  return r;
}

// Faces whose normal points against the summed normals of the faces around their corners (a fold).
std::vector<Index> folded_faces(const SurfaceMesh& m) {
  const MatX3 fn = face_normals(m.V, m.F);
  MatX3 vn = MatX3::Zero(m.V.rows(), 3);
  for (Index f = 0; f < m.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) vn.row(m.F(f, c)) += fn.row(f);
  std::vector<Index> bad;
  for (Index f = 0; f < m.num_faces(); ++f) {
    const Vec3 around = (vn.row(m.F(f, 0)) + vn.row(m.F(f, 1)) + vn.row(m.F(f, 2))).transpose();
    if (fn.row(f).dot(around) <= 0.0) bad.push_back(f);
  }
  return bad;
}

// The faces with a node moved from `prev` that make the surface unacceptable: zero-area triangles (two
// nodes on one place), intersecting pairs, folds (faces that were not folded in `prev`; folds_before,
// sorted).
std::vector<Index> problem_faces(const SurfaceMesh& m, const MatX3& prev,
                                 const std::vector<Index>& folds_before) {
  auto moved = [&](Index f) {
    for (int c = 0; c < 3; ++c)
      if (m.V.row(m.F(f, c)) != prev.row(m.F(f, c))) return true;
    return false;
  };
  std::vector<Index> bad;
  for (Index f = 0; f < m.num_faces(); ++f) {
    const Vec3 a = m.V.row(m.F(f, 0)).transpose(), b = m.V.row(m.F(f, 1)).transpose(),
               c = m.V.row(m.F(f, 2)).transpose();
    const double e2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    if ((b - a).cross(c - a).norm() <= 1e-6 * e2 && moved(f)) bad.push_back(f);
  }
  if (!bad.empty()) return bad;
  std::vector<Index> cross;
  try {
    cross = self_intersecting_faces(m, "vessel surface fitted to the wall");
  } catch (const InvalidInput&) {  // a zero-area triangle CGAL finds: every moved face is suspect
    for (Index f = 0; f < m.num_faces(); ++f)
      if (moved(f)) bad.push_back(f);
    return bad;
  }
  for (Index f : cross)
    if (moved(f)) bad.push_back(f);
  for (Index f : folded_faces(m))
    if (!std::binary_search(folds_before.begin(), folds_before.end(), f) && moved(f)) bad.push_back(f);
  return bad;
}

// Puts the nodes of the faces that problem_faces finds back towards `prev` (halfway in the first 4 passes,
// then all the way) until none is left; false (and m.V =
// prev) when that takes more than 16 passes.
bool settle(SurfaceMesh& m, const MatX3& prev) {
  const std::vector<Index> folds = folded_faces(SurfaceMesh{prev, m.F});
  for (int pass = 0; pass < 16; ++pass) {
    const std::vector<Index> bad = problem_faces(m, prev, folds);
    if (bad.empty()) return true;
    for (Index f : bad)  // first half of the way back, then all of it
      for (int c = 0; c < 3; ++c) {
        const Index v = m.F(f, c);
        m.V.row(v) = pass < 4 ? MatX3(0.5 * (m.V.row(v) + prev.row(v))) : MatX3(prev.row(v));
      }
  }
  m.V = prev;
  return false;
}

// Closest hit in (0, t_max] of the ray o + t w with the faces `faces` of `mesh` (Moeller-Trumbore, both
// sides), +inf if none.
double ray_hit(const SurfaceMesh& mesh, const std::vector<Index>& faces, const Vec3& o, const Vec3& w,
               double t_max) {
  double best = std::numeric_limits<double>::infinity();
  for (Index f : faces) {
    const Vec3 a = mesh.V.row(mesh.F(f, 0)).transpose();
    const Vec3 e1 = mesh.V.row(mesh.F(f, 1)).transpose() - a, e2 = mesh.V.row(mesh.F(f, 2)).transpose() - a;
    const Vec3 p = w.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-14 * e1.norm() * e2.norm()) continue;
    const Vec3 sv = o - a;
    const double u = sv.dot(p) / det;
    if (u < -1e-9 || u > 1.0 + 1e-9) continue;
    const Vec3 q = sv.cross(e1);
    const double v = w.dot(q) / det;
    if (v < -1e-9 || u + v > 1.0 + 1e-9) continue;
    const double t = e2.dot(q) / det;
    if (t > 1e-9 && t <= t_max && t < best) best = t;
  }
  return best;
}

// The area centroid, in the plane through p normal to t, of the wall section seen from p (rays every
// 360/kRays degrees); false when a ray misses within 3 r or the section is far from round (the plane cuts
// another branch or a cap).
constexpr int kRays = 24;
bool section_centroid(const SurfaceMesh& input, const std::vector<Index>& faces, const Vec3& p, const Vec3& t,
                      double r, Vec3& g) {
  Vec3 u = t.cross(std::abs(t.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).normalized();
  const Vec3 v = t.cross(u);
  double x[kRays], y[kRays], hmin = std::numeric_limits<double>::infinity(), hmax = 0.0;
  for (int j = 0; j < kRays; ++j) {
    const double th = 2.0 * std::numbers::pi * j / kRays;
    const double h = ray_hit(input, faces, p, std::cos(th) * u + std::sin(th) * v, 3.0 * r);
    if (!std::isfinite(h)) return false;
    x[j] = h * std::cos(th);
    y[j] = h * std::sin(th);
    hmin = std::min(hmin, h);
    hmax = std::max(hmax, h);
  }
  if (hmax > 2.5 * hmin) return false;
  double A = 0.0, cx = 0.0, cy = 0.0;
  for (int j = 0; j < kRays; ++j) {
    const int k = (j + 1) % kRays;
    const double c = x[j] * y[k] - x[k] * y[j];
    A += 0.5 * c;
    cx += (x[j] + x[k]) * c;
    cy += (y[j] + y[k]) * c;
  }
  if (A <= 0.0) return false;
  g = p + (cx / (6.0 * A)) * u + (cy / (6.0 * A)) * v;
  return true;
}

}  // namespace

Index fill_enclosed_holes(MaskVolume& mask, Index* holes) {
  const Index nx = mask.dims[0], ny = mask.dims[1], nz = mask.dims[2];
  std::vector<char> outside(mask.size(), 0);  // background reached from the border (6-connected)
  std::vector<std::size_t> stack;
  auto seed = [&](Index i, Index j, Index k) {
    const std::size_t w = mask.index(i, j, k);
    if (mask.data[w] == 0 && !outside[w]) {
      outside[w] = 1;
      stack.push_back(w);
    }
  };
  for (Index k = 0; k < nz; ++k)
    for (Index j = 0; j < ny; ++j)
      for (Index i = 0; i < nx; ++i)
        if (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1) seed(i, j, k);
  while (!stack.empty()) {
    const std::size_t v = stack.back();
    stack.pop_back();
    const Index i = static_cast<Index>(v % static_cast<std::size_t>(nx));
    const Index j = static_cast<Index>((v / static_cast<std::size_t>(nx)) % static_cast<std::size_t>(ny));
    const Index k = static_cast<Index>(v / (static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny)));
    if (i > 0) seed(i - 1, j, k);
    if (i < nx - 1) seed(i + 1, j, k);
    if (j > 0) seed(i, j - 1, k);
    if (j < ny - 1) seed(i, j + 1, k);
    if (k > 0) seed(i, j, k - 1);
    if (k < nz - 1) seed(i, j, k + 1);
  }
  Index filled = 0;
  MaskVolume holes_only = mask;
  std::fill(holes_only.data.begin(), holes_only.data.end(), std::uint8_t{0});
  for (std::size_t w = 0; w < mask.size(); ++w)
    if (mask.data[w] == 0 && !outside[w]) {
      mask.data[w] = 1;
      holes_only.data[w] = 1;
      ++filled;
    }
  if (holes) {
    *holes = 0;
    if (filled > 0) largest_component(holes_only, holes);
  }
  return filled;
}

CenterlineTree recentre_tree(const CenterlineTree& ct, const SurfaceMesh& input, Recentring& rep) {
  CenterlineTree out = ct;
  const Index nb = static_cast<Index>(ct.branches.size());
  std::vector<std::pair<Vec3, double>> junctions;  // every junction point and its radius
  for (Index b = 1; b < nb; ++b) {
    const Centerline& c = ct.branches[static_cast<std::size_t>(b)].line;
    junctions.emplace_back(c.points.row(0).transpose(), c.radii[0]);
  }
  std::vector<char> has_child(static_cast<std::size_t>(nb), 0);
  for (Index b = 1; b < nb; ++b)
    has_child[static_cast<std::size_t>(ct.branches[static_cast<std::size_t>(b)].parent)] = 1;
  double shift_sum = 0.0;
  MatX3 fc(input.num_faces(), 3);  // face centroids and the largest distance of a corner from it
  VecX fr(input.num_faces());
  for (Index f = 0; f < input.num_faces(); ++f) {
    fc.row(f) = (input.V.row(input.F(f, 0)) + input.V.row(input.F(f, 1)) + input.V.row(input.F(f, 2))) / 3.0;
    fr[f] = 0.0;
    for (int q = 0; q < 3; ++q) fr[f] = std::max(fr[f], (input.V.row(input.F(f, q)) - fc.row(f)).norm());
  }
  for (Index b = 0; b < nb; ++b) {
    const Centerline& c = ct.branches[static_cast<std::size_t>(b)].line;
    const Index n = c.size();
    const VecX s = c.arc_length();
    MatX3 offset = MatX3::Zero(n, 3);
    std::vector<char> fitted(static_cast<std::size_t>(n), 0);
    for (Index k = 0; k < n; ++k) {
      const double r = c.radii[k];
      const Vec3 p = c.points.row(k).transpose();
      // not at a cut end (within one radius of arc), nor where the section plane reaches a junction
      const bool root_start = b == 0 && s[k] < r;
      const bool leaf_end = !has_child[static_cast<std::size_t>(b)] && s[n - 1] - s[k] < c.radii[n - 1];
      bool near_junction = false;
      for (const auto& [j, rj] : junctions) near_junction = near_junction || (p - j).norm() < 2.0 * (r + rj);
      if (root_start || leaf_end || near_junction) continue;
      // tangent over one radius of arc either side (the skeleton's voxel steps are noisy)
      Index a = k, e = k;
      while (a > 0 && s[k] - s[a] < r) --a;
      while (e < n - 1 && s[e] - s[k] < r) ++e;
      if (a == e) continue;
      const Vec3 t = (c.points.row(e) - c.points.row(a)).transpose().normalized();
      std::vector<Index> faces;  // the input's faces the section plane cuts near the point
      for (Index f = 0; f < input.num_faces(); ++f) {
        const Vec3 d = fc.row(f).transpose() - p;
        if (std::abs(d.dot(t)) <= fr[f] && d.norm() <= 3.5 * r + fr[f]) faces.push_back(f);
      }
      Vec3 g = p;
      bool ok = true;
      for (int it = 0; ok && it < 3; ++it) ok = section_centroid(input, faces, g, t, r, g);
      if (!ok || (g - p).norm() > 0.5 * r) continue;
      offset.row(k) = (g - p).transpose();
      fitted[static_cast<std::size_t>(k)] = 1;
    }
    // smoothed along the branch over about one radius either side (points not fitted count as 0: a taper)
    MatX3 smooth = MatX3::Zero(n, 3);
    for (Index k = 0; k < n; ++k) {
      if (!fitted[static_cast<std::size_t>(k)]) continue;
      Index cnt = 0;
      for (Index q = 0; q < n; ++q)
        if (std::abs(s[q] - s[k]) <= c.radii[k]) {
          smooth.row(k) += offset.row(q);
          ++cnt;
        }
      smooth.row(k) /= static_cast<double>(cnt);
      ++rep.points;
      shift_sum += smooth.row(k).norm();
      rep.max_shift_mm = std::max(rep.max_shift_mm, smooth.row(k).norm());
    }
    Centerline& o = out.branches[static_cast<std::size_t>(b)].line;
    o.points += smooth;
    // the radius: the distance to the wall from the centred point (the largest inscribed sphere there)
    std::vector<Index> moved;
    for (Index k = 0; k < n; ++k)
      if (fitted[static_cast<std::size_t>(k)]) moved.push_back(k);
    if (!moved.empty()) {
      MatX3 P(static_cast<Index>(moved.size()), 3);
      for (std::size_t q = 0; q < moved.size(); ++q) P.row(static_cast<Index>(q)) = o.points.row(moved[q]);
      const VecX d = distances_to_surface(P, input);
      for (std::size_t q = 0; q < moved.size(); ++q) o.radii[moved[q]] = d[static_cast<Index>(q)];
    }
    rep.total += n;
  }
  rep.mean_shift_mm = rep.points > 0 ? shift_sum / static_cast<double>(rep.points) : 0.0;
  return out;
}

Index refine_long_edges(SurfaceMesh& m, double max_edge) {
  std::map<std::pair<Index, Index>, Index> mid;
  std::vector<Vec3> added;
  const Index n0 = m.num_vertices();
  auto split = [&](Index a, Index b) -> Index {  // -1: not split
    if ((m.V.row(a) - m.V.row(b)).norm() <= max_edge) return -1;
    const auto key = std::minmax(a, b);
    auto it = mid.find(key);
    if (it != mid.end()) return it->second;
    const Index k = n0 + static_cast<Index>(added.size());
    added.push_back(0.5 * (m.V.row(a) + m.V.row(b)).transpose());
    mid.emplace(key, k);
    return k;
  };
  std::vector<std::array<Index, 3>> F;
  for (Index f = 0; f < m.num_faces(); ++f) {
    Index v[3] = {m.F(f, 0), m.F(f, 1), m.F(f, 2)};
    Index e[3] = {split(v[0], v[1]), split(v[1], v[2]), split(v[2], v[0])};
    const int cnt = (e[0] >= 0) + (e[1] >= 0) + (e[2] >= 0);
    if (cnt == 0) {
      F.push_back({v[0], v[1], v[2]});
    } else if (cnt == 3) {
      F.push_back({v[0], e[0], e[2]});
      F.push_back({e[0], v[1], e[1]});
      F.push_back({e[2], e[1], v[2]});
      F.push_back({e[0], e[1], e[2]});
    } else {
      // rotate: cnt 1 puts the split edge first (v0 v1); cnt 2 puts the edge left whole last (v2 v0)
      int r = 0;
      while (cnt == 1 ? e[0] < 0 : e[2] >= 0) {
        std::rotate(v, v + 1, v + 3);
        std::rotate(e, e + 1, e + 3);
        if (++r > 3) break;
      }
      if (cnt == 1) {
        F.push_back({v[0], e[0], v[2]});
        F.push_back({e[0], v[1], v[2]});
      } else {
        F.push_back({e[0], v[1], e[1]});
        F.push_back({v[0], e[0], e[1]});
        F.push_back({v[0], e[1], v[2]});
      }
    }
  }
  m.V.conservativeResize(n0 + static_cast<Index>(added.size()), 3);
  for (std::size_t k = 0; k < added.size(); ++k) m.V.row(n0 + static_cast<Index>(k)) = added[k].transpose();
  m.F.resize(static_cast<Index>(F.size()), 3);
  for (std::size_t f = 0; f < F.size(); ++f) m.F.row(static_cast<Index>(f)) << F[f][0], F[f][1], F[f][2];
  return static_cast<Index>(added.size());
}

WallFit fit_to_wall(SurfaceMesh& m, const SurfaceMesh& input, int rounds) {
  WallFit r;
  const Index n = m.num_vertices();
  std::vector<std::vector<Index>> nb(static_cast<std::size_t>(n));
  for (Index f = 0; f < m.num_faces(); ++f)
    for (int c = 0; c < 3; ++c)
      for (int e = 1; e < 3; ++e) nb[static_cast<std::size_t>(m.F(f, c))].push_back(m.F(f, (c + e) % 3));
  for (auto& v : nb) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  }
  MatX3 N;
  for (int round = 0; round < rounds; ++round) {
    const MatX3 prev = m.V;
    vertex_normals(m.V, m.F, N);
    MatX3 P(n, 3);
    for (Index v = 0; v < n; ++v) {  // half a tangential umbrella step, then onto the wall
      Vec3 mean = Vec3::Zero();
      for (Index w : nb[static_cast<std::size_t>(v)]) mean += m.V.row(w).transpose();
      const auto& ns = nb[static_cast<std::size_t>(v)];
      Vec3 L =
          ns.empty() ? Vec3::Zero() : Vec3(mean / static_cast<double>(ns.size()) - m.V.row(v).transpose());
      const Vec3 nv = N.row(v).transpose();
      L -= L.dot(nv) * nv;
      P.row(v) = m.V.row(v) + 0.5 * L.transpose();
    }
    m.V = closest_points_on_surface(P, input);
    if (!settle(m, prev)) break;  // the nodes of crossing or folding faces stay where they were
    ++r.rounds;
    Index moved = 0;
    for (Index v = 0; v < n; ++v) moved += m.V.row(v) != prev.row(v);
    r.held = n - moved;
  }
  // then the wall's features between the nodes (a bump narrower than the node spacing): every input vertex
  // farther than 0.5 mm from the surface pulls its nearest node onto itself (the farthest one wins)
  for (int round = 0; round < 3; ++round) {
    const MatX3 prev = m.V;
    const VecX d = distances_to_surface(input.V, m);
    std::vector<Index> pull(static_cast<std::size_t>(n), -1);
    std::vector<double> pull_d(static_cast<std::size_t>(n), 0.0);
    for (Index q = 0; q < input.V.rows(); ++q) {
      if (d[q] <= 0.5) continue;
      Index best = 0;
      double bd = std::numeric_limits<double>::infinity();
      for (Index v = 0; v < n; ++v) {
        const double e = (m.V.row(v) - input.V.row(q)).squaredNorm();
        if (e < bd) {
          bd = e;
          best = v;
        }
      }
      if (d[q] > pull_d[static_cast<std::size_t>(best)]) {
        pull_d[static_cast<std::size_t>(best)] = d[q];
        pull[static_cast<std::size_t>(best)] = q;
      }
    }
    Index pulled = 0;
    for (Index v = 0; v < n; ++v)
      if (pull[static_cast<std::size_t>(v)] >= 0) {
        m.V.row(v) = input.V.row(pull[static_cast<std::size_t>(v)]);
        ++pulled;
      }
    if (pulled == 0) break;
    if (!settle(m, prev)) break;
    Index kept = 0;
    for (Index v = 0; v < n; ++v) kept += pull[static_cast<std::size_t>(v)] >= 0 && m.V.row(v) != prev.row(v);
    r.pulled += kept;
  }
  r.folds = static_cast<Index>(folded_faces(m).size());
  return r;
}

void measure_away_from_ends(const SurfaceMesh& rebuilt, const SurfaceMesh& input,
                            const std::vector<Centerline>& lines, const std::vector<CutEnd>& cuts,
                            VesselSummary& s) {
  require(!lines.empty(), "vessel distance: no atoms");
  std::vector<VecX> arc;
  for (const Centerline& c : lines) arc.push_back(c.arc_length());
  const auto ba = (rebuilt.V.colwise().maxCoeff() - rebuilt.V.colwise().minCoeff()).norm();
  const auto bb = (input.V.colwise().maxCoeff() - input.V.colwise().minCoeff()).norm();
  const double spacing = std::max(std::max(ba, bb) / 250.0, 1e-6);  // as surface_distance's default
  AwayFromEnds& r = s.away;
  r = AwayFromEnds{};
  r.measured = true;
  double wsum = 0.0, sum = 0.0;
  auto one_side = [&](const SurfaceMesh& from, const SurfaceMesh& to, const char* direction) {
    VecX w;
    const MatX3 P = surface_samples(from, spacing, &w);
    std::vector<Index> keep;
    std::vector<AxisPoint> where;
    for (Index k = 0; k < P.rows(); ++k) {
      const AxisPoint a = nearest_axis(lines, arc, cuts, P.row(k).transpose());
      if (a.near_cut) continue;
      keep.push_back(k);
      where.push_back(a);
    }
    MatX3 Q(static_cast<Index>(keep.size()), 3);
    for (std::size_t q = 0; q < keep.size(); ++q) Q.row(static_cast<Index>(q)) = P.row(keep[q]);
    const VecX d = keep.empty() ? VecX() : distances_to_surface(Q, to);
    double side_sum = 0.0, side_w = 0.0;
    for (Index q = 0; q < d.size(); ++q) {
      const double wq = w[keep[static_cast<std::size_t>(q)]];
      side_sum += wq * d[q];
      side_w += wq;
      if (d[q] > 2.0) ++r.samples_over_2mm;
      if (d[q] > r.hausdorff_mm) {
        r.hausdorff_mm = d[q];
        const AxisPoint& a = where[static_cast<std::size_t>(q)];
        r.worst_branch = a.branch;
        r.worst_atom = a.atom;
        r.worst_from_cut_mm = std::isfinite(a.from_cut) ? a.from_cut : -1.0;
        r.worst_point = Q.row(q).transpose();
        r.worst_direction = direction;
      }
    }
    r.samples += static_cast<Index>(d.size());
    if (side_w > 0) sum += side_sum / side_w;
    wsum += 1.0;
  };
  one_side(rebuilt, input, "rebuilt surface -> input");
  one_side(input, rebuilt, "input -> rebuilt surface");
  r.mean_mm = wsum > 0 ? sum / wsum : 0.0;
  // the rebuilt nodes away from the cut ends
  std::vector<Index> nodes;
  for (Index k = 0; k < rebuilt.V.rows(); ++k)
    if (!nearest_axis(lines, arc, cuts, rebuilt.V.row(k).transpose()).near_cut) nodes.push_back(k);
  MatX3 N(static_cast<Index>(nodes.size()), 3);
  for (std::size_t q = 0; q < nodes.size(); ++q) N.row(static_cast<Index>(q)) = rebuilt.V.row(nodes[q]);
  const VecX dn = nodes.empty() ? VecX() : distances_to_surface(N, input);
  r.nodes = static_cast<Index>(dn.size());
  for (Index q = 0; q < dn.size(); ++q) {
    r.nodes_over_2mm += dn[q] > 2.0;
    r.node_max_mm = std::max(r.node_max_mm, dn[q]);
  }
}

}  // namespace medspring::builders_detail
