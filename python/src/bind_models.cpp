// Models layer: the Body interface and its three kinds (SurfaceBody, HybridKidney, SmrmVessel), with the
// medial pieces they are built from (chain settings, frames, vessel phantoms).
#include "bind_common.hpp"
#include "bind_params.hpp"
#include "medspring/medial/chain.hpp"
#include "medspring/medial/frames.hpp"
#include "medspring/medial/reconstruction.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/models/body.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/models/smrm_tree.hpp"
#ifdef MEDSPRING_PYTHON_WITH_BUILDERS
#include "medspring/builders/vessel_build.hpp"
#endif
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/models/tissue.hpp"

namespace medspring::python {

using namespace pybind11::literals;

namespace {

void check_state(const Body& body, const State& s) {
  const Index n = body.model().num_nodes();
  require(s.x.rows() == n && s.v.rows() == n, "state: has ", s.x.rows(), " nodes, the ", body.kind(),
          " model has ", n);
}

void bind_medial(py::module_& m) {
  py::enum_<FrameMode> frame_mode(m, "FrameMode",
                                  "How the first spoke u_i of every atom is chosen (§5.4-5.5).");
  frame_mode.value("RMF", FrameMode::RMF, "default (D-12): rotation-minimising frames")
      .value("PaperXOY", FrameMode::PaperXOY, "eq. (3) literally: u_i = normalize(e_z x t_i)");
  enum_accepts_strings(frame_mode, &parse_frame_mode);
  py::enum_<FrameAnchor> frame_anchor(m, "FrameAnchor", "How the roll of the RMF frames is fixed (§5.5).");
  frame_anchor.value("OneEnd", FrameAnchor::OneEnd)
      .value("TwoEnd", FrameAnchor::TwoEnd, "vessel default")
      .value("BestFit", FrameAnchor::BestFit);
  enum_accepts_strings(frame_anchor, &parse_frame_anchor);
  py::class_<FrameSettings> frame_settings(m, "FrameSettings", "Frame mode and anchor.");
  def_enum_field(frame_settings, "mode", &FrameSettings::mode, "FrameMode (RMF).");
  def_enum_field(frame_settings, "anchor", &FrameSettings::anchor, "FrameAnchor (TwoEnd).");
  settings_helpers(frame_settings);
  py::class_<FrameReport>(m, "FrameReport", "What a frame computation met (reported, never raised).")
      .def_readonly("degenerate", &FrameReport::degenerate, "PaperXOY: atoms with t parallel to e_z.")
      .def_readonly("first_degenerate", &FrameReport::first_degenerate, "First degenerate atom, -1 if none.")
      .def_readonly("degenerate_chords", &FrameReport::degenerate_chords,
                    "Tangents taken from a fallback (chord < 1e-9 mm).")
      .def_readonly("transport_fallbacks", &FrameReport::transport_fallbacks,
                    "RMF: transported spoke parallel to the tangent (MinRot used).")
      .def_readonly("gamma", &FrameReport::gamma, "TwoEnd: roll mismatch spread along the chain, rad.")
      .def_property_readonly("ok", &FrameReport::ok, "No degenerate atom.");
  py::class_<CurvatureCheck>(m, "CurvatureCheck", "Validity of the cross-sections: rho_i kappa_i < 1 (§5.6).")
      .def_readonly("violations", &CurvatureCheck::violations, "Atoms with rho_i kappa_i >= 1.")
      .def_readonly("first_atom", &CurvatureCheck::first_atom, "First violating atom, -1 if none.")
      .def_readonly("max_rho_kappa", &CurvatureCheck::max_rho_kappa, "Largest rho_i kappa_i.")
      .def_property_readonly("ok", &CurvatureCheck::ok, "No violation.");

  py::class_<ChainSettings> chain(m, "ChainSettings",
                                  "The SMRM centerline chain (§5.2); vessel defaults of §9.");
  chain.def_readwrite("k", &ChainSettings::k, "Chain spring stiffness k_cl, N/mm (0.2).")
      .def_readwrite("kr", &ChainSettings::kr, "Return-spring stiffness per atom, N/mm (0.02).")
      .def_readwrite("mass", &ChainSettings::mass, "Per atom, g (0.5).")
      .def_readwrite("beta", &ChainSettings::beta, "Damping d = beta m, 1/ms (0.5).")
      .def_readwrite("nonlinear", &ChainSettings::nonlinear, "Duffing chain springs (True).")
      .def_readwrite("duffing", &ChainSettings::duffing, "k' rule when nonlinear (Strain).")
      .def_readwrite("fix_first", &ChainSettings::fix_first, "Atom 0 fixed (True).")
      .def_readwrite("fix_last", &ChainSettings::fix_last, "Atom n-1 fixed (True).")
      .def_readwrite("kb", &ChainSettings::kb, "Optional bending springs, N/mm (0 = off).");
  settings_helpers(chain);
  m.def(
      "make_chain_model",
      [](py::handle C0, const ChainSettings& settings, const std::string& name) {
        return make_chain_model(points_arg(C0, "C0"), settings, name);
      },
      "C0"_a, "settings"_a = ChainSettings{}, "name"_a = "centerline",
      "The chain Model of rest atoms C0 (n, 3), mm: springs (i, i+1), return springs, masses, fixed ends.");

  py::enum_<VesselPath> path(m, "VesselPath", "The test centerlines of §8.0.");
  path.value("StraightX", VesselPath::StraightX)
      .value("StraightZ", VesselPath::StraightZ)
      .value("Arc", VesselPath::Arc)
      .value("Helix", VesselPath::Helix);
  enum_accepts_strings(path, &parse_vessel_path);
  py::enum_<CrossSectionShape> shape(m, "CrossSectionShape", "The cross-sections of §8.0.");
  shape.value("Circular", CrossSectionShape::Circular)
      .value("Elliptical", CrossSectionShape::Elliptical)
      .value("NonPlanar", CrossSectionShape::NonPlanar);
  enum_accepts_strings(shape, &parse_cross_section);
  m.def(
      "vessel_phantom_atoms",
      [](py::handle p, Index n, double spacing) {
        return copy_of(vessel_phantom_atoms(enum_arg<VesselPath>(p, "path"), n, spacing));
      },
      "path"_a, "n"_a = 40, "spacing"_a = 2.5, "Atoms (n, 3) of a phantom centerline, mm.");
  m.def(
      "vessel_phantom_centerline",
      [](py::handle p, Index n, double radius, double spacing) {
        return vessel_phantom_centerline(enum_arg<VesselPath>(p, "path"), n, radius, spacing);
      },
      "path"_a, "n"_a = 40, "radius"_a = 3.0, "spacing"_a = 2.5,
      "The phantom centerline with a constant radius (mm).");
  m.def(
      "cross_section_offsets",
      [](py::handle s, Index spokes, double scale) {
        return copy_of(cross_section_offsets(enum_arg<CrossSectionShape>(s, "shape"), spokes, scale));
      },
      "shape"_a, "spokes"_a = 30, "scale"_a = 1.0, "Local offsets (M, 3) of one cross-section, mm.");
}

}  // namespace

void bind_models(py::module_& m) {
  bind_medial(m);

  py::class_<GridLayout> grid(m, "GridLayout", "Structured tube-grid layout (rings x spokes) of a surface.");
  grid.def_readwrite("rings", &GridLayout::rings, "Rings n (0 = no grid).")
      .def_readwrite("spokes", &GridLayout::spokes, "Spokes per ring M (0 = no grid).");
  grid.def_property_readonly("valid", &GridLayout::valid, "rings > 0 and spokes > 0.");
  settings_helpers(grid);

  py::class_<Body, std::shared_ptr<Body>>(
      m, "Body",
      "A simulated organ: physics degrees of freedom (model) + a map to the surface the user sees. The "
      "three kinds are SurfaceBody ('surface'), HybridKidney ('hybrid') and SmrmVessel ('smrm').")
      .def_property_readonly("kind", &Body::kind, "'surface', 'hybrid' or 'smrm'.")
      .def_property_readonly("model", &Body::model, py::return_value_policy::reference_internal,
                             "The physics Model integrated by the engine.")
      .def_property_readonly(
          "faces", [](py::object self) { return view_of(self.cast<const Body&>().faces(), self); },
          "Surface triangles (F, 3), read-only view.")
      .def_property_readonly(
          "rest_surface",
          [](py::object self) { return view_of(self.cast<const Body&>().rest_surface(), self); },
          "Rest positions of the surface nodes (S, 3), mm, read-only view.")
      .def_property_readonly("num_surface_nodes", &Body::num_surface_nodes, "Number of surface nodes S.")
      .def(
          "map_to_surface",
          [](const Body& b, const State& s) {
            check_state(b, s);
            MatX3 S;
            b.map_to_surface(s, S);
            return copy_of(S);
          },
          "state"_a, "Surface positions (S, 3), mm, for a physics state (forward map).")
      .def(
          "transfer_force",
          [](const Body& b, Index node, py::handle F, py::handle f_dof) {
            require_index(node, b.num_surface_nodes(), "node");
            const Index n = b.model().num_nodes();
            MatX3 f = f_dof.is_none() ? MatX3(MatX3::Zero(n, 3)) : points_arg(f_dof, "f_dof", n);
            b.transfer_force(node, vec3_arg(F, "F"), f);
            return copy_of(f);
          },
          "node"_a, "F"_a, "f_dof"_a = py::none(),
          "f_dof (zeros if None) plus the DOF forces (N, 3) equivalent to force F (N) on surface node "
          "`node`.")
      .def_property_readonly("grid", &Body::grid, "GridLayout of the surface (invalid if unstructured).")
      .def_property_readonly("local_stiffness", &Body::local_stiffness, "k_loc of the local patch, N/mm.")
      .def_property_readonly(
          "fixed_surface_nodes",
          [](const Body& b) {
            std::vector<std::uint8_t> f = b.fixed_surface_nodes();
            if (f.empty()) f.assign(static_cast<std::size_t>(b.num_surface_nodes()), 0);
            return bool_array(f);
          },
          "(S,) bool: surface nodes fixed by the model.")
      .def(
          "spoke_length",
          [](const Body& b, Index node) {
            require_index(node, b.num_surface_nodes(), "node");
            return b.spoke_length(node);
          },
          "node"_a, "Rest spoke length of a surface node (mm), 0 where the model has no atoms.")
      .def("__repr__", [](const Body& b) {
        return cat("<medspring.", b.kind(), " body: ", b.model().num_nodes(), " DOF nodes, ",
                   b.num_surface_nodes(), " surface nodes>");
      });

  // ---- SurfaceBody ----
  py::class_<SurfaceBody, Body, std::shared_ptr<SurfaceBody>>(
      m, "SurfaceBody", "The plain surface mass-spring body (§1): every surface node is a DOF.")
      .def(py::init<const SurfaceMesh&, const SurfaceBodyParams&, std::string, GridLayout>(), "mesh"_a,
           "params"_a = SurfaceBodyParams{}, "name"_a = "surface", "grid"_a = GridLayout{},
           "A surface body from a triangle mesh (mm): one spring per unique edge; `grid` for a structured "
           "tube "
           "(local 5 x 5 window).")
      .def_property_readonly(
          "dof_of_surface", [](const SurfaceBody& b) { return copy_of(b.dof_of_surface()); },
          "DOF (model node) of every surface node: a large mesh with scattered numbering is simulated in "
          "reverse Cuthill-McKee order (empty array: DOF = surface node). Loads, fixed nodes, surface, "
          "normals keep the mesh's numbering; positions/velocities are in DOF order.");

  // ---- HybridKidney ----
  py::class_<HybridSettings> hs(m, "HybridSettings",
                                "Parameters of the hybrid kidney (§4, kidney column of §9).");
  hs.def_readwrite("surface_node", &HybridSettings::surface_node, "NodeParams of surface nodes.")
      .def_readwrite("atom_node", &HybridSettings::atom_node, "NodeParams of centerline atoms.")
      .def_readwrite("nonlinear", &HybridSettings::nonlinear,
                     "Every inter-node spring Duffing (D-4) (True).");
  def_params(hs);  // mass, k_spoke, spokes_per_atom, ...: declared in models/hybrid_kidney.hpp
  settings_helpers(hs);
  py::class_<HybridStats>(m, "HybridStats", "Statistics of a hybrid model.")
      .def_readonly("surface_nodes", &HybridStats::surface_nodes, "Surface nodes.")
      .def_readonly("atoms", &HybridStats::atoms, "Centerline atoms.")
      .def_readonly("surface_springs", &HybridStats::surface_springs, "Surface springs (unique edges).")
      .def_readonly("centerline_springs", &HybridStats::centerline_springs,
                    "Springs between consecutive atoms.")
      .def_readonly("spokes", &HybridStats::spokes, "Spokes (surface node - atom springs).")
      .def_readonly("min_spokes_per_atom", &HybridStats::min_spokes_per_atom, "Fewest spokes of an atom.")
      .def_readonly("max_spokes_per_atom", &HybridStats::max_spokes_per_atom, "Most spokes of an atom.")
      .def_readonly("surface_nodes_without_spoke", &HybridStats::surface_nodes_without_spoke,
                    "Surface nodes with no spoke (0 by the union rule).");
  py::class_<HybridKidney, Body, std::shared_ptr<HybridKidney>>(
      m, "HybridKidney",
      "The hybrid kidney (§4): a surface mass-spring body and a centerline skeleton of atoms tied by spokes, "
      "integrated as one system. DOFs: the surface nodes, then the atoms.")
      .def(py::init([](const SurfaceMesh& surface, py::handle atoms, const HybridSettings& settings,
                       std::string name) {
             return std::make_shared<HybridKidney>(surface, points_arg(atoms, "atoms"), settings,
                                                   std::move(name));
           }),
           "surface"_a, "atoms"_a, "settings"_a = HybridSettings{}, "name"_a = "kidney",
           "surface: closed organ surface (mm); atoms: (A, 3) centerline atoms (mm) in order along the "
           "skeleton.")
      .def_property_readonly("num_atoms", &HybridKidney::num_atoms, "Number of centerline atoms A.")
      .def(
          "atom_dof",
          [](const HybridKidney& k, Index a) {
            require_index(a, k.num_atoms(), "atom");
            return k.atom_dof(a);
          },
          "a"_a, "DOF index of atom a (atoms follow the surface nodes).")
      .def_property_readonly(
          "spokes", [](py::object self) { return view_of(self.cast<const HybridKidney&>().spokes(), self); },
          "(K, 2) rows (surface node, atom), read-only view.")
      .def_property_readonly("settings", &HybridKidney::settings, "HybridSettings (a copy).")
      .def_property_readonly("stats", &HybridKidney::stats, "HybridStats.");
  m.def(
      "union_spokes",
      [](py::handle surface, py::handle atoms, Index k) {
        return copy_of(union_spokes(points_arg(surface, "surface"), points_arg(atoms, "atoms"), k));
      },
      "surface"_a, "atoms"_a, "spokes_per_atom"_a = 8, "Spokes (K, 2) by the union rule of D-9.");
  m.def(
      "kidney_phantom_atoms", [](Index count) { return copy_of(kidney_phantom_atoms(count)); },
      "count"_a = 42, "The atoms (count, 3) of the kidney phantom (§4.1), mm.");
  m.def(
      "hybrid_kidney_phantom",
      [](const HybridSettings& s) { return std::make_shared<HybridKidney>(hybrid_kidney_phantom(s)); },
      "settings"_a = HybridSettings{}, "The hybrid kidney phantom: 458 surface nodes + 42 atoms (§4.1).");

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
            check_state(v, s);
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

  // ---- Model packages ----
  m.def(
      "save_model_package",
      [](const std::string& path, const Body& body, const std::string& name, const std::string& description) {
        save_model_package(path, package_of(body, name, description));
      },
      "path"_a, "body"_a, "name"_a = "", "description"_a = "",
      "Writes the body as a model package (.msm, docs/model_packages.md), atomically: what the engine needs "
      "to rebuild "
      "it exactly (the browser page loads these).");
  m.def(
      "load_model_package",
      [](const std::string& path) {
        return std::const_pointer_cast<Body>(make_body(read_model_package(path)));
      },
      "path"_a,
      "Rebuilds the body saved in a model package. Raises IoError (truncated, corrupted, other version) or "
      "InvalidInput (invalid contents), naming the file.");
  // ---- Tissue materials (models/tissue.hpp, docs/accuracy.md) ----
  m.def(
      "tissue_settings",
      [](py::handle material, const std::string& kind, bool nonlinear,
         const std::string& organ) -> py::object {
        TissueMaterial t;
        if (py::isinstance<py::str>(material)) {
          t = tissue_preset(material.cast<std::string>());
        } else if (py::isinstance<py::dict>(material)) {
          const auto d = material.cast<py::dict>();
          for (const auto& item : d) {
            const auto key = item.first.cast<std::string>();
            if (key != "preset" && key != "E_kPa" && key != "nu")
              throw InvalidInput("material." + key + ": unknown key (expected one of: preset, E_kPa, nu)");
          }
          if (d.contains("preset")) t = tissue_preset(d["preset"].cast<std::string>());
          if (!d.contains("preset") && !d.contains("E_kPa"))
            throw InvalidInput("material.E_kPa: is required (Young's modulus, kPa) unless a preset is named");
          if (d.contains("E_kPa")) t.E_kPa = d["E_kPa"].cast<double>();
          if (d.contains("nu")) t.nu = d["nu"].cast<double>();
        } else {
          throw InvalidInput("material: must be a preset name (kidney, aorta) or a dict {E_kPa, nu}");
        }
        check_tissue(t, "material");
        require(organ == "phantom" || organ == "kidney", "organ: must be phantom or kidney (got ", organ,
                ")");
        const TissueOrgan o = organ == "phantom" ? TissueOrgan::Phantom : TissueOrgan::RealKidney;
        if (kind == "hybrid") {
          HybridSettings s;
          s.nonlinear = nonlinear;
          apply_tissue(t, o, s);
          return py::cast(s);
        }
        if (kind == "surface") {
          SurfaceBodyParams p;
          if (!nonlinear) p.duffing.mode = DuffingMode::Linear;
          apply_tissue(t, o, p);
          return py::cast(p);
        }
        if (kind == "smrm") {
          SmrmSettings s;
          s.chain.nonlinear = nonlinear;
          apply_tissue(t, s);
          return py::cast(s);
        }
        throw InvalidInput("kind: must be hybrid, surface or smrm (got " + kind + ")");
      },
      "material"_a, "kind"_a = "hybrid", "nonlinear"_a = true, "organ"_a = "phantom",
      "Settings of a model kind for a tissue: material is a preset ('kidney', 'aorta') or a dict {'E_kPa', "
      "'nu'} "
      "(or {'preset'}); hybrid and surface get the stiffnesses calibrated against the CalculiX reference "
      "(organ: "
      "'phantom' or 'kidney', the calibration's body), scaled by the shear modulus; smrm gets the wall's E. "
      "Raises InvalidInput for E <= 0, nu outside (-1, 0.5) or an unknown preset, naming the key.");
}

}  // namespace medspring::python
