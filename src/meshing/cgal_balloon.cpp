// The balloon surface (balloon.hpp), ALGORITHMS.md §1.1 / §4.4:
//   1. CGAL isotropic remeshing to an edge length found by a secant search on the node count;
//   2. exact count by scored edge collapses / splits (valence gain first, then length);
//   3. valence-driven flips + tangential relaxation (CGAL's, then ours);
//   4. defect migration: random plateau flips (fixed seed) that move 5-7 valence pairs until
//      they cancel, keeping the most regular mesh;
//   5. error-weighted relaxation and feature snapping that pull nodes onto organ ridges;
// every node projected onto the organ (AABB tree) after every move. Compiled in one translation unit
// with cgal_meshing.cpp (cgal_support.hpp).
#include "cgal_support.hpp"

namespace medspring {

using namespace cgal_detail;

namespace {

/// The state of one balloon build: the working mesh, the organ to project on, the target length.
struct Balloon {
  Mesh m;
  const SurfaceQuery& organ;
  double l = 1.0;                    // target edge length, mm
  double max_flip_deviation = 0.15;  // fraction of l
  Index flips = 0;

  /// Valence-driven flips: an edge is flipped when that lowers sum (valence - 6)^2 over its four
  /// vertices and the new pair of triangles is well shaped, not folded, and stays on the organ.
  Index flip_pass() {
    Index total = 0;
    for (int pass = 0; pass < 50; ++pass) {
      Index n = 0;
      for (const ED e : m.edges()) {
        const HD h = m.halfedge(e);
        const VD a = m.source(h), b = m.target(h);
        const VD c = m.target(m.next(h)), d = m.target(m.next(m.opposite(h)));
        const int va = valence(m, a), vb = valence(m, b), vc = valence(m, c), vd = valence(m, d);
        const int before = sq(va - 6) + sq(vb - 6) + sq(vc - 6) + sq(vd - 6);
        const int after = sq(va - 7) + sq(vb - 7) + sq(vc - 5) + sq(vd - 5);
        if (after >= before || va <= 3 || vb <= 3 || c == d) continue;
        if (CGAL::halfedge(c, d, m).second) continue;  // c-d already an edge
        if (!flip_geometry_ok(a, b, c, d)) continue;
        CGAL::Euler::flip_edge(h, m);
        ++n;
      }
      total += n;
      if (n == 0) break;
    }
    flips += total;
    return total;
  }

  // Faces (a,b,c) and (b,a,d) become (a,d,c) and (d,b,c).
  bool flip_geometry_ok(VD a, VD b, VD c, VD d) const {
    const Point &pa = m.point(a), &pb = m.point(b), &pc = m.point(c), &pd = m.point(d);
    const Vector n1 = normal_of(pa, pb, pc), n2 = normal_of(pb, pa, pd);
    const Vector n3 = normal_of(pa, pd, pc), n4 = normal_of(pd, pb, pc);
    const Vector avg = n1 / std::max(norm(n1), 1e-300) + n2 / std::max(norm(n2), 1e-300);
    if (cos_between(n3, avg) <= 0.2 || cos_between(n4, avg) <= 0.2) return false;  // folded
    const double dihedral_old = cos_between(n1, n2), dihedral_new = cos_between(n3, n4);
    if (dihedral_new < std::min(dihedral_old, std::cos(35.0 * kPi / 180.0))) return false;
    constexpr double kMinAngle = 12.0 * kPi / 180.0;
    if (min_angle(pa, pd, pc) < kMinAngle || min_angle(pd, pb, pc) < kMinAngle) return false;
    const Point mid = CGAL::midpoint(pc, pd);
    return organ.distance(mid) <= max_flip_deviation * l;
  }

  /// Sum over the nodes of (valence - 6)^2: the irregularity the flips lower.
  long irregularity() const {
    long e = 0;
    for (const VD v : m.vertices()) e += sq(valence(m, v) - 6);
    return e;
  }

