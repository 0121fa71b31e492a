// Local layer: eq. (6) patches, the precomputed patch solve, the per-update deformer and the overlay.
#include "bind_common.hpp"
#include "medspring/local/deformer.hpp"
#include "medspring/local/overlay.hpp"
#include "medspring/local/patch.hpp"
#include "medspring/local/solver.hpp"

namespace medspring::python {

using namespace pybind11::literals;

namespace {

std::vector<std::uint8_t> optional_flags(py::handle obj, const char* name, Index n = -1) {
  return obj.is_none() ? std::vector<std::uint8_t>{} : flags_arg(obj, name, n);
}

MatX3 patch_displacement(const LocalPatch& patch, py::handle U) {
  return points_arg(U, "U", patch.size(), "P");
}

}  // namespace

void bind_local(py::module_& m) {
  py::class_<GridNode> grid_node(m, "GridNode",
                                 "A node of the structured tube grid: ring i, spoke j (i * M + j).");
  grid_node.def_readwrite("ring", &GridNode::ring, "Ring i.")
      .def_readwrite("spoke", &GridNode::spoke, "Spoke j (cyclic).");
  settings_helpers(grid_node);

  py::class_<PatchOptions> patch_options(m, "PatchOptions", "Options of the patch selectors (§6.1, §9).");
  patch_options.def_readwrite("k_loc", &PatchOptions::k_loc, "Stiffness of every patch spring, N/mm (0.05).")
      .def_readwrite("half_width", &PatchOptions::half_width, "Structured window half-width (2: 5 x 5).")
      .def_readwrite("count", &PatchOptions::count, "BFS patch: number of nodes (25).");
  settings_helpers(patch_options);

  py::class_<LocalPatch>(
      m, "LocalPatch",
      "The nodes, springs and boundary of one local patch (§6.1); arrays are read-only views.")
      .def_property_readonly(
          "nodes", [](py::object self) { return view_of(self.cast<const LocalPatch&>().nodes, self); },
          "(P,) global node indices in selection order.")
      .def_property_readonly(
          "fixed", [](const LocalPatch& p) { return bool_array(p.fixed); },
          "(P,) bool: fixed patch nodes (D-15).")
      .def_property_readonly(
          "free_nodes",
          [](py::object self) { return view_of(self.cast<const LocalPatch&>().free_nodes, self); },
          "Local indices of the free nodes, ascending.")
      .def_property_readonly(
          "springs", [](py::object self) { return view_of(self.cast<const LocalPatch&>().springs, self); },
          "(S, 2) local end indices.")
      .def_property_readonly(
          "k", [](py::object self) { return view_of(self.cast<const LocalPatch&>().k, self); },
          "(S,) patch spring stiffness, N/mm.")
      .def_readonly("contact", &LocalPatch::contact, "Global index of the contact node.")
      .def_readonly("contact_local", &LocalPatch::contact_local, "Local index of the contact node.")
      .def_property_readonly("size", &LocalPatch::size, "Number of patch nodes P.")
      .def_property_readonly("num_free", &LocalPatch::num_free, "Number of free patch nodes.")
      .def_property_readonly("num_springs", &LocalPatch::num_springs, "Number of patch springs.")
      .def_property_readonly("trivial", &LocalPatch::trivial,
                             "U = 0 for every force (contact fixed or no free node).")
      .def("__len__", &LocalPatch::size)
      .def("__repr__", [](const LocalPatch& p) {
        return cat("<medspring.LocalPatch ", p.size(), " nodes (", p.num_free(), " free), contact ",
                   p.contact, ">");
      });

  m.def(
      "make_local_patch",
      [](const Adjacency& adj, py::handle nodes, Index contact, double k_loc, py::handle fixed) {
        return make_local_patch(adj, index_list_arg(nodes, "nodes", adj.num_nodes()), contact, k_loc,
                                optional_flags(fixed, "fixed", adj.num_nodes()));
      },
      "adj"_a, "nodes"_a, "contact"_a, "k_loc"_a, "fixed"_a = py::none(),
      "A patch from an explicit node list: the mesh edges inside it as springs of stiffness k_loc; a node is "
      "fixed when it has a neighbour outside the patch or is model-fixed (D-15).");
  m.def(
      "structured_window_patch",
      [](Index rings, Index spokes, Index contact, const PatchOptions& options, py::handle fixed) {
        return structured_window_patch(rings, spokes, contact, options, optional_flags(fixed, "fixed"));
      },
      "rings"_a, "spokes"_a, "contact"_a, "options"_a = PatchOptions{}, "fixed"_a = py::none(),
      "The (2 h + 1) x (2 h + 1) tube-grid window of §6.1 around global node `contact` = i * spokes + j.");
  m.def(
      "structured_window_patch",
      [](Index rings, Index spokes, const GridNode& contact, const PatchOptions& options, py::handle fixed) {
        return structured_window_patch(rings, spokes, contact, options, optional_flags(fixed, "fixed"));
      },
      "rings"_a, "spokes"_a, "contact"_a, "options"_a = PatchOptions{}, "fixed"_a = py::none(),
      "The tube-grid window of §6.1 around GridNode `contact`.");
  m.def(
      "bfs_local_patch",
      [](const Adjacency& adj, py::handle X0, Index contact, const PatchOptions& options, py::handle fixed) {
        return bfs_local_patch(adj, points_arg(X0, "X0", adj.num_nodes()), contact, options,
                               optional_flags(fixed, "fixed", adj.num_nodes()));
      },
      "adj"_a, "X0"_a, "contact"_a, "options"_a = PatchOptions{}, "fixed"_a = py::none(),
      "The general-mesh patch of §6.1 (kidney): the first options.count nodes in BFS order from the contact "
      "(which is local node 0).");

  py::enum_<LocalStiffness> stiffness(m, "LocalStiffness",
                                      "How a patch spring contributes to K (§6.2, D-16).");
  stiffness.value("Isotropic", LocalStiffness::Isotropic, "default: K = L (x) I3")
      .value("Linearized", LocalStiffness::Linearized, "exact linearised spring block + k_r I")
      .value("AxisProjected", LocalStiffness::AxisProjected, "diagonal of the linearised block + k_r I")
      .value("PaperLiteral", LocalStiffness::PaperLiteral,
             "the paper's printed assignments; comparison only");
  enum_accepts_strings(stiffness);
  py::enum_<BoundaryMethod> boundary(m, "BoundaryMethod", "How fixed patch nodes are imposed (§6.3).");
  boundary.value("Elimination", BoundaryMethod::Elimination, "default: solve K_ff U_f = F_f")
      .value("RowReplacement", BoundaryMethod::RowReplacement, "the paper's reading, solved by LU");
  enum_accepts_strings(boundary);

  py::class_<LocalSettings> local_settings(m, "LocalSettings", "Settings of the patch solve (§6, §9).");
  def_enum_field(local_settings, "stiffness", &LocalSettings::stiffness, "LocalStiffness (Isotropic).");
  def_enum_field(local_settings, "boundary", &LocalSettings::boundary, "BoundaryMethod (Elimination).");
  local_settings
      .def_readwrite("return_stiffness", &LocalSettings::return_stiffness,
                     "k_r added per patch node in Linearized / AxisProjected, N/mm (0.02).")
      .def_readwrite("sparse_threshold", &LocalSettings::sparse_threshold,
                     "Isotropic: sparse Cholesky above this many free nodes (64).")
      .def_readwrite("pivot_tolerance", &LocalSettings::pivot_tolerance, "Singularity threshold (1e-12).");
  settings_helpers(local_settings);

  py::class_<LocalSolveInfo>(m, "LocalSolveInfo", "What one patch solve did.")
      .def_readonly("zero", &LocalSolveInfo::zero, "U = 0: contact fixed or no free node.")
      .def_property_readonly(
          "note", [](const LocalSolveInfo& i) { return std::string(i.note); },
          "Non-empty only for PaperLiteral.");

  m.def(
      "local_stiffness_matrix",
      [](const LocalPatch& patch, py::handle X, const LocalSettings& settings) {
        return local_stiffness_matrix(patch, X.is_none() ? MatX3() : points_arg(X, "X"), settings);
      },
      "patch"_a, "X"_a = py::none(), "settings"_a = LocalSettings{},
      "The full 3P x 3P patch stiffness K before boundary conditions (§6.2), dense. X: (N, 3) positions, "
      "needed by Linearized / AxisProjected only.");

  py::class_<LocalSolver>(m, "LocalSolver",
                          "Precomputed solver of K U = F for one patch (precompute + solve).")
      .def(py::init<>())
      .def(
          "precompute",
          [](LocalSolver& s, const LocalPatch& patch, py::handle X, const LocalSettings& settings) {
            s.precompute(patch, X.is_none() ? MatX3() : points_arg(X, "X"), settings);
          },
          "patch"_a, "X"_a = py::none(), "settings"_a = LocalSettings{},
          "Assembles K (§6.2), imposes the fixed nodes (§6.3) and factors (§6.4). Raises SolverError for a "
          "singular patch stiffness.")
      .def(
          "solve",
          [](LocalSolver& s, py::handle F) {
            MatX3 U;
            s.solve(vec3_arg(F, "F"), U);
            return copy_of(U);
          },
          "F"_a, "Displacement U (P, 3) of the patch nodes, mm, for the force F (N) on the contact node.")
      .def_property_readonly("ready", &LocalSolver::ready, "True after precompute.")
      .def_property_readonly("patch_size", &LocalSolver::patch_size,
                             "Number of patch nodes P of the last precompute.")
      .def_property_readonly(
          "green", [](const LocalSolver& s) { return copy_of(s.green()); },
          "Isotropic mode: g (P,), U_a = g_a F.");

  py::class_<LocalDeformationSettings> lds(m, "LocalDeformationSettings",
                                           "Settings of the per-update local deformation (§6, §9).");
  lds.def_readwrite("patch", &LocalDeformationSettings::patch, "PatchOptions.")
      .def_readwrite("solver", &LocalDeformationSettings::solver, "LocalSettings.")
      .def_readwrite("cache_local", &LocalDeformationSettings::cache_local,
                     "Keep the factor while the contact node stays the same (True).");
  settings_helpers(lds);

  py::class_<LocalDeformer>(
      m, "LocalDeformer",
      "Selects the patch around a contact node and solves eq. (6), caching the factor per "
      "contact node.")
      .def_static(
          "tube",
          [](Index rings, Index spokes, const LocalDeformationSettings& settings, py::handle X,
             py::handle fixed) {
            return LocalDeformer::tube(rings, spokes, settings, X.is_none() ? MatX3() : points_arg(X, "X"),
                                       optional_flags(fixed, "fixed"));
          },
          "rings"_a, "spokes"_a, "settings"_a = LocalDeformationSettings{}, "X"_a = py::none(),
          "fixed"_a = py::none(), "Structured tube grid (vessel, 5 x 5 window).")
      .def_static(
          "mesh",
          [](const Adjacency& adj, py::handle X0, const LocalDeformationSettings& settings,
             py::handle fixed) {
            return LocalDeformer::mesh(adj, points_arg(X0, "X0", adj.num_nodes()), settings,
                                       optional_flags(fixed, "fixed", adj.num_nodes()));
          },
          "adj"_a, "X0"_a, "settings"_a = LocalDeformationSettings{}, "fixed"_a = py::none(),
          "General mesh (kidney, BFS patch). X0: (N, 3) rest positions, mm.")
      .def(
          "compute",
          [](LocalDeformer& d, Index contact, py::handle F) {
            MatX3 U;
            d.compute(contact, vec3_arg(F, "F"), U);
            return copy_of(U);
          },
          "contact"_a, "F"_a, "Displacement U (P, 3), mm, of the patch around `contact` for force F (N).")
      .def_property_readonly("patch", &LocalDeformer::patch, py::return_value_policy::reference_internal,
                             "The patch of the last compute.")
      .def("invalidate", &LocalDeformer::invalidate, "Drops the cached factor.");

  m.def(
      "apply_local_overlay",
      [](const LocalPatch& patch, py::handle U, py::handle surface) {
        MatX3 S = points_arg(surface, "surface");
        apply_local_overlay(patch, patch_displacement(patch, U), S);
        return copy_of(S);
      },
      "patch"_a, "U"_a, "surface"_a,
      "surface + U on the patch nodes (§6.5, D-17), as a new (N, 3) array (the input is not modified).");

  py::class_<LocalGuard> guard(m, "LocalGuard", "The dent guard of §6.5.");
  guard.def_readwrite("enabled", &LocalGuard::enabled, "Apply the guard (True).")
      .def_readwrite("fraction", &LocalGuard::fraction, "Limit |U_c| <= fraction x rho_c (0.9).");
  settings_helpers(guard);
  m.def(
      "limit_local_displacement",
      [](const LocalPatch& patch, py::handle U, double rho_c, const LocalGuard& g) {
        MatX3 V = patch_displacement(patch, U);
        const double f = limit_local_displacement(patch, V, rho_c, g);
        return py::make_tuple(copy_of(V), f);
      },
      "patch"_a, "U"_a, "rho_c"_a, "guard"_a = LocalGuard{},
      "Scales U so that |U_c| <= fraction * rho_c (§6.5); returns (U_limited, factor).");

  py::class_<LocalSmoother>(
      m, "LocalSmoother", "First-order smoothing of the local displacement with time constant tau_U (§6.5).")
      .def(py::init<double>(), "tau_U"_a = 0.0)
      .def(
          "apply",
          [](LocalSmoother& s, const LocalPatch& patch, py::handle U, double dt, py::handle surface) {
            MatX3 S = points_arg(surface, "surface");
            s.apply(patch, patch_displacement(patch, U), dt, S);
            return copy_of(S);
          },
          "patch"_a, "U"_a, "dt"_a, "surface"_a,
          "Advances the smoothed field by dt (ms) towards U and returns surface + field (new array).")
      .def(
          "apply_released",
          [](LocalSmoother& s, double dt, py::handle surface) {
            MatX3 S = points_arg(surface, "surface");
            s.apply_released(dt, S);
            return copy_of(S);
          },
          "dt"_a, "surface"_a, "The same with no load (release).")
      .def_property_readonly(
          "displacement", [](const LocalSmoother& s) { return copy_of(s.displacement()); },
          "Smoothed field (N, 3).")
      .def("reset", &LocalSmoother::reset, "Sets the smoothed field to zero.")
      .def_property_readonly("time_constant", &LocalSmoother::time_constant, "tau_U, ms.");
}

}  // namespace medspring::python
