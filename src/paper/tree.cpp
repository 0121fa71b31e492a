// The whole vessel tree of the study (issue 17, docs/vessels.md): the tree of the VMR 0159 centerline (or
// the phantom tree), a light and a strong force on the arch and on the longest side branch.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "internal.hpp"
#include "medspring/core/check.hpp"

namespace medspring::paper::detail {

namespace {

/// The surface node on ring `local` (spoke 0) of a tree branch.
Index tree_node(const SmrmTree& t, Index branch, Index local) {
  return t.node_begin(branch) + local * t.settings().vessel.spokes;
}

std::string sig(double x) {
  std::ostringstream os;
  os << std::setprecision(3) << x;
  return os.str();
}

}  // namespace

json run_tree(const StudyOptions& o, StudyHost& host, const std::string& primary, const fs::path& root,
              std::vector<SceneRun>& tree_runs) {
  fs::path file;
  std::string unit = "mm";
  if (primary == "real") {
    file = (o.data_dir.empty() ? scene_data_dir() : o.data_dir) / "vmr-0159-aorta-centerline.vtp";
    unit = "cm";
  } else {
    file = root / "data" / "phantom_tree.vtp";
    host.write_centerlines(file, phantom_tree_lines());
  }
  const Index every = o.quick ? 100 : 20;
  host.begin(cat("vessel tree (", primary, ")"));
  // The sites: "arch" = the middle atom of the longest root-to-leaf path (the aorta itself; on VMR 0159
  // its arch), "branch" = the middle atom of the longest leaf branch off that path.
  const BuiltScene probe =
      build_scene(parse_scene(tree_scene_json("probe", file, unit, 0, 0, 0.05, every), root, "tree scene"),
                  host.loader());
  const auto& tree = dynamic_cast<const SmrmTree&>(*probe.body);
  // The runs use the tree's watertight surface (the union of its path tubes, one closed surface with a
  // blended junction) where the loader has CGAL; else the tubes (the sites below are on the tubes' rings:
  // on the watertight surface the nearest node of the same branch)
  bool blend = true;
  BodyPtr blended_body;
  try {
    blended_body = build_scene(parse_scene(tree_scene_json("probe", file, unit, 0, 0, 0.05, every, true),
                                           root, "tree scene"),
                               host.loader())
                       .body;
  } catch (const InvalidInput&) {
    blend = false;
  }
  const SmrmTree* run_tree = blend ? dynamic_cast<const SmrmTree*>(blended_body.get()) : &tree;
  auto run_node = [&](Index tube_node) {
    if (!blend) return tube_node;
    const Vec3 p = tree.rest_surface().row(tube_node).transpose();
    const Index b = tree.node_branch(tube_node);
    Index best = -1;
    double bd = 0.0;
    for (Index k = 0; k < run_tree->num_surface_nodes(); ++k) {
      if (run_tree->node_branch(k) != b) continue;
      const double d = (run_tree->rest_surface().row(k).transpose() - p).squaredNorm();
      if (best < 0 || d < bd) {
        best = k;
        bd = d;
      }
    }
    return best;
  };
  const Index nb = tree.num_branches();
  std::vector<double> path_len(static_cast<std::size_t>(nb), 0.0);
  std::vector<char> has_child(static_cast<std::size_t>(nb), 0);
  for (Index b = 0; b < nb; ++b) {
    const Index p = tree.parent(b);
    const double len = static_cast<double>(tree.branch_atoms(b).size() - 1);
    path_len[static_cast<std::size_t>(b)] = len + (p >= 0 ? path_len[static_cast<std::size_t>(p)] : 0.0);
    if (p >= 0) has_child[static_cast<std::size_t>(p)] = 1;
  }
  Index leaf = 0;
  for (Index b = 0; b < nb; ++b)
    if (!has_child[static_cast<std::size_t>(b)] &&
        path_len[static_cast<std::size_t>(b)] > path_len[static_cast<std::size_t>(leaf)])
      leaf = b;
  std::vector<Index> path;  // branches root .. leaf
  for (Index b = leaf; b >= 0; b = tree.parent(b)) path.insert(path.begin(), b);
  // the middle atom of the longest path: walk half its atom steps
  Index arch_branch = path.front(), arch_local = 1;
  {
    double half = 0.5 * path_len[static_cast<std::size_t>(leaf)];
    for (Index b : path) {
      const double len = static_cast<double>(tree.branch_atoms(b).size() - 1);
      if (half <= len || b == path.back()) {
        arch_branch = b;
        arch_local = std::clamp<Index>(static_cast<Index>(std::lround(half)), 1,
                                       static_cast<Index>(tree.branch_atoms(b).size()) - 2);
        break;
      }
      half -= len;
    }
  }
  Index side = -1;
  for (Index b = 0; b < nb; ++b)
    if (!has_child[static_cast<std::size_t>(b)] && std::find(path.begin(), path.end(), b) == path.end() &&
        (side < 0 || tree.branch_atoms(b).size() > tree.branch_atoms(side).size()))
      side = b;
  if (side < 0) side = leaf;
  const Index side_local = static_cast<Index>(tree.branch_atoms(side).size()) / 2;
  SmrmTree::Workspace ws = tree.make_workspace();
  const CurvatureCheck rest_check = tree.validity(tree.model().x0, ws);
  json out = {
      {"set", primary},
      {"branches", nb},
      {"junctions", tree.num_junctions()},
      {"atoms", tree.num_atoms()},
      {"surface_nodes", run_tree->num_surface_nodes()},
      {"surface", blend ? "watertight (blended junctions)" : "one tube per branch"},
      {"rest_max_rho_kappa", rest_check.max_rho_kappa},
      {"rest_rho_kappa_violations", rest_check.violations},
      {"arch",
       {{"branch", arch_branch},
        {"atom", tree.branch_atoms(arch_branch)[static_cast<std::size_t>(arch_local)]}}},
      {"branch", {{"branch", side}, {"atom", tree.branch_atoms(side)[static_cast<std::size_t>(side_local)]}}},
      {"runs", json::array()}};
  struct Site {
    std::string key, label;
    Index node;
  };
  const std::vector<Site> sites = {
      {"arch", "arch", run_node(tree_node(tree, arch_branch, arch_local))},
      {"branch", cat("branch ", side), run_node(tree_node(tree, side, side_local))}};
  for (const Site& site : sites)
    for (const double f : {0.05, 0.5}) {
      SceneRun r;
      const std::string strength = f < 0.1 ? "light" : "strong";
      r.e = {cat("tree_", strength, "_", site.key),
             "tree",
             f,
             true,
             false,
             false,
             cat(strength, " ", sig(f), " N on the ", site.label)};
      r.set = primary;
      r.scene = parse_scene(
          tree_scene_json(r.e.file, file, unit, site.node, run_tree->node_atom(site.node), f, every, blend),
          root, "tree scene");
      const BuiltScene built = build_scene(r.scene, host.loader());
      r.rel = cat("scenes/", r.set, "/", r.e.file);
      r.dir = root / r.rel;
      r.summary = json::parse(host.run_to_folder(built, r.dir, false));
      record_geometry(r, built);
      const Index a = run_tree->node_atom(site.node);
      const Index b = run_tree->node_branch(site.node);
      const auto& ids = tree.branch_atoms(b);
      const auto it = std::find(ids.begin(), ids.end(), a);
      const std::size_t k = static_cast<std::size_t>(it - ids.begin());
      const MatX3& X0 = tree.model().x0;
      r.tangent = (X0.row(ids[std::min(k + 1, ids.size() - 1)]) - X0.row(ids[k > 0 ? k - 1 : 0]))
                      .transpose()
                      .normalized();
      r.radius = (r.contact - X0.row(a).transpose()).norm();
      json s = r.summary;
      s.erase("frames");
      s.erase("atoms_rest");
      s["folder"] = r.rel;
      s["site"] = site.key;
      s["label"] = r.e.label;
      s["loaded_atom"] = a;
      out["runs"].push_back(s);
      tree_runs.push_back(std::move(r));
    }
  host.end(cat(nb, " branches, ", tree_runs.size(), " runs"));
  return out;
}

}  // namespace medspring::paper::detail