  /// Defect migration: random valence flips that do not raise the irregularity (plateau moves let
  /// 5-7 pairs wander until they meet and cancel), from a fixed-seed generator (deterministic).
  Index walk(std::mt19937& rng, int sweeps) {
    Index n = 0;
    const auto ne = static_cast<std::uint32_t>(m.number_of_edges());
    for (int s = 0; s < sweeps; ++s) {
      for (std::uint32_t t = 0; t < ne; ++t) {
        const ED e(static_cast<Mesh::size_type>(rng() % ne));
        if (m.is_removed(e)) continue;
        const HD h = m.halfedge(e);
        const VD a = m.source(h), b = m.target(h);
        const VD c = m.target(m.next(h)), d = m.target(m.next(m.opposite(h)));
        const int va = valence(m, a), vb = valence(m, b), vc = valence(m, c), vd = valence(m, d);
        const int before = sq(va - 6) + sq(vb - 6) + sq(vc - 6) + sq(vd - 6);
        const int after = sq(va - 7) + sq(vb - 7) + sq(vc - 5) + sq(vd - 5);
        if (after > before || va <= 4 || vb <= 4 || c == d) continue;
        if (after == before && (rng() & 1u)) continue;
        if (CGAL::halfedge(c, d, m).second) continue;
        if (!flip_geometry_ok(a, b, c, d)) continue;
        CGAL::Euler::flip_edge(h, m);
        ++n;
      }
    }
    flips += n;
    return n;
  }

  /// The organ point farthest from the balloon surface and its distance.
  std::pair<Point, double> farthest_organ_point(const std::vector<Point>& samples) const {
    Triangles tris;
    tris.reserve(m.number_of_faces());
    for (const FD f : m.faces()) {
      const HD h = m.halfedge(f);
      tris.emplace_back(m.point(m.source(h)), m.point(m.target(h)), m.point(m.target(m.next(h))));
    }
    const SurfaceQuery balloon(std::move(tris));
    Point worst = samples.front();
    double dmax = -1.0;
    for (const Point& p : samples) {
      const double d = balloon.distance(p);
      if (d > dmax) {
        dmax = d;
        worst = p;
      }
    }
    return {worst, dmax};
  }

  /// Feature capture: the organ point farthest from the balloon pulls the nearest balloon node
  /// that can move onto it without folding or degrading its triangles; kept only when the
  /// organ-to-balloon distance drops. Lowers the Hausdorff distance at ridges the uniform node
  /// spacing misses (the renal pelvis at the hilum).
  Index snap_features(const std::vector<Point>& samples, int max_moves) {
    Index moves = 0;
    auto [worst, dmax] = farthest_organ_point(samples);
    std::vector<std::pair<double, VD>> near;
    for (int it = 0; it < max_moves; ++it) {
      near.clear();
      for (const VD v : m.vertices()) near.emplace_back(CGAL::squared_distance(m.point(v), worst), v);
      std::sort(near.begin(), near.end());
      bool improved = false;
      for (std::size_t k = 0; k < std::min<std::size_t>(near.size(), 6) && !improved; ++k) {
        const VD v = near[k].second;
        if (!fan_ok_after_move(v, VD(), worst, 15.0)) continue;
        const Point old = m.point(v);
        m.point(v) = worst;
        const auto [w2, d2] = farthest_organ_point(samples);
        if (d2 < dmax - 1e-9) {
          worst = w2;
          dmax = d2;
          improved = true;
          ++moves;
        } else {
          m.point(v) = old;
        }
      }
      if (!improved) break;
    }
    return moves;
  }

