#include "medspring/local/patch.hpp"

#include <algorithm>
#include <utility>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

void require_fixed_flags(const std::vector<std::uint8_t>& fixed, Index n, const char* what) {
  require(fixed.empty() || static_cast<Index>(fixed.size()) == n, what, ": model-fixed flags have ",
          fixed.size(), " entries, the mesh has ", n, " nodes");
}

// Fills free_nodes and copies the springs / stiffnesses into the patch.
void finish_patch(LocalPatch& p, const std::vector<Index>& ends, double k_loc) {
  p.free_nodes.clear();
  for (Index a = 0; a < p.size(); ++a)
    if (p.fixed[a] == 0) p.free_nodes.push_back(a);
  const Index S = static_cast<Index>(ends.size() / 2);
  p.springs.resize(S, 2);
  for (Index s = 0; s < S; ++s) {
    const auto e = 2 * static_cast<std::size_t>(s);
    p.springs(s, 0) = ends[e];
    p.springs(s, 1) = ends[e + 1];
  }
  p.k = VecX::Constant(S, k_loc);
}

}  // namespace

LocalPatch make_local_patch(const Adjacency& adj, const std::vector<Index>& nodes, Index contact,
                            double k_loc, const std::vector<std::uint8_t>& fixed) {
  const Index n = adj.num_nodes();
  require_positive(k_loc, "local patch: k_loc");
  require_fixed_flags(fixed, n, "local patch");
  require(!nodes.empty(), "local patch: the node list is empty");
  require_index(contact, n, "local patch: contact node");
  // (global, local) pairs sorted by global index: membership test by binary search, no #N buffer.
  std::vector<std::pair<Index, Index>> order(nodes.size());
  for (std::size_t a = 0; a < nodes.size(); ++a) {
    require(nodes[a] >= 0 && nodes[a] < n, "local patch: nodes[", a, "]: index ", nodes[a],
            " out of range [0, ", n, ")");
    order[a] = {nodes[a], static_cast<Index>(a)};
  }
  std::sort(order.begin(), order.end());
  for (std::size_t a = 1; a < order.size(); ++a)
    require(order[a].first != order[a - 1].first, "local patch: node ", order[a].first, " is listed twice");
  auto local_of = [&](Index g) -> Index {
    const auto it = std::lower_bound(order.begin(), order.end(), std::pair<Index, Index>{g, -1});
    return (it != order.end() && it->first == g) ? it->second : -1;
  };

  LocalPatch p;
  p.nodes = nodes;
  p.contact = contact;
  p.contact_local = local_of(contact);
  require(p.contact_local >= 0, "local patch: contact node ", contact, " is not one of the patch nodes");
  p.fixed.assign(nodes.size(), 0);
  std::vector<Index> ends;
  for (Index a = 0; a < p.size(); ++a) {
    const Index g = nodes[a];
    std::uint8_t f = fixed.empty() ? 0 : (fixed[g] != 0);
    for (const Index* q = adj.begin(g); q != adj.end(g); ++q) {
      const Index b = local_of(*q);
      if (b < 0) {
        f = 1;  // D-15: a mesh neighbour outside the patch
      } else if (g < *q) {
        ends.push_back(a);
        ends.push_back(b);
      }
    }
    p.fixed[a] = f;
  }
  finish_patch(p, ends, k_loc);
  return p;
}

