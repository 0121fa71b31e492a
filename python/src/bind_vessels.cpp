// Models layer, vessels: SmrmVessel (§5), vessel trees (issue 17) and the vessel experiment of §7.2.
// Called from bind_models (bind_models.cpp), after the medial pieces they are built from.
#include <optional>

#include "bind_common.hpp"
#include "bind_models.hpp"
#include "bind_params.hpp"
#include "medspring/medial/chain.hpp"
#include "medspring/medial/frames.hpp"
#include "medspring/medial/reconstruction.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/models/body.hpp"
#include "medspring/models/smrm_tree.hpp"
#ifdef MEDSPRING_PYTHON_WITH_BUILDERS
#include "medspring/builders/vessel_build.hpp"
#endif
#include "medspring/models/smrm_vessel.hpp"

namespace medspring::python {

using namespace pybind11::literals;

void bind_vessels(py::module_& m) {
  // ---- SmrmVessel ----
  py::enum_<BendingMode> bending_mode(m, "BendingMode", "Bending of the SMRM centerline (docs/vessels.md).");
  bending_mode.value("Wall", BendingMode::Wall, "default: k_b,i = E I_i / h_i^3 of the wall (hollow tube)")
      .value("Constant", BendingMode::Constant, "chain.kb at every interior atom (0 = the paper's chain)");
  enum_accepts_strings(bending_mode, &parse_bending_mode);
  py::class_<WallSettings> wall(m, "WallSettings",
                                "The vessel wall that gives the default bending stiffness.");
  wall.def_readwrite("E", &WallSettings::E, "Young's modulus of the wall, MPa (0.5).")
      .def_readwrite("thickness_ratio", &WallSettings::thickness_ratio,
                     "Wall thickness / lumen radius (0.1).");
  settings_helpers(wall);
  m.def(
      "wall_bending_stiffness",
      [](py::handle atoms, py::handle radius, const WallSettings& w) {
        const MatX3 C = points_arg(atoms, "atoms");
        return copy_of(
            wall_bending_stiffness(C, vector_arg(radius, "radius", static_cast<Index>(C.rows())), w));
      },
      "atoms"_a, "radius"_a, "wall"_a = WallSettings{},
      "Bending stiffness k_b,i = E pi/4 (r_o^4 - r_i^4) / h_i^3 (N/mm) of every atom of a rest chain.");
  py::class_<SmrmSettings> ss(m, "SmrmSettings", "Settings of the SMRM vessel (vessel column of §9).");
  ss.def_readwrite("atoms", &SmrmSettings::atoms, "Centerline atoms after resampling (40).")
      .def_readwrite("spokes", &SmrmSettings::spokes, "Spokes per atom of the structured builders (30).")
      .def_readwrite("frames", &SmrmSettings::frames, "FrameSettings (RMF, TwoEnd).")
      .def_readwrite("chain", &SmrmSettings::chain, "ChainSettings.")
      .def_readwrite("k_loc", &SmrmSettings::k_loc, "Local patch stiffness, N/mm (0.05).")
      .def_readwrite("dedup_tolerance", &SmrmSettings::dedup_tolerance, "mm (1e-3).")
      .def_readwrite("max_radius_factor", &SmrmSettings::max_radius_factor, "In local radii (3).")
      .def_readwrite("wall", &SmrmSettings::wall, "WallSettings of the default bending.");
  def_enum_field(ss, "bending", &SmrmSettings::bending, "BendingMode (Wall; Constant uses chain.kb).");
  def_params(ss);  // spokes, mass, k_cl, k_b, wall_E, frame_mode, ...: declared in models/smrm_vessel.hpp
  settings_helpers(ss);
  py::class_<SmrmBuildReport>(m, "SmrmBuildReport", "What the SMRM builders found (reported, not raised).")
      .def_readonly("atoms", &SmrmBuildReport::atoms, "Atoms n.")
      .def_readonly("surface_nodes", &SmrmBuildReport::surface_nodes, "Surface nodes S.")
      .def_readonly("removed_duplicates", &SmrmBuildReport::removed_duplicates,
                    "Centerline points removed by deduplication.")
      .def_readonly("rest_frames", &SmrmBuildReport::rest_frames,
                    "FrameReport of the rest frames (PaperXOY degeneracy).")
      .def_readonly("curvature", &SmrmBuildReport::curvature, "CurvatureCheck (§5.6 rho kappa < 1).")
      .def_readonly("spokes_without_hit", &SmrmBuildReport::spokes_without_hit,
                    "Spoke marching: spokes with no boundary hit (rho = r_i).")
      .def_readonly("first_spoke_without_hit", &SmrmBuildReport::first_spoke_without_hit,
                    "Its surface node, -1 if none.")
      .def_readonly("max_distance_ratio", &SmrmBuildReport::max_distance_ratio,
                    "Generic binding: max node distance / local radius.")
      .def_readonly("notes", &SmrmBuildReport::notes, "One line per reported condition.");
  py::class_<SmrmVessel, Body, std::shared_ptr<SmrmVessel>>(
      m, "SmrmVessel",
      "The simplified medial representation vessel (§5): the physics integrates a chain of centerline atoms; "
      "the surface is rebuilt from the deformed centerline (S = C + F o). Build with smrm_from_centerline, "
      "smrm_from_offsets, smrm_from_surface, smrm_from_marched_spokes or smrm_phantom.")
      .def_property_readonly("name", &SmrmVessel::name, "The vessel's name.")
      .def_property_readonly("settings", &SmrmVessel::settings, "SmrmSettings (a copy).")
      .def_property_readonly("report", &SmrmVessel::report, "SmrmBuildReport (a copy).")
      .def_property_readonly("num_atoms", &SmrmVessel::num_atoms, "Number of centerline atoms n.")
      .def_property_readonly(
          "rest_atoms",
          [](py::object self) { return view_of(self.cast<const SmrmVessel&>().rest_atoms(), self); },
          "Rest atoms (n, 3), mm, read-only view.")
      .def_property_readonly(
          "atom_radius",
          [](py::object self) { return view_of(self.cast<const SmrmVessel&>().atom_radius(), self); },
          "(n,) local lumen radius, mm, read-only view.")
      .def_property_readonly(
          "bending_stiffness",
          [](py::object self) { return view_of(self.cast<const SmrmVessel&>().bending_stiffness(), self); },
          "(n,) bending stiffness k_b,i, N/mm (0 at the ends), read-only view.")
      .def(
          "max_turning_change_deg",
          [](const SmrmVessel& v, py::handle atoms) {
            Index a = -1;
            const double d = v.max_turning_change_deg(points_arg(atoms, "atoms", v.num_atoms(), "n"), &a);
            return py::make_tuple(d, a);
          },
          "atoms"_a, "(degrees, atom): largest |alpha_i - alpha_i^0| of the turning angle of atoms (n, 3).")
      .def(
          "validity",
          [](const SmrmVessel& v, py::handle atoms) {
            return v.validity(points_arg(atoms, "atoms", v.num_atoms(), "n"));
          },
          "atoms"_a, "CurvatureCheck (§5.6 rho kappa < 1) of atoms (n, 3).")
      .def(
          "surface_from_atoms",
          [](const SmrmVessel& v, py::handle atoms) {
            auto ws = v.make_workspace();
            MatX3 S;
            v.map_to_surface(points_arg(atoms, "atoms", v.num_atoms(), "n"), ws, S);
            return copy_of(S);
          },
          "atoms"_a,
          "The reconstructed surface (S, 3) of deformed atoms (n, 3): frames + S = C + F o (§5.5, §5.7).")
      .def(
          "surface_normals",
          [](const SmrmVessel& v, py::handle surface) {
            auto ws = v.make_workspace();
            MatX3 N;
            v.surface_normals(points_arg(surface, "surface", v.num_surface_nodes(), "S"), ws, N);
            return copy_of(N);
          },
          "surface"_a, "Area-weighted unit vertex normals (S, 3) of a reconstructed surface.")
      .def("make_chain", &SmrmVessel::make_chain, "nonlinear"_a,
           "The chain Model of this vessel with Duffing springs on (nonlinear) or off.")
      .def(
          "reaction_force",
          [](const SmrmVessel& v, const State& s, Index node) {
            check_body_state(v, s);
            require_index(node, v.num_surface_nodes(), "node");
            return copy_of(Vec3(v.reaction_force(s, node)));
          },
          "state"_a, "node"_a,
          "Elastic force (N) of the chain at the atom(s) receiving a force on surface node `node`: -F at "
          "static equilibrium under a force F on the node.")
      .def(
          "node_atom",
          [](const SmrmVessel& v, Index node) {
            require_index(node, v.num_surface_nodes(), "node");
            return v.node_atom(node);
          },
          "node"_a, "The atom a surface node belongs to.")
      .def(
          "contact_node",
          [](const SmrmVessel& v, Index atom, py::handle F) {
            return v.contact_node(atom, vec3_arg(F, "F"));
          },
          "atom"_a, "F"_a, "The node of ring `atom` whose rest outward normal is most opposed to F (§7.2).");

  m.def(
      "smrm_from_offsets",
      [](py::handle atoms, py::handle offsets, const SmrmSettings& s, const std::string& name) {
        return std::make_shared<SmrmVessel>(
            smrm_from_offsets(points_arg(atoms, "atoms"), points_arg(offsets, "offsets"), s, name));
      },
      "atoms"_a, "offsets"_a, "settings"_a = SmrmSettings{}, "name"_a = "vessel",
      "Structured vessel from rest atoms (n, 3) and cross-section offsets (o_u, o_v, o_t) in the rest "
      "frames: "
      "(n * M, 3) or (M, 3) shared by every atom, mm.");
  m.def(
      "smrm_from_centerline",
      [](const Centerline& line, const SmrmSettings& s) {
        return std::make_shared<SmrmVessel>(smrm_from_centerline(line, s));
      },
      "line"_a, "settings"_a = SmrmSettings{},
      "Structured circular vessel from a centerline in mm (eq. 4, D-11): deduplicated, resampled to "
      "settings.atoms atoms, settings.spokes spokes of the local radius.");
  m.def(
      "smrm_from_surface",
      [](const SurfaceMesh& surface, const Centerline& line, const SmrmSettings& s) {
        return std::make_shared<SmrmVessel>(smrm_from_surface(surface, line, s));
      },
      "surface"_a, "line"_a, "settings"_a = SmrmSettings{},
      "Generic vessel (§5.9) from a closed surface mesh and its centerline (mm).");
  m.def(
      "smrm_from_marched_spokes",
      [](const Centerline& line, const SurfaceMesh& boundary, const SmrmSettings& s) {
        return std::make_shared<SmrmVessel>(smrm_from_marched_spokes(line, boundary, s));
      },
      "line"_a, "boundary"_a, "settings"_a = SmrmSettings{},
      "Structured vessel whose spoke lengths are marched to a boundary mesh (§5.6).");
  m.def(
      "smrm_phantom",
      [](py::handle p, py::handle sh, const SmrmSettings& s) {
        return std::make_shared<SmrmVessel>(
            smrm_phantom(enum_arg<VesselPath>(p, "path"), enum_arg<CrossSectionShape>(sh, "shape"), s));
      },
      "path"_a = VesselPath::StraightX, "shape"_a = CrossSectionShape::Circular,
      "settings"_a = SmrmSettings{},
      "A procedural vessel phantom of §8.0 (settings.atoms atoms at 2.5 mm, settings.spokes spokes).");
  // ---- Vessel trees (issue 17) ----
  py::class_<SmrmTree, Body, std::shared_ptr<SmrmTree>>(
      m, "SmrmTree",
      "A branching SMRM vessel: one chain over all atoms with shared junction atoms, one tube per branch. "
      "Build with smrm_tree_from_centerlines or smrm_tree_from_parents.")
      .def_property_readonly("num_branches", &SmrmTree::num_branches, "Branches.")
      .def_property_readonly("num_junctions", &SmrmTree::num_junctions, "Branch ends with children.")
      .def_property_readonly("num_atoms", &SmrmTree::num_atoms, "Atoms of the tree (junction atoms once).")
      .def("parent", &SmrmTree::parent, "branch"_a, "The parent branch (-1 for the root).")
      .def("branch_atoms", &SmrmTree::branch_atoms, "branch"_a,
           "The tree atoms of a branch in order (a child's first is its parent's last).")
      .def("node_branch", &SmrmTree::node_branch, "node"_a, "The branch of a surface node.")
      .def("node_atom", &SmrmTree::node_atom, "node"_a, "The tree atom a surface node rides on.")
      .def_property_readonly("blended", &SmrmTree::blended,
                             "True for a tree with one watertight surface (blend=True), False for one tube "
                             "per branch.");
  // blend: the watertight junction surface (union of the closed path tubes; needs the builders layer).
  const auto tree_of = [](const CenterlineTree& ct, const SmrmSettings& s, bool blend,
                          double blend_spacing) -> std::shared_ptr<SmrmTree> {
    if (!blend) return std::make_shared<SmrmTree>(ct, SmrmTreeSettings{s});
#ifdef MEDSPRING_PYTHON_WITH_BUILDERS
    return make_blended_tree(ct, SmrmTreeSettings{s}, blend_spacing);
#else
    (void)blend_spacing;
    throw InvalidInput(
        "blend=True: the watertight tree surface needs CGAL (the builders layer) in this build");
#endif
  };
  m.def(
      "smrm_tree_from_centerlines",
      [tree_of](const std::vector<Centerline>& lines, double tolerance, const SmrmSettings& s, bool blend,
                double blend_spacing) {
        return tree_of(merge_centerlines(lines, tolerance), s, blend, blend_spacing);
      },
      "lines"_a, "tolerance"_a = 0.05, "settings"_a = SmrmSettings{}, "blend"_a = false,
      "blend_spacing"_a = 0.0,
      "A vessel tree from centerlines sharing their start (VMTK): merged where they agree within "
      "`tolerance` mm; settings.atoms = atoms on the longest root-to-leaf path. blend=True gives one "
      "watertight surface (the union of the closed path tubes, rings blend_spacing mm apart, 0 = the atom "
      "spacing) instead of one tube per branch.");
  m.def(
      "smrm_tree_from_parents",
      [tree_of](py::handle atoms, py::handle parent, py::handle radii, const SmrmSettings& s, bool blend,
                double blend_spacing) {
        const MatX3 X = points_arg(atoms, "atoms");
        const Index n = static_cast<Index>(X.rows());
        const py::array_t<long long, py::array::c_style | py::array::forcecast> p(
            py::reinterpret_borrow<py::object>(parent));
        require(p.ndim() == 1 && p.shape(0) == n, "parent: must have shape (", n, ",), got ", p.size(),
                " values");
        std::vector<Index> par(static_cast<std::size_t>(n));
        for (Index i = 0; i < n; ++i) {
          const long long v = p.at(i);
          require(v >= -1 && v < n, "parent[", i, "]: ", v, " is not -1 or an atom index");
          par[static_cast<std::size_t>(i)] = static_cast<Index>(v);
        }
        return tree_of(tree_from_parents(X, par, vector_arg(radii, "radii", n)), s, blend, blend_spacing);
      },
      "atoms"_a, "parent"_a, "radii"_a, "settings"_a = SmrmSettings{}, "blend"_a = false,
      "blend_spacing"_a = 0.0,
      "A vessel tree from NumPy: atoms (n, 3) mm, parent index of every atom (n,) (-1 for the root atom 0, "
      "else an earlier atom), radii (n,) mm. Runs of atoms form branches; an atom with several children is a "
      "junction. settings.atoms = atoms on the longest root-to-leaf path (the resampling spacing). "
      "blend=True: "
      "one watertight surface, as smrm_tree_from_centerlines.");
#ifdef MEDSPRING_PYTHON_WITH_BUILDERS
  m.def(
      "smrm_tree_from_organ",
      [](std::optional<std::filesystem::path> mesh, std::optional<std::filesystem::path> segmentation,
         std::optional<std::int32_t> label, std::optional<LengthUnit> unit, const SmrmSettings& s, bool blend,
         double blend_spacing) {
        require(mesh.has_value() != segmentation.has_value(),
                "smrm_tree_from_organ: give exactly one of mesh and segmentation");
        require(!label || segmentation, "smrm_tree_from_organ: label applies to a segmentation");
        VesselBuildSettings st;
        if (mesh) {
          st.source.mesh = *mesh;
          st.source.unit = unit.value_or(LengthUnit::Millimetre);
        } else {
          st.source.mask = *segmentation;
          st.source.label = label;
        }
        st.all_branches = true;
        st.no_blend = !blend;
        st.blend_spacing = blend_spacing;
        st.smrm = s;
        VesselBuild v = [&] {
          py::gil_scoped_release release;
          return build_vessel(st);
        }();
        const VesselSummary& r = v.summary;
        py::dict d;
        d["input"] = r.input;
        d["input_kind"] = r.input_kind;
        d["atoms"] = r.atoms;
        d["branches"] = r.branches;
        d["junctions"] = r.junctions;
        d["surface_nodes"] = r.surface_nodes;
        d["length_mm"] = r.length_mm;
        d["radius_min_mm"] = r.radius_min_mm;
        d["radius_max_mm"] = r.radius_max_mm;
        d["rest_error_mm"] = r.rest_error_mm;
        d["hausdorff_mm"] = r.hausdorff_mm;
        d["mean_distance_mm"] = r.mean_distance_mm;
        d["to_input_max_mm"] = r.to_input_max_mm;
        d["to_input_mean_mm"] = r.to_input_mean_mm;
        d["away_hausdorff_mm"] = r.away.hausdorff_mm;  // away from the cut ends (docs/vessels.md)
        d["away_mean_mm"] = r.away.mean_mm;
        d["away_nodes_over_2mm"] = r.away.nodes_over_2mm;
        d["blended"] = r.blended;
        d["surface_closed"] = r.surface_closed;
        d["build_seconds"] = r.seconds;
        d["notes"] = r.notes;
        d["warnings"] = r.warnings;
        return py::make_tuple(std::const_pointer_cast<SmrmTree>(v.tree), d, v.input);
      },
      py::kw_only(), "mesh"_a = py::none(), "segmentation"_a = py::none(), "label"_a = py::none(),
      "unit"_a = py::none(), "settings"_a = SmrmSettings{}, "blend"_a = true, "blend_spacing"_a = 0.0,
      "A vessel tree from a closed surface mesh (unit: of its coordinates, None = mm) or a segmentation "
      "(label: the "
      "vessel's, default the only non-zero one), as `medspring build vessel --branches all` "
      "(docs/vessels.md): the tree skeleton of every endpoint (ends extended to the input's caps), and by "
      "default the watertight surface fitted to the input's wall (blend=False: one open tube per branch, "
      "the skeleton's circles). Returns (tree, summary, input_surface): summary is a dict (atoms, branches, "
      "junctions, rest_error_mm, hausdorff_mm, mean_distance_mm, to_input_max_mm, to_input_mean_mm, "
      "blended, notes, ...); input_surface the mesh the distances are measured to. Raises InvalidInput "
      "(several components, an absent label, a blob) or IoError naming the file.");
#endif
  m.def(
      "first_ray_hit",
      [](const SurfaceMesh& mesh, py::handle o, py::handle w, double t_max) {
        return first_ray_hit(mesh, vec3_arg(o, "o"), vec3_arg(w, "w"), t_max);
      },
      "mesh"_a, "o"_a, "w"_a, "t_max"_a = std::numeric_limits<double>::infinity(),
      "Distance along the ray o + t w (w unit) to the closest hit in (0, t_max], or inf.");

  py::class_<VesselExperimentSettings> ves(m, "VesselExperimentSettings",
                                           "The paper's vessel experiment (§7.2, Fig. 10).");
  ves.def_readwrite("atom", &VesselExperimentSettings::atom, "Loaded atom (20).")
      .def_property(
          "direction", [](const VesselExperimentSettings& s) { return copy_of(s.direction); },
          [](VesselExperimentSettings& s, py::handle d) { s.direction = vec3_arg(d, "direction"); },
          "Force direction (zero = u_atom^0).")
      .def_readwrite("light", &VesselExperimentSettings::light, "N (0.05).")
      .def_readwrite("strong", &VesselExperimentSettings::strong, "N (0.5).")
      .def_readwrite("t_ramp", &VesselExperimentSettings::t_ramp, "ms (20).")
      .def_readwrite("t_release", &VesselExperimentSettings::t_release, "ms (500).")
      .def_readwrite("t_end", &VesselExperimentSettings::t_end, "ms (1000).")
      .def_readwrite("dt", &VesselExperimentSettings::dt, "ms (0.5).")
      .def_readwrite("rest_tolerance", &VesselExperimentSettings::rest_tolerance, "mm (1e-3).");
  settings_helpers(ves);
  py::class_<VesselRun>(m, "VesselRun", "One force level with the linear or nonlinear chain (arrays: views).")
      .def_readonly("force", &VesselRun::force, "N.")
      .def_readonly("nonlinear", &VesselRun::nonlinear, "Duffing chain springs.")
      .def_property_readonly(
          "time", [](py::object self) { return view_of(self.cast<const VesselRun&>().time, self); },
          "(T,) ms.")
      .def_property_readonly(
          "atom_displacement",
          [](py::object self) { return view_of(self.cast<const VesselRun&>().atom_displacement, self); },
          "(T,) mm.")
      .def_property_readonly(
          "contact_displacement",
          [](py::object self) { return view_of(self.cast<const VesselRun&>().contact_displacement, self); },
          "(T,) mm.")
      .def_property_readonly(
          "max_surface_displacement",
          [](py::object self) {
            return view_of(self.cast<const VesselRun&>().max_surface_displacement, self);
          },
          "(T,) mm.")
      .def_property_readonly(
          "profile", [](py::object self) { return view_of(self.cast<const VesselRun&>().profile, self); },
          "(n, 3) atom displacements at release, mm.")
      .def_property_readonly(
          "surface", [](py::object self) { return view_of(self.cast<const VesselRun&>().surface, self); },
          "(S, 3) surface at release, mm.")
      .def_readonly("atom_hold", &VesselRun::atom_hold, "mm.")
      .def_readonly("contact_hold", &VesselRun::contact_hold, "mm.")
      .def_readonly("return_time", &VesselRun::return_time, "ms after release (inf: never).")
      .def_readonly("warnings", &VesselRun::warnings, "Integrator warnings (State.warnings.total()).")
      .def_readonly("max_rho_kappa", &VesselRun::max_rho_kappa, "§5.6 validity, max over updates and atoms.")
      .def_readonly("rho_kappa_violations", &VesselRun::rho_kappa_violations,
                    "(update, atom) pairs with rho kappa >= 1.")
      .def_readonly("max_turning_change_deg", &VesselRun::max_turning_change_deg,
                    "Max over updates and atoms of |alpha_i - alpha_i^0|, degrees.")
      .def_readonly("max_turning_atom", &VesselRun::max_turning_atom, "Where it was largest.");
  py::class_<VesselExperimentResult>(m, "VesselExperimentResult", "The four runs of the vessel experiment.")
      .def_readonly("atom", &VesselExperimentResult::atom, "Loaded atom.")
      .def_readonly("contact_node", &VesselExperimentResult::contact_node,
                    "Node of ring `atom` most opposed to F (the local-deformation hook).")
      .def_property_readonly(
          "direction", [](const VesselExperimentResult& r) { return copy_of(r.direction); },
          "Unit force direction.")
      .def_readonly("light_linear", &VesselExperimentResult::light_linear,
                    "VesselRun: light force, linear chain.")
      .def_readonly("light_nonlinear", &VesselExperimentResult::light_nonlinear,
                    "VesselRun: light force, nonlinear chain.")
      .def_readonly("strong_linear", &VesselExperimentResult::strong_linear,
                    "VesselRun: strong force, linear chain.")
      .def_readonly("strong_nonlinear", &VesselExperimentResult::strong_nonlinear,
                    "VesselRun: strong force, nonlinear chain.");
  m.def(
      "run_vessel_experiment",
      [](const SmrmVessel& v, const VesselExperimentSettings& s) {
        py::gil_scoped_release release;
        return run_vessel_experiment(v, s);
      },
      "vessel"_a, "settings"_a = VesselExperimentSettings{},
      "Runs the four cases of §7.2 (light / strong force, linear / nonlinear chain); GIL released.");
}

}  // namespace medspring::python