  /// Error-weighted relaxation: every organ sample (point s, area a) finds its closest balloon
  /// point q on face f with barycentric weights lambda; the corners of f accumulate
  /// w * lambda_i * s with w = a (1 + (|s - q| / tau)^2), and each node moves half-way to its
  /// weighted centroid, projected onto the organ. Uniform weights give a Lloyd-like smoothing;
  /// the error term draws nodes to ridges the balloon cuts (lowers the Hausdorff distance).
  void fit_relax(const std::vector<Point>& samples, const std::vector<double>& sample_area, double tau,
                 int iterations) {
    std::vector<VD> corner;
    for (int it = 0; it < iterations; ++it) {
      Triangles tris;
      corner.clear();
      for (const FD f : m.faces()) {
        const HD h = m.halfedge(f);
        const VD a = m.source(h), b = m.target(h), c = m.target(m.next(h));
        tris.emplace_back(m.point(a), m.point(b), m.point(c));
        corner.insert(corner.end(), {a, b, c});
      }
      Tree tree(tris.cbegin(), tris.cend());
      tree.accelerate_distance_queries();
      std::vector<double> W(m.num_vertices(), 0.0);
      std::vector<Vector> C(m.num_vertices(), CGAL::NULL_VECTOR);
      for (std::size_t i = 0; i < samples.size(); ++i) {
        const auto [q, prim] = tree.closest_point_and_primitive(samples[i]);
        const auto f = static_cast<std::size_t>(prim - tris.cbegin());
        const Triangle& t = tris[f];
        // Barycentric coordinates of q in t (q lies in t's plane, inside or on its boundary).
        const Vector n = CGAL::cross_product(t[1] - t[0], t[2] - t[0]);
        const double nn = n.squared_length();
        if (!(nn > 0.0)) continue;
        const double l0 = (CGAL::cross_product(t[2] - t[1], q - t[1]) * n) / nn;
        const double l1 = (CGAL::cross_product(t[0] - t[2], q - t[2]) * n) / nn;
        const double lam[3] = {std::max(l0, 0.0), std::max(l1, 0.0), std::max(1.0 - l0 - l1, 0.0)};
        const double d = std::sqrt(CGAL::squared_distance(samples[i], q)) / tau;
        const double w = sample_area[i] * (1.0 + d * d);
        for (int k = 0; k < 3; ++k) {
          const VD v = corner[3 * f + static_cast<std::size_t>(k)];
          W[v] += w * lam[k];
          C[v] = C[v] + (w * lam[k]) * (samples[i] - CGAL::ORIGIN);
        }
      }
      for (const VD v : m.vertices()) {
        if (!(W[v] > 0.0)) continue;
        const Point target = CGAL::ORIGIN + C[v] / W[v];
        const Point p = m.point(v);
        for (double alpha = 0.5; alpha > 0.05; alpha *= 0.5) {
          const Point moved = organ.closest(p + alpha * (target - p));
          if (fan_ok_after_move(v, VD(), moved, 15.0)) {
            m.point(v) = moved;
            break;
          }
        }
      }
    }
  }

  /// Tangential relaxation (CGAL, uniform weights) followed by projection onto the organ.
  void relax(unsigned iterations = 1) {
    PMP::tangential_relaxation(m.vertices(), m, CGAL::parameters::number_of_iterations(iterations));
    project_all();
  }
  void project_all() {
    for (const VD v : m.vertices()) m.point(v) = organ.closest(m.point(v));
  }

  /// Faces around v other than the ones containing the edge (v, w): would they flip or degenerate
  /// when v moves to p?
  bool fan_ok_after_move(VD v, VD w, const Point& p, double min_angle_deg = 5.0) const {
    for (const HD h : CGAL::halfedges_around_target(m.halfedge(v), m)) {
      if (m.is_border(h)) return false;
      const VD x = m.source(h), y = m.target(m.next(h));  // face (x, v, y)
      if (x == w || y == w) continue;
      const Point &px = m.point(x), &py = m.point(y);
      const Vector before = normal_of(px, m.point(v), py), after = normal_of(px, p, py);
      if (cos_between(before, after) < 0.5) return false;
      if (min_angle(px, p, py) < min_angle_deg * kPi / 180.0) return false;
    }
    return true;
  }

