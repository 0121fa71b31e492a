// Models layer: the Body interface, SurfaceBody and HybridKidney, model packages and tissue presets, with
// the medial pieces the vessels are built from (chain settings, frames, vessel phantoms). The SMRM vessel
// and vessel trees are in bind_vessels.cpp.
#include "bind_models.hpp"

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
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/models/tissue.hpp"

namespace medspring::python {

using namespace pybind11::literals;

void check_body_state(const Body& body, const State& s) {
  const Index n = body.model().num_nodes();
  require(s.x.rows() == n && s.v.rows() == n, "state: has ", s.x.rows(), " nodes, the ", body.kind(),
          " model has ", n);
}

namespace {

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
            check_body_state(b, s);
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
      .def_property_readonly(
          "dof_of_surface", [](const HybridKidney& k) { return copy_of(k.dof_of_surface()); },
          "DOF (model node) of every surface node: a large surface with scattered numbering is simulated in "
          "reverse Cuthill-McKee order (empty array: DOF = surface node; atoms always follow the surface "
          "nodes). Loads, fixed nodes, spokes, surface, normals keep the mesh's numbering.")
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

  bind_vessels(m);  // SmrmVessel, vessel trees, the vessel experiment: bind_vessels.cpp

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