LocalPatch structured_window_patch(Index rings, Index spokes, GridNode contact, const PatchOptions& options,
                                   const std::vector<std::uint8_t>& fixed) {
  const Index hw = options.half_width;
  require(rings >= 2, "local patch (tube window): rings must be >= 2 (got ", rings, ")");
  require(spokes >= 3, "local patch (tube window): spokes must be >= 3 (got ", spokes, ")");
  require(hw >= 0, "local patch (tube window): half_width must be >= 0 (got ", hw, ")");
  require(spokes >= 2 * hw + 1, "local patch (tube window): a window of half-width ", hw, " needs at least ",
          2 * hw + 1, " spokes per ring (got ", spokes, ")");
  require_index(contact.ring, rings, "local patch (tube window): contact ring");
  require_index(contact.spoke, spokes, "local patch (tube window): contact spoke");
  require_positive(options.k_loc, "local patch: k_loc");
  require_fixed_flags(fixed, rings * spokes, "local patch (tube window)");

  const Index ic = contact.ring, jc = contact.spoke, W = 2 * hw + 1;
  const Index i_lo = std::max<Index>(0, ic - hw), i_hi = std::min<Index>(rings - 1, ic + hw);
  auto spoke_of = [&](Index delta) { return ((jc + delta) % spokes + spokes) % spokes; };
  // Local index of grid node (i, j), or -1 outside the window.
  auto local_of = [&](Index i, Index j) -> Index {
    if (i < i_lo || i > i_hi) return -1;
    const Index d = ((j - jc) % spokes + spokes) % spokes;
    const Index delta = d <= hw ? d : (d >= spokes - hw ? d - spokes : spokes);
    if (delta == spokes) return -1;
    return (i - i_lo) * W + (delta + hw);
  };

  LocalPatch p;
  const Index P = (i_hi - i_lo + 1) * W;
  p.nodes.resize(static_cast<std::size_t>(P));
  p.fixed.assign(static_cast<std::size_t>(P), 0);
  for (Index i = i_lo; i <= i_hi; ++i)
    for (Index delta = -hw; delta <= hw; ++delta)
      p.nodes[(i - i_lo) * W + delta + hw] = i * spokes + spoke_of(delta);
  p.contact = ic * spokes + jc;
  p.contact_local = local_of(ic, jc);

  std::vector<Index> ends;
  ends.reserve(6 * static_cast<std::size_t>(P));
  for (Index a = 0; a < P; ++a) {
    const Index i = i_lo + a / W, j = spoke_of(a % W - hw), g = p.nodes[a];
    std::uint8_t f = fixed.empty() ? 0 : (fixed[g] != 0);
    // The six tube-grid neighbours (§1.1): circumferential, axial, diagonal (i,j)-(i+1,j+1).
    const Index nb[6][2] = {{i, j + 1}, {i, j - 1}, {i + 1, j}, {i - 1, j}, {i + 1, j + 1}, {i - 1, j - 1}};
    for (const auto& q : nb) {
      if (q[0] < 0 || q[0] >= rings) continue;
      const Index jq = (q[1] % spokes + spokes) % spokes;
      const Index b = local_of(q[0], jq);
      if (b < 0) {
        f = 1;  // D-15
      } else if (g < p.nodes[b]) {
        ends.push_back(a);
        ends.push_back(b);
      }
    }
    p.fixed[a] = f;
  }
  finish_patch(p, ends, options.k_loc);
  return p;
}

LocalPatch structured_window_patch(Index rings, Index spokes, Index contact, const PatchOptions& options,
                                   const std::vector<std::uint8_t>& fixed) {
  require(rings >= 2 && spokes >= 3, "local patch (tube window): grid of ", rings, " rings x ", spokes,
          " spokes is too small (needs >= 2 x 3)");
  require_index(contact, rings * spokes, "local patch (tube window): contact node");
  return structured_window_patch(rings, spokes, GridNode{contact / spokes, contact % spokes}, options, fixed);
}

LocalPatch bfs_local_patch(const Adjacency& adj, const MatX3& X0, Index contact, const PatchOptions& options,
                           const std::vector<std::uint8_t>& fixed) {
  const Index n = adj.num_nodes();
  require_index(contact, n, "local patch (BFS): contact node");
  require(options.count >= 1, "local patch (BFS): count must be >= 1 (got ", options.count, ")");
  require(options.count <= n, "local patch (BFS): patch of ", options.count,
          " nodes is larger than the mesh (", n, " nodes)");
  require(X0.rows() == n, "local patch (BFS): rest positions have ", X0.rows(), " rows, the mesh has ", n,
          " nodes");
  return make_local_patch(adj, bfs_patch(adj, X0, contact, options.count), contact, options.k_loc, fixed);
}

}  // namespace medspring