  /// Collapses the edge whose removal best regularises the valences (ties: the shortest edge).
  bool collapse_one() {
    double best = std::numeric_limits<double>::infinity();
    ED best_e;
    Point best_p;
    for (const ED e : m.edges()) {
      const HD h = m.halfedge(e);
      const VD a = m.source(h), b = m.target(h);
      const VD c = m.target(m.next(h)), d = m.target(m.next(m.opposite(h)));
      const int va = valence(m, a), vb = valence(m, b), vc = valence(m, c), vd = valence(m, d);
      const int merged = va + vb - 4;
      if (vc <= 4 || vd <= 4 || merged > 9) continue;
      const int delta =
          sq(merged - 6) + sq(vc - 7) + sq(vd - 7) - sq(va - 6) - sq(vb - 6) - sq(vc - 6) - sq(vd - 6);
      const double len = std::sqrt(CGAL::squared_distance(m.point(a), m.point(b)));
      const double score = delta + 2.0 * len / l;
      if (score >= best) continue;
      if (!CGAL::Euler::does_satisfy_link_condition(e, m)) continue;
      const Point p = organ.closest(CGAL::midpoint(m.point(a), m.point(b)));
      if (!fan_ok_after_move(a, b, p) || !fan_ok_after_move(b, a, p)) continue;
      best = score;
      best_e = e;
      best_p = p;
    }
    if (!std::isfinite(best)) return false;
    const VD kept = CGAL::Euler::collapse_edge(best_e, m);
    m.point(kept) = best_p;
    return true;
  }

  /// Splits the edge whose new midpoint best regularises the valences (ties: the longest edge).
  bool split_one() {
    double best = std::numeric_limits<double>::infinity();
    HD best_h;
    for (const ED e : m.edges()) {
      const HD h = m.halfedge(e);
      const VD c = m.target(m.next(h)), d = m.target(m.next(m.opposite(h)));
      const int vc = valence(m, c), vd = valence(m, d);
      if (vc >= 8 || vd >= 8) continue;
      const int delta = sq(4 - 6) + sq(vc - 5) + sq(vd - 5) - sq(vc - 6) - sq(vd - 6);
      const double len = std::sqrt(CGAL::squared_distance(m.point(m.source(h)), m.point(m.target(h))));
      const double score = delta - 2.0 * len / l;
      if (score < best) {
        best = score;
        best_h = h;
      }
    }
    if (!std::isfinite(best)) return false;
    const HD h = best_h, o = m.opposite(h);
    const Point p = organ.closest(CGAL::midpoint(m.point(m.source(h)), m.point(m.target(h))));
    // split_edge: hnew = (source -> w) followed by h = (w -> target); then triangulate both quads.
    const HD hnew = CGAL::Euler::split_edge(h, m);
    const VD w = m.target(hnew);
    m.point(w) = p;
    CGAL::Euler::split_face(hnew, m.next(h), m);
    CGAL::Euler::split_face(o, m.next(m.opposite(hnew)), m);
    return true;
  }

