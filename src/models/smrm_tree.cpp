#include "medspring/models/smrm_tree.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "medspring/core/check.hpp"
#include "medspring/medial/reconstruction.hpp"

namespace medspring {

namespace {

inline Vec3 row3(const MatX3& M, Index i) {
  return {M(i, 0), M(i, 1), M(i, 2)};
}

Centerline sub_line(const Centerline& c, Index first, Index last) {
  Centerline s;
  s.points = c.points.middleRows(first, last - first + 1);
  s.radii = c.radii.segment(first, last - first + 1);
  return s;
}

void check_line(const Centerline& line) {
  const std::string w = cat("centerline '", line.name, "'");
  require(line.radii.size() == line.points.rows(), w, ": ", line.points.rows(), " points but ",
          line.radii.size(), " radii");
  require(line.size() >= 2, w, ": has ", line.size(), " point(s); a branch needs at least 2");
  for (Index k = 0; k < line.size(); ++k) {
    require(line.points.row(k).allFinite(), w, ": point ", k, ": coordinates must be finite");
    require(std::isfinite(line.radii[k]) && line.radii[k] > 0, w, ": point ", k, ": radius must be > 0 (got ",
            line.radii[k], ")");
  }
}

// A loop: the line comes back within tol of one of its own points more than two radii of arc behind.
void check_no_loop(const Centerline& line, double tol) {
  const VecX s = line.arc_length();
  for (Index i = 2; i < line.size(); ++i)
    for (Index j = 0; j + 1 < i; ++j) {
      if (s[i] - s[j] <= 2.0 * std::max(line.radii[i], line.radii[j]) + tol) break;
      if ((line.points.row(i) - line.points.row(j)).norm() <= tol)
        throw InvalidInput(cat("centerline '", line.name, "': point ", i, " comes back to point ", j,
                               " (a loop; a vessel tree has none)"));
    }
}

}  // namespace

Index CenterlineTree::junctions() const {
  std::vector<char> has_child(branches.size(), 0);
  for (const Branch& b : branches)
    if (b.parent >= 0) has_child[static_cast<std::size_t>(b.parent)] = 1;
  return static_cast<Index>(std::count(has_child.begin(), has_child.end(), 1));
}

CenterlineTree merge_centerlines(const std::vector<Centerline>& input, double tol) {
  require(!input.empty(), "centerline tree: no centerlines");
  require(std::isfinite(tol) && tol > 0, "centerline tree: tolerance must be > 0 mm (got ", tol, ")");
  std::vector<Centerline> lines;
  for (std::size_t k = 0; k < input.size(); ++k) {
    Centerline c = input[k];
    if (c.name.empty()) c.name = cat("line ", k);
    check_line(c);
    c = deduplicate(c, 1e-3);
    require(c.size() >= 2, "centerline '", c.name, "': fewer than 2 distinct points");
    check_no_loop(c, tol);
    if (k > 0) {
      const double d = (c.points.row(0) - lines[0].points.row(0)).norm();
      require(d <= tol, "centerline '", c.name, "': starts ", d, " mm from the start of '", lines[0].name,
              "' (branches must meet: the lines of a tree share their start within ", tol, " mm)");
    }
    lines.push_back(std::move(c));
  }
  CenterlineTree tree;
  auto agree = [&](std::size_t a, std::size_t b, Index q) {
    return q < lines[a].size() && q < lines[b].size() &&
           (lines[a].points.row(q) - lines[b].points.row(q)).norm() <= tol;
  };
  // group: lines that agree up to index s (the branch's first point)
  auto split = [&](auto& self, std::vector<std::size_t> group, Index s, Index parent) -> void {
    const std::size_t rep = group.front();
    Index e = s;
    if (group.size() == 1) {
      e = lines[rep].size() - 1;
    } else {
      for (;;) {
        bool all = true;
        for (std::size_t g : group) all = all && agree(rep, g, e + 1);
        if (!all) break;
        ++e;
      }
    }
    CenterlineTree::Branch br;
    br.line = sub_line(lines[rep], s, e);
    br.parent = parent;
    if (parent >= 0) {  // start exactly at the parent's junction point (the lines agree there within tol)
      const Centerline& p = tree.branches[static_cast<std::size_t>(parent)].line;
      br.line.points.row(0) = p.points.row(p.size() - 1);
      br.line.radii[0] = p.radii[p.size() - 1];
    }
    br.line.name = group.size() == 1 ? lines[rep].name : cat("trunk of ", lines[rep].name);
    const Index b = static_cast<Index>(tree.branches.size());
    tree.branches.push_back(std::move(br));
    if (group.size() == 1) return;
    std::vector<std::vector<std::size_t>> parts;
    for (std::size_t g : group) {
      if (lines[g].size() <= e + 1) continue;  // ends at the junction: its path is the trunk itself
      bool placed = false;
      for (auto& p : parts)
        if (agree(p.front(), g, e + 1)) {
          p.push_back(g);
          placed = true;
          break;
        }
      if (!placed) parts.push_back({g});
    }
    for (auto& p : parts) self(self, std::move(p), e, b);
  };
  std::vector<std::size_t> all(lines.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = k;
  split(split, all, 0, -1);
  return tree;
}

CenterlineTree tree_from_parents(const MatX3& atoms, const std::vector<Index>& parent, const VecX& radii) {
  const Index n = static_cast<Index>(atoms.rows());
  require(n >= 2, "vessel tree: needs at least 2 atoms (got ", n, ")");
  require(static_cast<Index>(parent.size()) == n, "vessel tree: ", parent.size(), " parent indices for ", n,
          " atoms");
  require(radii.size() == n, "vessel tree: ", radii.size(), " radii for ", n, " atoms");
  require(parent[0] == -1, "vessel tree: atom 0 is the root and must have parent -1 (got ", parent[0], ")");
  std::vector<Index> children(static_cast<std::size_t>(n), 0);
  for (Index i = 0; i < n; ++i) {
    require(atoms.row(i).allFinite(), "vessel tree: atom ", i, ": coordinates must be finite");
    require(std::isfinite(radii[i]) && radii[i] > 0, "vessel tree: atom ", i, ": radius must be > 0 (got ",
            radii[i], ")");
    if (i > 0) {
      const Index p = parent[static_cast<std::size_t>(i)];
      require(p >= 0 && p < i, "vessel tree: atom ", i, ": parent ", p, " must be an earlier atom (0..",
              i - 1, "; -1 only for the root)");
      ++children[static_cast<std::size_t>(p)];
    }
  }
  require(children[0] == 1, "vessel tree: the root atom 0 must have exactly one child (got ", children[0],
          ")");
  std::vector<std::vector<Index>> kids(static_cast<std::size_t>(n));
  for (Index j = 1; j < n; ++j)
    kids[static_cast<std::size_t>(parent[static_cast<std::size_t>(j)])].push_back(j);
  CenterlineTree tree;
  struct Start {
    Index from, first, parent_branch;
  };
  std::vector<Start> starts{{0, kids[0].front(), -1}};
  for (std::size_t q = 0; q < starts.size(); ++q) {
    const Start st = starts[q];
    std::vector<Index> path{st.from};
    Index a = st.first;
    for (;;) {  // follow single children to a leaf or the next junction
      path.push_back(a);
      if (kids[static_cast<std::size_t>(a)].size() != 1) break;
      a = kids[static_cast<std::size_t>(a)].front();
    }
    CenterlineTree::Branch br;
    br.parent = st.parent_branch;
    const Index m = static_cast<Index>(path.size());
    br.line.points.resize(m, 3);
    br.line.radii.resize(m);
    for (Index k = 0; k < m; ++k) {
      br.line.points.row(k) = atoms.row(path[static_cast<std::size_t>(k)]);
      br.line.radii[k] = radii[path[static_cast<std::size_t>(k)]];
    }
    const Index b = static_cast<Index>(tree.branches.size());
    br.line.name = cat("branch ", b, " (atoms ", path.front(), "..", path.back(), ")");
    tree.branches.push_back(std::move(br));
    for (Index c : kids[static_cast<std::size_t>(path.back())]) starts.push_back({path.back(), c, b});
  }
  return tree;
}

// ---------------------------------------------------------------------------------------------------

SmrmTree::SmrmTree(const CenterlineTree& tree, const SmrmTreeSettings& settings)
    : settings_(settings), tree_(tree) {
  const SmrmSettings& vs = settings.vessel;
  const Index nb = static_cast<Index>(tree.branches.size());
  require(nb >= 1, "vessel tree: has no branches");
  require(vs.atoms >= 3, "vessel tree: atoms must be >= 3 (got ", vs.atoms, ")");
  require(vs.spokes >= 3, "vessel tree: spokes must be >= 3 (got ", vs.spokes, ")");
  std::vector<double> path_length(static_cast<std::size_t>(nb), 0.0);
  for (Index b = 0; b < nb; ++b) {
    const CenterlineTree::Branch& br = tree.branches[static_cast<std::size_t>(b)];
    Centerline c = br.line;
    if (c.name.empty()) c.name = cat("branch ", b);
    check_line(c);
    if (b == 0) {
      require(br.parent == -1, "vessel tree: branch 0 is the root and must have parent -1 (got ", br.parent,
              ")");
    } else {
      require(br.parent >= 0 && br.parent < b, "vessel tree: branch ", b, ": parent ", br.parent,
              " must be an earlier branch");
      const Centerline& p = tree.branches[static_cast<std::size_t>(br.parent)].line;
      const double d = (c.points.row(0) - p.points.row(p.size() - 1)).norm();
      require(d <= 1e-6, "vessel tree: branch ", b, " ('", c.name, "') starts ", d,
              " mm from the end of its parent ", br.parent, " (branches must meet at the junction)");
    }
    path_length[static_cast<std::size_t>(b)] =
        c.length() + (br.parent >= 0 ? path_length[static_cast<std::size_t>(br.parent)] : 0.0);
  }
  const double longest = *std::max_element(path_length.begin(), path_length.end());
  const double h = longest / static_cast<double>(vs.atoms - 1);
  require(h > 1e-9, "vessel tree: has zero length");

  // Atoms: the root's, then per child its atoms after the shared junction atom.
  std::vector<Centerline> sampled(static_cast<std::size_t>(nb));
  atoms_.assign(static_cast<std::size_t>(nb), {});
  parent_.resize(static_cast<std::size_t>(nb));
  std::vector<Vec3> X;
  std::vector<double> R;
  std::vector<char> has_child(static_cast<std::size_t>(nb), 0);
  for (Index b = 0; b < nb; ++b) {
    const CenterlineTree::Branch& br = tree.branches[static_cast<std::size_t>(b)];
    parent_[static_cast<std::size_t>(b)] = br.parent;
    if (br.parent >= 0) has_child[static_cast<std::size_t>(br.parent)] = 1;
    const double L = br.line.length();
    const long segs = std::lround(L / h);
    require(segs >= 1, "vessel tree: branch ", b, " ('", br.line.name, "') is ", L,
            " mm long, shorter than two atoms at the tree's spacing of ", h, " mm");
    const Centerline c =
        resample(deduplicate(br.line, 1e-3), std::max<Index>(3, static_cast<Index>(segs) + 1));
    std::vector<Index>& ids = atoms_[static_cast<std::size_t>(b)];
    for (Index i = 0; i < c.size(); ++i) {
      if (i == 0 && br.parent >= 0) {
        ids.push_back(atoms_[static_cast<std::size_t>(br.parent)].back());  // the shared junction atom
        continue;
      }
      ids.push_back(static_cast<Index>(X.size()));
      X.push_back(row3(c.points, i));
      R.push_back(c.radii[i]);
    }
    sampled[static_cast<std::size_t>(b)] = c;
  }
  junctions_ = static_cast<Index>(std::count(has_child.begin(), has_child.end(), 1));
  const Index n = static_cast<Index>(X.size());

  // Chain model over all atoms (§5.2 per branch; junction bending terms parent -> child).
  const ChainSettings& cs = vs.chain;
  require_positive(cs.mass, "vessel tree: chain.mass");
  require_nonnegative(cs.beta, "vessel tree: chain.beta");
  require_nonnegative(cs.kr, "vessel tree: chain.kr");
  require_positive(cs.k, "vessel tree: chain.k");
  const DuffingSettings duffing = cs.nonlinear ? cs.duffing : DuffingSettings{.mode = DuffingMode::Linear};
  ModelBuilder mb("vessel tree");
  for (Index i = 0; i < n; ++i)
    mb.add_node(X[static_cast<std::size_t>(i)], cs.mass, cs.beta * cs.mass, cs.kr);
  if (cs.fix_first) mb.set_fixed(0);
  auto positions = [&](const std::vector<Index>& ids) {
    MatX3 P(static_cast<Index>(ids.size()), 3);
    for (std::size_t k = 0; k < ids.size(); ++k)
      P.row(static_cast<Index>(k)) = X[static_cast<std::size_t>(ids[k])].transpose();
    return P;
  };
  auto radii_of = [&](const std::vector<Index>& ids, Index b) {
    VecX r(static_cast<Index>(ids.size()));
    for (std::size_t k = 0; k < ids.size(); ++k)
      r[static_cast<Index>(k)] = sampled[static_cast<std::size_t>(b)].radii[static_cast<Index>(k)];
    return r;
  };
  auto bending_of = [&](const MatX3& P, const VecX& r) -> VecX {
    if (vs.bending == BendingMode::Wall) return wall_bending_stiffness(P, r, vs.wall);
    VecX k = VecX::Constant(P.rows(), cs.kb);
    k[0] = k[P.rows() - 1] = 0.0;
    return k;
  };
  branches_.resize(static_cast<std::size_t>(nb));
  node_begin_.assign(static_cast<std::size_t>(nb) + 1, 0);
  std::vector<MatX3> surfaces;
  std::vector<MatX3i> faces;
  for (Index b = 0; b < nb; ++b) {
    const std::vector<Index>& ids = atoms_[static_cast<std::size_t>(b)];
    const MatX3 P = positions(ids);
    const VecX r = radii_of(ids, b);
    if (!has_child[static_cast<std::size_t>(b)] && cs.fix_last) mb.set_fixed(ids.back());
    for (std::size_t k = 0; k + 1 < ids.size(); ++k) mb.add_spring(ids[k], ids[k + 1], cs.k, duffing);
    const VecX kb = bending_of(P, r);
    for (std::size_t k = 1; k + 1 < ids.size(); ++k)
      if (kb[static_cast<Index>(k)] > 0)
        mb.add_bending(ids[k - 1], ids[k], ids[k + 1], kb[static_cast<Index>(k)]);
    const Index p = parent_[static_cast<std::size_t>(b)];
    if (p >= 0) {  // junction: parent's second-to-last, junction, child's second atom
      const std::vector<Index>& pid = atoms_[static_cast<std::size_t>(p)];
      const std::vector<Index> j3{pid[pid.size() - 2], ids[0], ids[1]};
      // The turn at the junction bends the parent's last half segment (wall of the junction radius r[0])
      // and the child's first half segment (wall of the child's radius r[1]) in series: the harmonic
      // mean of the two E I, weighted by the segment lengths (I ~ r^4 at a fixed thickness ratio).
      const double hp = (X[static_cast<std::size_t>(j3[1])] - X[static_cast<std::size_t>(j3[0])]).norm();
      const double hc = (X[static_cast<std::size_t>(j3[2])] - X[static_cast<std::size_t>(j3[1])]).norm();
      const double r0 = r[0], r1 = r[1];
      const double req = std::pow((hp + hc) / (hp / std::pow(r0, 4) + hc / std::pow(r1, 4)), 0.25);
      VecX rj(3);
      rj << req, req, req;
      const VecX kj = bending_of(positions(j3), rj);
      if (kj[1] > 0) mb.add_bending(j3[0], j3[1], j3[2], kj[1]);
    }
    // The branch's surface: a circular structured tube over its atoms.
    const Index M = vs.spokes, nbA = static_cast<Index>(ids.size());
    MatX3 O(nbA * M, 3);
    for (Index i = 0; i < nbA; ++i)
      for (Index j = 0; j < M; ++j) {
        const double th = 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(M);
        O.row(i * M + j) << r[i] * std::cos(th), r[i] * std::sin(th), 0.0;
      }
    auto v = std::make_shared<SmrmVessel>(smrm_from_offsets(P, O, vs, cat("branch ", b)));
    node_begin_[static_cast<std::size_t>(b) + 1] =
        node_begin_[static_cast<std::size_t>(b)] + static_cast<Index>(v->rest_surface().rows());
    surfaces.push_back(v->rest_surface());
    faces.push_back(v->faces());
    branches_[static_cast<std::size_t>(b)] = std::move(v);
  }
  model_ = mb.build();
  const Index ns = node_begin_.back();
  rest_surface_.resize(ns, 3);
  Index nf = 0;
  for (const auto& f : faces) nf += static_cast<Index>(f.rows());
  faces_.resize(nf, 3);
  Index fo = 0;
  for (Index b = 0; b < nb; ++b) {
    const Index o = node_begin_[static_cast<std::size_t>(b)];
    rest_surface_.middleRows(o, surfaces[static_cast<std::size_t>(b)].rows()) =
        surfaces[static_cast<std::size_t>(b)];
    const MatX3i& F = faces[static_cast<std::size_t>(b)];
    faces_.middleRows(fo, F.rows()) = F.array() + o;
    fo += static_cast<Index>(F.rows());
  }
}

SmrmTree::SmrmTree(const CenterlineTree& tree, const SmrmTreeSettings& settings, const SurfaceMesh& surface)
    : SmrmTree(tree, settings) {
  const MeshReport rep = require_valid_mesh(surface, "vessel tree surface", {.closed = true});
  require(rep.inconsistent_edges == 0, "vessel tree surface: inconsistently oriented (",
          rep.inconsistent_edges, " edges)");
  const Index m = surface.num_vertices(), nb = num_branches();
  // Which branch's rest tube every vertex lies on: |distance to the atoms' polyline - radius there|.
  blend_branch_.assign(static_cast<std::size_t>(m), 0);
  VecX best = VecX::Constant(m, std::numeric_limits<double>::infinity());
  for (Index b = 0; b < nb; ++b) {
    const SmrmVessel& v = *branches_[static_cast<std::size_t>(b)];
    const MatX3& C = v.rest_atoms();
    const VecX& r = v.atom_radius();
    for (Index k = 0; k < m; ++k) {
      const PolylinePoint q = closest_point_on_polyline(C, row3(surface.V, k));
      const Index i = std::min<Index>(q.segment, static_cast<Index>(C.rows()) - 2);
      const double lam = q.segment > i ? 1.0 : q.lambda;
      const double score = std::abs(q.distance - ((1.0 - lam) * r[i] + lam * r[i + 1]));
      if (score < best[k]) {
        best[k] = score;
        blend_branch_[static_cast<std::size_t>(k)] = b;
      }
    }
  }
  blend_.assign(static_cast<std::size_t>(nb), {});
  blend_local_.assign(static_cast<std::size_t>(m), 0);
  for (Index k = 0; k < m; ++k) {
    BlendBranch& bb = blend_[static_cast<std::size_t>(blend_branch_[static_cast<std::size_t>(k)])];
    blend_local_[static_cast<std::size_t>(k)] = static_cast<Index>(bb.nodes.size());
    bb.nodes.push_back(k);
  }
  blend_spoke_.resize(m);
  for (Index b = 0; b < nb; ++b) {
    BlendBranch& bb = blend_[static_cast<std::size_t>(b)];
    const SmrmVessel& v = *branches_[static_cast<std::size_t>(b)];
    MatX3 P(static_cast<Index>(bb.nodes.size()), 3);
    for (std::size_t q = 0; q < bb.nodes.size(); ++q)
      P.row(static_cast<Index>(q)) = surface.V.row(bb.nodes[q]);
    VecX dist;
    bb.binding = bind_to_polyline(P, v.frame_reference(), &dist);  // §5.9 bracket (i, lambda)
    if (bb.binding.lambda.empty())  // keep it generic even with no node (an empty branch)
      bb.binding.lambda.assign(bb.binding.atom.size(), 0.0);
    const FrameReference& ref = v.frame_reference();
    const Index nq = static_cast<Index>(bb.nodes.size());
    bb.o0.resize(nq, 3);
    bb.o1.resize(nq, 3);
    for (Index q = 0; q < nq; ++q) {  // o = F0_a^T (p0 - C0_a) for both bracket atoms
      const Index i = bb.binding.atom[static_cast<std::size_t>(q)];
      const Vec3 p0 = row3(P, q);
      bb.o0.row(q) = (ref.F0.frame(i).transpose() * (p0 - row3(ref.C0, i))).transpose();
      bb.o1.row(q) = (ref.F0.frame(i + 1).transpose() * (p0 - row3(ref.C0, i + 1))).transpose();
    }
    for (std::size_t q = 0; q < bb.nodes.size(); ++q) blend_spoke_[bb.nodes[q]] = dist[static_cast<Index>(q)];
  }
  rest_surface_ = surface.V;
  faces_ = surface.F;
  if (signed_volume(rest_surface_, faces_) < 0.0) faces_.col(1).swap(faces_.col(2));  // outward
}

Index SmrmTree::surface_rows(std::size_t b) const {
  return blended() ? 0 : static_cast<Index>(branches_[b]->rest_surface().rows());
}

SmrmTree::Workspace SmrmTree::make_workspace() const {
  Workspace ws;
  for (std::size_t b = 0; b < branches_.size(); ++b) {
    ws.atoms.emplace_back(static_cast<Index>(atoms_[b].size()), 3);
    ws.surface.emplace_back(surface_rows(b), 3);
    ws.vessel.push_back(branches_[b]->make_workspace());
  }
  return ws;
}

void SmrmTree::map_to_surface(const MatX3& x, Workspace& ws, MatX3& surface) const {
  if (surface.rows() != rest_surface_.rows()) surface.resize(rest_surface_.rows(), 3);
  for (std::size_t b = 0; b < branches_.size(); ++b) {
    const std::vector<Index>& ids = atoms_[b];
    MatX3& A = ws.atoms[b];
    for (std::size_t k = 0; k < ids.size(); ++k) A.row(static_cast<Index>(k)) = x.row(ids[k]);
    if (!blended()) {  // §5.5 frames, §5.7 straight into the branch's rows of the tree surface
      const SmrmVessel& v = *branches_[b];
      compute_frames(A, v.frame_reference(), ws.vessel[b].frames);
      reconstruct(v.binding(), A, ws.vessel[b].frames, ws.vessel[b].scratch,
                  surface.data() + 3 * node_begin_[b]);
      continue;
    }
    const BlendBranch& bb = blend_[b];
    if (bb.nodes.empty()) continue;
    const FrameField& F = ws.vessel[b].frames;
    compute_frames(A, branches_[b]->frame_reference(), ws.vessel[b].frames);  // §5.5
    const double* C = A.data();
    const double* U = F.u.data();
    const double* V = F.v.data();
    const double* T = F.t.data();
    const double* O0 = bb.o0.data();
    const double* O1 = bb.o1.data();
    double* out = surface.data();
    const std::size_t nq = bb.nodes.size();
    for (std::size_t q = 0; q < nq; ++q) {  // both bracket atoms' rigid maps, blended linearly
      const Index i0 = 3 * bb.binding.atom[q], i1 = i0 + 3;
      const double l = bb.binding.lambda[q], w = 1.0 - l;
      const double a = O0[3 * q], bo = O0[3 * q + 1], c = O0[3 * q + 2];
      const double d = O1[3 * q], e = O1[3 * q + 1], g = O1[3 * q + 2];
      double* o = out + 3 * bb.nodes[q];
      for (int r = 0; r < 3; ++r)
        o[r] = w * (C[i0 + r] + a * U[i0 + r] + bo * V[i0 + r] + c * T[i0 + r]) +
               l * (C[i1 + r] + d * U[i1 + r] + e * V[i1 + r] + g * T[i1 + r]);
    }
  }
}

CurvatureCheck SmrmTree::validity(const MatX3& x, Workspace& ws) const {
  CurvatureCheck r;
  for (std::size_t b = 0; b < branches_.size(); ++b) {
    const std::vector<Index>& ids = atoms_[b];
    MatX3& A = ws.atoms[b];
    for (std::size_t k = 0; k < ids.size(); ++k) A.row(static_cast<Index>(k)) = x.row(ids[k]);
    const CurvatureCheck c = branches_[b]->validity(A);
    r.max_rho_kappa = std::max(r.max_rho_kappa, c.max_rho_kappa);
    r.violations += c.violations;
    if (r.first_atom < 0 && c.first_atom >= 0) r.first_atom = ids[static_cast<std::size_t>(c.first_atom)];
  }
  return r;
}

double SmrmTree::max_turning_change_deg(const MatX3& x, Workspace& ws, Index* atom) const {
  double best = 0.0;
  Index where = -1;
  for (std::size_t b = 0; b < branches_.size(); ++b) {
    const std::vector<Index>& ids = atoms_[b];
    MatX3& A = ws.atoms[b];
    for (std::size_t k = 0; k < ids.size(); ++k) A.row(static_cast<Index>(k)) = x.row(ids[k]);
    Index local = -1;
    const double d = branches_[b]->max_turning_change_deg(A, &local);
    if (local >= 0 && (d > best || where < 0)) {
      best = d;
      where = ids[static_cast<std::size_t>(local)];
    }
  }
  if (atom) *atom = where;
  return best;
}

void SmrmTree::map_to_surface(const State& state, MatX3& surface) const {
  const auto ws = workspaces_.acquire([this] { return make_workspace(); });
  map_to_surface(state.x, *ws, surface);
}

Index SmrmTree::node_branch(Index node) const {
  require_index(node, static_cast<Index>(rest_surface_.rows()), "vessel tree: surface node");
  if (blended()) return blend_branch_[static_cast<std::size_t>(node)];
  const auto it = std::upper_bound(node_begin_.begin(), node_begin_.end(), node);
  return static_cast<Index>(it - node_begin_.begin()) - 1;
}

Index SmrmTree::node_atom(Index node) const {
  const Index b = node_branch(node);
  if (blended()) {
    const SurfaceBinding& sb = blend_[static_cast<std::size_t>(b)].binding;
    const std::size_t q = static_cast<std::size_t>(blend_local_[static_cast<std::size_t>(node)]);
    const Index local = sb.atom[q] + (sb.lambda[q] > 0.5 ? 1 : 0);
    return atoms_[static_cast<std::size_t>(b)][static_cast<std::size_t>(local)];
  }
  const Index local =
      branches_[static_cast<std::size_t>(b)]->node_atom(node - node_begin_[static_cast<std::size_t>(b)]);
  return atoms_[static_cast<std::size_t>(b)][static_cast<std::size_t>(local)];
}

void SmrmTree::transfer_force(Index node, const Vec3& F, MatX3& f_dof) const {
  if (blended()) {  // D-14, generic: (1 - lambda) F and lambda F to the bracket atoms of the branch
    const Index b = node_branch(node);
    const SurfaceBinding& sb = blend_[static_cast<std::size_t>(b)].binding;
    const std::size_t q = static_cast<std::size_t>(blend_local_[static_cast<std::size_t>(node)]);
    const std::vector<Index>& ids = atoms_[static_cast<std::size_t>(b)];
    const Index a0 = ids[static_cast<std::size_t>(sb.atom[q])],
                a1 = ids[static_cast<std::size_t>(sb.atom[q] + 1)];
    const double lam = sb.lambda[q];
    if (lam < 1.0 && !model_.fixed[static_cast<std::size_t>(a0)])
      f_dof.row(a0) += ((1.0 - lam) * F).transpose();
    if (lam > 0.0 && !model_.fixed[static_cast<std::size_t>(a1)]) f_dof.row(a1) += (lam * F).transpose();
    return;
  }
  const Index a = node_atom(node);
  if (!model_.fixed[static_cast<std::size_t>(a)]) f_dof.row(a) += F.transpose();
}

double SmrmTree::spoke_length(Index node) const {
  const Index b = node_branch(node);
  if (blended()) return blend_spoke_[node];
  return branches_[static_cast<std::size_t>(b)]->spoke_length(node -
                                                              node_begin_[static_cast<std::size_t>(b)]);
}

}  // namespace medspring
