// A vessel's rebuilt surface against its input away from the cut ends (docs/vessels.md, "Distance to the
// input"); internal to the builders.
#include <algorithm>
#include <cmath>
#include <limits>

#include "medspring/core/check.hpp"
#include "medspring/medial/reconstruction.hpp"
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

}  // namespace

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