  /// CGAL's isotropic remeshing without splits or collapses: valence flips, relaxation, projection.
  void cgal_regularise(unsigned iterations) {
    auto project = [this](VD v) { return organ.closest(m.point(v)); };
    PMP::isotropic_remeshing(m.faces(), l, m,
                             CGAL::parameters::number_of_iterations(iterations)
                                 .do_split(false)
                                 .do_collapse(false)
                                 .projection_functor(project));
  }
};

/// Isotropic remeshing of `input` to edge length l, projecting onto the organ.

Mesh remesh(const Mesh& input, double l, unsigned iterations, const SurfaceQuery& organ) {
  Mesh m = input;
  auto project = [&m, &organ](VD v) { return organ.closest(m.point(v)); };
  PMP::isotropic_remeshing(m.faces(), l, m,
                           CGAL::parameters::number_of_iterations(iterations)
                               .number_of_relaxation_steps(1)
                               .projection_functor(project));
  m.collect_garbage();
  return m;
}

void sample_organ(const SurfaceMesh& s, double spacing, std::vector<Point>& pts, std::vector<double>& w) {
  pts.clear();
  w.assign(static_cast<std::size_t>(s.num_vertices()), 0.0);
  for (Index i = 0; i < s.num_vertices(); ++i) pts.push_back(to_point(s.V, i));
  for (Index f = 0; f < s.num_faces(); ++f) {
    const Vec3 a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const int n = std::clamp(static_cast<int>(std::ceil(longest / spacing)), 1, 64);
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const double weight = area / (0.5 * (n + 1) * (n + 2));
    for (int k = 0; k < 3; ++k) w[static_cast<std::size_t>(s.F(f, k))] += weight;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        if ((i == 0 && j == 0) || i == n || j == n) continue;  // corners are the vertex samples
        const Vec3 p = a + (static_cast<double>(i) / n) * (b - a) + (static_cast<double>(j) / n) * (c - a);
        pts.emplace_back(p.x(), p.y(), p.z());
        w.push_back(weight);
      }
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// balloon.hpp

BalloonResult build_balloon_surface(const SurfaceMesh& organ_in, const BalloonSettings& settings) {
  const auto t0 = std::chrono::steady_clock::now();
  const Index N = settings.target_nodes;
  require(settings.min_nodes >= 4, "BalloonSettings::min_nodes must be >= 4 (got ", settings.min_nodes, ")");
  require(N >= settings.min_nodes, "balloon surface: target_nodes ", N, " is too small: at least ",
          settings.min_nodes, " nodes are needed to follow an organ surface");
  require(settings.remesh_iterations >= 1, "BalloonSettings::remesh_iterations must be >= 1 (got ",
          settings.remesh_iterations, ")");
  require(settings.length_trials >= 1, "BalloonSettings::length_trials must be >= 1 (got ",
          settings.length_trials, ")");
  require(settings.migration_rounds >= 0, "BalloonSettings::migration_rounds must be >= 0 (got ",
          settings.migration_rounds, ")");
  require(settings.fit_iterations >= 0, "BalloonSettings::fit_iterations must be >= 0 (got ",
          settings.fit_iterations, ")");
  require(settings.feature_snaps >= 0, "BalloonSettings::feature_snaps must be >= 0 (got ",
          settings.feature_snaps, ")");
  require_positive(settings.fit_error_scale, "BalloonSettings::fit_error_scale");
  require_positive(settings.max_flip_deviation, "BalloonSettings::max_flip_deviation");

  const ClosedManifoldReport check = require_closed_manifold(organ_in, "balloon surface: organ");
  require(check.mesh.components == 1, "balloon surface: organ has ", check.mesh.components,
          " connected components; a balloon surface wraps one (keep the largest component first)");

  BalloonResult result;
  BalloonReport& rep = result.report;
  rep.organ_size_mm = check.mesh.bbox_diagonal;
  if (std::string w = organ_size_warning(rep.organ_size_mm); !w.empty()) rep.warnings.push_back(std::move(w));

  // Outward orientation of the organ (one closed, consistently oriented component).
  SurfaceMesh organ = organ_in;
  if (signed_volume(organ.V, organ.F) < 0.0) organ.F.col(1).swap(organ.F.col(2));
  const double area = surface_area(organ.V, organ.F);
  require(area > 0.0, "balloon surface: organ has zero area");

  const SurfaceQuery query(to_triangles(organ));
  const Mesh input = to_cgal(organ, "balloon surface: organ");

  // 1. Edge length for ~N nodes: V ~ 2 A / (sqrt(3) l^2) on a regular triangulation; secant steps
  //    on V ~ c / l^2 from the measured counts, until within 1 % of N. Keep the closest trial (ties:
  //    the one above N, as collapses can regularise valences while splits create valence-4 nodes).
  double l = std::sqrt(2.0 * area / (std::sqrt(3.0) * static_cast<double>(N)));
  Mesh best;
  double best_l = l;
  Index best_gap = std::numeric_limits<Index>::max();
  for (int trial = 0; trial < settings.length_trials; ++trial) {
    Mesh m = remesh(input, l, static_cast<unsigned>(settings.remesh_iterations), query);
    const auto V = static_cast<Index>(m.number_of_vertices());
    const Index gap = V >= N ? 2 * (V - N) : 2 * (N - V) + 1;
    if (gap < best_gap) {
      best_gap = gap;
      best = std::move(m);
      best_l = l;
    }
    if (std::abs(V - N) <= std::max<Index>(1, N / 100) || V < 4) break;
    l *= std::sqrt(static_cast<double>(V) / static_cast<double>(N));
  }
  rep.target_edge_length = best_l;
  rep.remeshed_nodes = static_cast<Index>(best.number_of_vertices());

  // 2. Exact count: scored collapses or splits, each followed by valence flips.
  Balloon b{std::move(best), query, best_l, settings.max_flip_deviation, 0};
  auto count = [&b] { return static_cast<Index>(b.m.number_of_vertices()); };
  while (count() > N) {
    require(b.collapse_one(), "balloon surface: target_nodes ", N,
            " is too small for this organ: no edge can be collapsed without breaking the surface at ",
            count(), " nodes");
    ++rep.collapses;
    b.flip_pass();
  }
  while (count() < N) {
    require(b.split_one(), "balloon surface: cannot add nodes (at ", count(), " of ", N, ")");
    ++rep.splits;
    b.flip_pass();
  }
  b.m.collect_garbage();

  // 3. Regularisation: CGAL's valence flips + relaxation + projection, then ours.
  for (int round = 0; round < 5; ++round) {
    b.cgal_regularise(1);
    b.flip_pass();
    b.relax(1);
  }
  b.flip_pass();

  // 4. Defect migration: rounds of plateau flips, greedy flips and relaxation; keep the most
  //    regular mesh; stop after migration_patience rounds without progress.
  std::mt19937 rng(20070101u);
  Mesh best_mesh = b.m;
  long best_irregularity = b.irregularity();
  for (int round = 0, since_best = 0;
       round < settings.migration_rounds && best_irregularity > 0 && since_best < settings.migration_patience;
       ++round, ++since_best) {
    b.walk(rng, 2);
    b.flip_pass();
    b.relax(2);
    b.flip_pass();
    const long irregularity = b.irregularity();
    if (irregularity < best_irregularity) {
      best_irregularity = irregularity;
      best_mesh = b.m;
      since_best = -1;
    }
  }
  b.m = std::move(best_mesh);

  // 5. Fit: error-weighted relaxation and feature snapping against dense organ samples.
  std::vector<Point> samples;
  std::vector<double> sample_area;
  sample_organ(organ, best_l / 2.0, samples, sample_area);
  b.fit_relax(samples, sample_area, settings.fit_error_scale * best_l, settings.fit_iterations);
  rep.feature_snaps = b.snap_features(samples, settings.feature_snaps);

  // 6. Checks on the result.
  require(count() == N, "balloon surface: internal error: ", count(), " nodes instead of ", N);
  require(!PMP::does_self_intersect(b.m), "balloon surface: target_nodes ", N,
          " is too small for this organ (", rep.organ_size_mm,
          " mm across): the surface intersects itself; use more nodes");
  result.mesh = from_cgal(b.m);
  const ClosedManifoldReport out = check_closed_manifold(result.mesh);
  require(out.ok() && out.mesh.components == 1, "balloon surface: target_nodes ", N,
          " is too small for this organ: the result is not a closed manifold surface (", out.mesh.summary(),
          ")");
  if (signed_volume(result.mesh.V, result.mesh.F) < 0.0) result.mesh.F.col(1).swap(result.mesh.F.col(2));
  // Generated numbering: renumber for locality (the users' node numbers are the ones of this result).
  if (settings.locality_order) result.mesh = permute_vertices(result.mesh, locality_order(result.mesh));

  rep.nodes = result.mesh.num_vertices();
  rep.faces = result.mesh.num_faces();
  rep.edges = out.mesh.edges;
  rep.flips = b.flips;
  rep.valence_histogram = valence_histogram(vertex_adjacency(rep.nodes, unique_edges(result.mesh.F)));
  const Index six = rep.valence_histogram.size() > 6 ? rep.valence_histogram[6] : 0;
  rep.valence6_fraction = static_cast<double>(six) / static_cast<double>(rep.nodes);
  if (settings.measure_distance) {
    const SurfaceDistance d = surface_distance(result.mesh, organ);
    rep.hausdorff_mm = d.hausdorff;
    rep.mean_distance_mm = d.mean;
  }
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

SurfaceMesh balloon_surface(const SurfaceMesh& organ, const BalloonSettings& settings) {
  return build_balloon_surface(organ, settings).mesh;
}

}  // namespace medspring
