// Physics layer: spring laws, Model / ModelBuilder, State, loads, integrators, forces, static solve,
// stability. step() releases the GIL.
#include <pybind11/eigen.h>

#include <cmath>

#include "bind_common.hpp"
#include "bind_params.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/linear_response.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/physics/model.hpp"
#include "medspring/physics/spring_law.hpp"
#include "medspring/physics/stability.hpp"
#include "medspring/physics/state.hpp"
#include "medspring/physics/static_solve.hpp"

namespace medspring::python {

using namespace pybind11::literals;

namespace {

void check_state(const Model& model, const State& s) {
  const Index n = model.num_nodes();
  require(s.x.rows() == n && s.v.rows() == n && s.f_ext.rows() == n && s.f.rows() == n, "state: has ",
          s.x.rows(), " nodes, model '", model.name, "' has ", n, " (make it with make_state(model))");
}

// A copy of `model` with some per-spring / per-node arrays replaced, finalized (validated).
Model with_parameters(const Model& model, py::handle k, py::handle kp, py::handle kr, py::handle mass,
                      py::handle damping, py::handle fixed) {
  Model out = model;
  const Index ns = model.num_springs(), n = model.num_nodes();
  auto per_spring = [&](py::handle obj, const char* name, std::vector<double>& dst) {
    if (obj.is_none()) return;
    if (PyFloat_Check(obj.ptr()) || PyLong_Check(obj.ptr())) {
      std::fill(dst.begin(), dst.end(), obj.cast<double>());
      return;
    }
    const VecX v = vector_arg(obj, name, ns, "S");
    std::copy(v.data(), v.data() + ns, dst.begin());
  };
  auto per_node = [&](py::handle obj, const char* name, VecX& dst) {
    if (obj.is_none()) return;
    if (PyFloat_Check(obj.ptr()) || PyLong_Check(obj.ptr())) {
      dst.setConstant(obj.cast<double>());
      return;
    }
    dst = vector_arg(obj, name, n);
  };
  per_spring(k, "k", out.springs.k);
  per_spring(kp, "kp", out.springs.kp);
  per_node(kr, "kr", out.kr);
  per_node(mass, "mass", out.mass);
  per_node(damping, "damping", out.damping);
  if (!fixed.is_none()) out.fixed = flags_arg(fixed, "fixed", n);
  out.finalized = false;
  finalize(out);
  return out;
}

}  // namespace

void bind_physics(py::module_& m) {
  // ---- Spring laws (eq. 5, D-3) ----
  py::enum_<DuffingMode> duffing_mode(
      m, "DuffingMode",
      "How the cubic coefficient k' of eq. (5) is chosen (D-3). Strings such as "
      "'strain' are accepted wherever a DuffingMode is expected.");
  duffing_mode.value("Linear", DuffingMode::Linear, "k' = 0")
      .value("Strain", DuffingMode::Strain, "default: k' = eta k / L0^2")
      .value("Absolute", DuffingMode::Absolute, "the paper's literal k' = k / length^2 (length = 10 mm)")
      .value("ScaledStrain", DuffingMode::ScaledStrain, "k' = k / (100 L0^2), for completeness");
  enum_accepts_strings(duffing_mode, &parse_duffing_mode);

  py::class_<DuffingSettings> duffing_cls(m, "DuffingSettings",
                                          "Choice of the Duffing coefficient k' (D-3).");
  def_params(duffing_cls);  // declared in physics/spring_law.hpp
  settings_helpers(duffing_cls);

  m.def("duffing_coefficient", &duffing_coefficient, "k"_a, "L0"_a, "settings"_a = DuffingSettings{},
        "k' (N/mm^3) for a spring of stiffness k (N/mm) and rest length L0 (mm).");
  m.def("spring_tension", py::vectorize(&spring_tension), "k"_a, "kp"_a, "delta"_a,
        "Scalar tension phi(delta) = k delta + k' delta^3 (eq. 5), N, with the soft-spring clamp (§1.7). "
        "Vectorised over NumPy arrays.");
  m.def("spring_tension_derivative", py::vectorize(&spring_tension_derivative), "k"_a, "kp"_a, "delta"_a,
        "d phi / d delta = k + 3 k' delta^2 (0 beyond a soft spring's peak), N/mm. Vectorised.");
  m.def("spring_energy", py::vectorize(&spring_energy), "k"_a, "kp"_a, "delta"_a,
        "Potential energy k delta^2 / 2 + k' delta^4 / 4, mJ. Vectorised.");
  m.def("soft_limit", &soft_limit, "k"_a, "kp"_a,
        "Peak elongation sqrt(k / (3 |k'|)) of a soft spring (mm); inf for hard or linear springs.");

  // ---- Model ----
  py::class_<NodeParams> node_params(m, "NodeParams", "Per-node parameters used by builders.");
  node_params.def_readwrite("mass", &NodeParams::mass, "g (default 0.3).")
      .def_readwrite("beta", &NodeParams::beta, "mass-proportional damping d = beta m, 1/ms (default 0.5).")
      .def_readwrite("return_k", &NodeParams::return_k, "return-spring stiffness, N/mm (default 0.02).");
  settings_helpers(node_params);

  py::class_<Springs>(m, "Springs",
                      "The springs of a Model as a struct of arrays (read-only views): spring s joins nodes "
                      "i[s] and j[s], rest length L0 (mm), stiffness k (N/mm), cubic stiffness kp (N/mm^3).")
      .def_property_readonly(
          "i", [](py::object self) { return view_of(self.cast<const Springs&>().i, self); }, "(S,) int32.")
      .def_property_readonly(
          "j", [](py::object self) { return view_of(self.cast<const Springs&>().j, self); }, "(S,) int32.")
      .def_property_readonly(
          "L0", [](py::object self) { return view_of(self.cast<const Springs&>().L0, self); }, "(S,) mm.")
      .def_property_readonly(
          "k", [](py::object self) { return view_of(self.cast<const Springs&>().k, self); }, "(S,) N/mm.")
      .def_property_readonly(
          "kp", [](py::object self) { return view_of(self.cast<const Springs&>().kp, self); }, "(S,) N/mm^3.")
      .def("__len__", &Springs::size);

  py::class_<BendingTerms>(
      m, "BendingTerms",
      "Optional discrete bending springs of a chain (§5.2), read-only views: triples "
      "(a, b, c) with middle node b, stiffness kb (N/mm), rest second differences D0 (mm).")
      .def_property_readonly(
          "a", [](py::object self) { return view_of(self.cast<const BendingTerms&>().a, self); },
          "(B,) int32.")
      .def_property_readonly(
          "b", [](py::object self) { return view_of(self.cast<const BendingTerms&>().b, self); },
          "(B,) int32.")
      .def_property_readonly(
          "c", [](py::object self) { return view_of(self.cast<const BendingTerms&>().c, self); },
          "(B,) int32.")
      .def_property_readonly(
          "kb", [](py::object self) { return view_of(self.cast<const BendingTerms&>().kb, self); },
          "(B,) N/mm.")
      .def_property_readonly(
          "D0", [](py::object self) { return view_of(self.cast<const BendingTerms&>().D0, self); },
          "(B, 3) mm.")
      .def("__len__", &BendingTerms::size);

  py::class_<Model>(m, "Model",
                    "The immutable physics model: nodes, springs, return springs, pins (§1). Arrays are "
                    "read-only NumPy views. Build with ModelBuilder, make_surface_model or make_chain_model; "
                    "vary parameters with with_parameters().")
      .def_readonly("name", &Model::name, "Name used in error messages.")
      .def_property_readonly(
          "x0", [](py::object self) { return view_of(self.cast<const Model&>().x0, self); },
          "Rest positions (N, 3), mm.")
      .def_property_readonly(
          "mass", [](py::object self) { return view_of(self.cast<const Model&>().mass, self); }, "(N,) g.")
      .def_property_readonly(
          "damping", [](py::object self) { return view_of(self.cast<const Model&>().damping, self); },
          "(N,) absolute damping d_i, g/ms.")
      .def_property_readonly(
          "kr", [](py::object self) { return view_of(self.cast<const Model&>().kr, self); },
          "(N,) return-spring stiffness, N/mm.")
      .def_property_readonly(
          "fixed", [](const Model& mo) { return bool_array(mo.fixed); },
          "(N,) bool, True = pinned at x0 (copy).")
      .def_property_readonly(
          "free_nodes", [](py::object self) { return view_of(self.cast<const Model&>().free_nodes, self); },
          "Indices of the free nodes (int32).")
      .def_property_readonly(
          "springs", [](const Model& mo) -> const Springs& { return mo.springs; },
          py::return_value_policy::reference_internal, "The springs (Springs).")
      .def_property_readonly(
          "bending", [](const Model& mo) -> const BendingTerms& { return mo.bending; },
          py::return_value_policy::reference_internal, "The bending terms (BendingTerms).")
      .def_property_readonly("num_nodes", &Model::num_nodes, "Number of nodes N.")
      .def_property_readonly("num_springs", &Model::num_springs, "Number of springs S.")
      .def_readonly("omega_rest", &Model::omega_rest,
                    "Power-iteration estimate of omega_max at rest x 1.05, rad/ms.")
      .def_readonly("omega_gershgorin", &Model::omega_gershgorin, "Gershgorin bound at rest, rad/ms.")
      .def_readonly("has_soft_springs", &Model::has_soft_springs, "Some spring has k' < 0.")
      .def("dt_safe_rest", &Model::dt_safe_rest, "safety"_a = 0.8,
           "safety * 2 / omega_rest: the stable explicit step at rest, ms.")
      .def(
          "with_parameters", &with_parameters, "k"_a = py::none(), "kp"_a = py::none(), "kr"_a = py::none(),
          "mass"_a = py::none(), "damping"_a = py::none(), "fixed"_a = py::none(),
          "A validated copy of the model with some parameters replaced: k, kp per spring ((S,) arrays or one "
          "number for all), kr, mass, damping per node ((N,) or one number), fixed ((N,) bool). Used to fit "
          "parameters: the topology and rest lengths stay.")
      .def(
          "copy", [](const Model& mo) { return Model(mo); }, "A deep copy.")
      .def("__repr__", [](const Model& mo) {
        return cat("<medspring.Model '", mo.name, "' ", mo.num_nodes(), " nodes, ", mo.num_springs(),
                   " springs>");
      });

  py::class_<ModelBuilder>(m, "ModelBuilder", "Incremental construction of a Model.")
      .def(py::init<std::string>(), "name"_a = "model")
      .def(
          "add_node",
          [](ModelBuilder& b, py::handle p, double mass, double damping, double return_k, bool fixed) {
            require_positive(mass, "add_node: mass");
            require_nonnegative(damping, "add_node: damping");
            require_nonnegative(return_k, "add_node: return_k");
            return b.add_node(vec3_arg(p, "p"), mass, damping, return_k, fixed);
          },
          "p"_a, "mass"_a = 0.3, "damping"_a = 0.15, "return_k"_a = 0.02, "fixed"_a = false,
          "Adds a node at rest position p (mm) with mass (g), absolute damping (g/ms) and return-spring "
          "stiffness (N/mm); returns its index.")
      .def(
          "add_node_params",
          [](ModelBuilder& b, py::handle p, const NodeParams& params) {
            return b.add_node(vec3_arg(p, "p"), params);
          },
          "p"_a, "params"_a, "Adds a node with NodeParams (damping = beta * mass); returns its index.")
      .def(
          "add_spring",
          [](ModelBuilder& b, Index a, Index c, double k, double kp, double rest_length) {
            require_index(a, b.num_nodes(), "add_spring: a");
            require_index(c, b.num_nodes(), "add_spring: b");
            if (std::isnan(rest_length)) rest_length = (b.position(a) - b.position(c)).norm();
            return b.add_spring(a, c, k, kp, rest_length);
          },
          "a"_a, "b"_a, "k"_a, "kp"_a = 0.0, "rest_length"_a = std::numeric_limits<double>::quiet_NaN(),
          "Adds a spring between nodes a and b with stiffness k (N/mm), cubic stiffness kp (N/mm^3) and rest "
          "length (mm; default: the rest distance); returns its index.")
      .def(
          "add_duffing_spring",
          [](ModelBuilder& b, Index a, Index c, double k, const DuffingSettings& duffing) {
            require_index(a, b.num_nodes(), "add_duffing_spring: a");
            require_index(c, b.num_nodes(), "add_duffing_spring: b");
            return b.add_spring(a, c, k, duffing);
          },
          "a"_a, "b"_a, "k"_a, "duffing"_a = DuffingSettings{},
          "Adds a spring with rest length = rest distance and k' from the Duffing settings; returns its "
          "index.")
      .def(
          "set_fixed",
          [](ModelBuilder& b, Index node, bool fixed) {
            require_index(node, b.num_nodes(), "set_fixed: node");
            b.set_fixed(node, fixed);
          },
          "node"_a, "fixed"_a = true, "Pins (or unpins) a node at its rest position.")
      .def(
          "add_bending",
          [](ModelBuilder& b, Index a, Index c, Index d, double kb) {
            require_index(a, b.num_nodes(), "add_bending: a");
            require_index(c, b.num_nodes(), "add_bending: b");
            require_index(d, b.num_nodes(), "add_bending: c");
            b.add_bending(a, c, d, kb);
          },
          "a"_a, "b"_a, "c"_a, "kb"_a,
          "Adds a discrete bending term over the triple (a, b, c), middle node b.")
      .def_property_readonly("num_nodes", &ModelBuilder::num_nodes, "Nodes added so far.")
      .def("build", &ModelBuilder::build, "Validates and returns the finished Model (raises InvalidInput).");

  py::class_<SurfaceBodyParams> sbp(m, "SurfaceBodyParams",
                                    "Parameters of a surface mass-spring body: one spring per unique edge.");
  sbp.def_readwrite("node", &SurfaceBodyParams::node,
                    "NodeParams (kidney defaults: 0.3 g, beta 0.5, k_r 0.02).")
      .def_readwrite("k", &SurfaceBodyParams::k, "Surface spring stiffness, N/mm (default 0.05).")
      .def_readwrite("duffing", &SurfaceBodyParams::duffing, "DuffingSettings (Strain by default).")
      .def_readwrite("fixed", &SurfaceBodyParams::fixed,
                     "Pinned nodes (list of indices; assign a new list).");
  def_params(sbp);  // mass, beta, k_r, k, duffing, fixed: declared in physics/model.hpp
  settings_helpers(sbp);
  m.def("make_surface_model", &make_surface_model, "mesh"_a, "params"_a = SurfaceBodyParams{},
        "name"_a = "surface",
        "A surface mass-spring Model from a triangle mesh (one spring per unique edge, D-1).");

  // ---- State ----
  py::class_<Warnings>(m, "Warnings", "Counters of numerical trouble detected inside steps (never raised).")
      .def_readonly("nonfinite", &Warnings::nonfinite, "Substeps that produced NaN/Inf (rolled back).")
      .def_readonly("velocity_limit", &Warnings::velocity_limit, "Substeps above v_max (rolled back).")
      .def_readonly("rollbacks", &Warnings::rollbacks, "Frames retried with a halved step.")
      .def_readonly("unstable_refused", &Warnings::unstable_refused,
                    "Frames refused: dt above the stable bound with sub-stepping off.")
      .def_readonly("substeps_capped", &Warnings::substeps_capped, "Frames that hit max_substeps.")
      .def_readonly("cg_not_converged", &Warnings::cg_not_converged,
                    "Implicit solves that hit the iteration limit.")
      .def_readonly("failed", &Warnings::failed, "Frames that could not be advanced (state restored).")
      .def("total", &Warnings::total, "Sum of the counters except rollbacks.")
      .def("__repr__", [](const Warnings& w) { return cat("<medspring.Warnings total=", w.total(), ">"); });

  py::class_<State>(m, "State",
                    "Everything that changes while simulating. x, v and f_ext are WRITABLE zero-copy (N, 3) "
                    "float64 views into the state: writing through them changes the state. Assigning an "
                    "array (state.x = X) copies into the same buffer, so earlier views stay valid. "
                    "copy() is a checkpoint.")
      .def_property(
          "x", [](py::object self) { return view_of(self.cast<State&>().x, self, true); },
          [](State& s, py::handle X) { assign_points(s.x, X, "x"); }, "Positions (N, 3), mm (writable view).")
      .def_property(
          "v", [](py::object self) { return view_of(self.cast<State&>().v, self, true); },
          [](State& s, py::handle V) { assign_points(s.v, V, "v"); },
          "Velocities (N, 3), mm/ms (writable view).")
      .def_property(
          "f_ext", [](py::object self) { return view_of(self.cast<State&>().f_ext, self, true); },
          [](State& s, py::handle F) { assign_points(s.f_ext, F, "f_ext"); },
          "External force held over the next frame (N, 3), N (writable view; step() with loads overwrites "
          "it).")
      .def_property(
          "t", [](const State& s) { return s.t; },
          [](State& s, double t) {
            require_finite(t, "t");
            s.t = t;
          },
          "Time, ms.")
      .def_readonly("frames", &State::frames, "Frames advanced.")
      .def_readonly("substeps", &State::substeps, "Substeps taken in total.")
      .def_readonly("stiffening", &State::stiffening,
                    "max kappa_s / k_s at the last force evaluation (>= 1).")
      .def_property_readonly(
          "warnings", [](const State& s) { return s.warnings; }, "Warnings (a copy).")
      .def_property_readonly(
          "num_nodes", [](const State& s) { return static_cast<Index>(s.x.rows()); }, "Number of nodes N.")
      .def(
          "copy", [](const State& s) { return State(s); }, "A checkpoint (deep copy).")
      .def("__copy__", [](const State& s) { return State(s); })
      .def(
          "__deepcopy__", [](const State& s, py::handle) { return State(s); }, "memo"_a)
      .def("__repr__", [](const State& s) {
        return cat("<medspring.State ", s.x.rows(), " nodes, t = ", s.t, " ms, ", s.frames, " frames>");
      });
  m.def("make_state", py::overload_cast<const Model&>(&make_state), "model"_a,
        "A state at rest (x = x0, v = 0, t = 0) with all scratch allocated.");

  // ---- Loads ----
  py::class_<PointLoad> load(
      m, "PointLoad",
      "A point force on one node: F(t) = scale(t) * force, ramped linearly from t_on over "
      "t_ramp, held, released at t_release (instantly, or over t_ramp with ramp_down).");
  load.def_readwrite("node", &PointLoad::node, "Node index (surface node for a Simulation).")
      .def_property(
          "force", [](const PointLoad& l) { return copy_of(l.force); },
          [](PointLoad& l, py::handle F) { l.force = vec3_arg(F, "force"); }, "Full force vector, N.")
      .def_readwrite("t_on", &PointLoad::t_on, "ms: the ramp starts here (default 0).")
      .def_readwrite("t_ramp", &PointLoad::t_ramp, "ms: linear ramp duration (default 20; 0 = step).")
      .def_readwrite("t_release", &PointLoad::t_release, "ms: release time (default inf).")
      .def_readwrite("ramp_down", &PointLoad::ramp_down, "Release over t_ramp instead of instantly.")
      .def("scale", &PointLoad::scale, "t"_a, "Profile factor in [0, 1] at time t (ms).")
      .def(
          "at", [](const PointLoad& l, double t) { return copy_of(Vec3(l.at(t))); }, "t"_a,
          "Force (N) at time t.");
  settings_helpers(load);
  m.def("validate_loads", &validate_loads, "loads"_a, "n"_a,
        "Raises InvalidInput naming 'loads[k].field' unless every load is valid for n nodes.");
  m.def(
      "accumulate_loads",
      [](const std::vector<PointLoad>& loads, double t, Index n) {
        validate_loads(loads, n);
        MatX3 f = MatX3::Zero(n, 3);
        accumulate_loads(loads, t, f);
        return copy_of(f);
      },
      "loads"_a, "t"_a, "n"_a, "The (n, 3) external force of the loads at time t (ms), N.");
  m.def(
      "nearest_node",
      [](py::handle X, py::handle p) {
        const MatX3 P = points_arg(X, "X");
        require(P.rows() > 0, "X: expected at least one point");
        return nearest_node(P, vec3_arg(p, "p"));
      },
      "X"_a, "p"_a, "Index of the row of X (N, 3) nearest to p (ties: lowest index).");

  // ---- Integrators ----
  py::enum_<Integrator> integrator(m, "Integrator", "Time integrator (§2). Strings accepted.");
  integrator.value("SymplecticEuler", Integrator::SymplecticEuler, "default, §2.1")
      .value("ImplicitEuler", Integrator::ImplicitEuler, "§2.3, unconditionally stable, dissipative")
      .value("LinearStatic", Integrator::LinearStatic,
             "quasi-static linear response x0 + K0^-1 f, precomputed (docs/linear-response.md)");
  enum_accepts_strings(integrator, &parse_integrator);
  py::enum_<StableStep> stable_step(m, "StableStep",
                                    "The symplectic step's stable-step rule (StepSettings.stable_step). "
                                    "Strings accepted.");
  stable_step.value("Bound", StableStep::Bound, "the growth bound (default)")
      .value("Refresh", StableStep::Refresh, "tangent refresh: fewer sub-steps, offline runs");
  enum_accepts_strings(stable_step, &parse_stable_step);

  py::class_<StepSettings> step_settings(m, "StepSettings",
                                         "Settings of one frame of time integration (§2).");
  def_params(step_settings);  // declared in physics/integrators.hpp
  settings_helpers(step_settings);
  m.def("effective_threads", &effective_threads, "model"_a, "settings"_a,
        "Threads the step really uses for this model (1 for small models, the implicit integrator or "
        "bending terms).");
  m.def("validate_step_settings", &validate_step_settings, "model"_a, "settings"_a,
        "Raises InvalidInput naming the field unless the settings are valid for the model.");

  py::enum_<StepCode>(m, "StepCode", "Outcome of a frame.")
      .value("Ok", StepCode::Ok)
      .value("RolledBack", StepCode::RolledBack, "recovered by halving the step")
      .value("Refused", StepCode::Refused, "dt above the stable bound with sub-stepping off")
      .value("Failed", StepCode::Failed, "could not be advanced (state restored)");
  py::class_<StepStatus>(m, "StepStatus", "What a frame (or the worst of several frames) did.")
      .def_readonly("code", &StepStatus::code, "StepCode of the frame.")
      .def_readonly("substeps", &StepStatus::substeps, "Substeps taken in the frame.")
      .def_readonly("cg_iterations", &StepStatus::cg_iterations, "Implicit: CG iterations in the frame.")
      .def_property_readonly("ok", &StepStatus::ok, "Ok or RolledBack.")
      .def("__bool__", &StepStatus::ok)
      .def("__repr__", [](const StepStatus& s) {
        return cat("<medspring.StepStatus ", py::str(py::cast(s.code)).cast<std::string>(), ", ", s.substeps,
                   " substeps>");
      });

  m.def(
      "step",
      [](const Model& model, State& state, const StepSettings& settings,
         std::optional<std::vector<PointLoad>> loads, long nsteps) {
        check_state(model, state);
        validate_step_settings(model, settings);
        require(nsteps >= 0, "nsteps: must be >= 0 (got ", nsteps, ")");
        if (loads) validate_loads(*loads, model.num_nodes());
        const std::vector<PointLoad>* lp = loads ? &*loads : nullptr;
        py::gil_scoped_release release;
        StepStatus worst, last;
        for (long i = 0; i < nsteps; ++i) {
          last = step(model, state, settings, lp);
          if (last.code != StepCode::Ok) worst = last;
        }
        return worst.code != StepCode::Ok ? worst : last;
      },
      "model"_a, "state"_a, "settings"_a = StepSettings{}, "loads"_a = py::none(), "nsteps"_a = 1,
      "Advances `state` in place by `nsteps` frames of settings.dt (GIL released). External force: `loads` "
      "(PointLoads on model nodes, evaluated at every substep) if given, else state.f_ext held constant. "
      "Returns the status of the last frame that was not Ok (or Ok). Numerical trouble never raises: see "
      "state.warnings.");

  // ---- Forces, energy, stiffness ----
  m.def(
      "internal_forces",
      [](const Model& model, py::handle x, py::handle f_ext) {
        const Index n = model.num_nodes();
        const MatX3 X = points_arg(x, "x", n);
        const MatX3 F = f_ext.is_none() ? MatX3(MatX3::Zero(n, 3)) : points_arg(f_ext, "f_ext", n);
        MatX3 f(n, 3);
        const double stiffening = internal_forces(model, X, F, f);
        return py::make_tuple(copy_of(f), stiffening);
      },
      "model"_a, "x"_a, "f_ext"_a = py::none(),
      "Total force without damping f = f_ext - k_r (x - x0) + springs + bending (N, (N, 3)) at positions x; "
      "returns (f, stiffening) with stiffening = max kappa_s / k_s (§2.2).");
  m.def(
      "total_energy",
      [](const Model& model, py::handle x, py::handle v) {
        return total_energy(model, points_arg(x, "x", model.num_nodes()),
                            points_arg(v, "v", model.num_nodes()));
      },
      "model"_a, "x"_a, "v"_a, "Kinetic + return springs + springs + bending energy (§1.8), mJ.");
  m.def(
      "potential_energy",
      [](const Model& model, py::handle x) {
        return potential_energy(model, points_arg(x, "x", model.num_nodes()));
      },
      "model"_a, "x"_a, "Potential energy (return springs + springs + bending), mJ.");
  m.def(
      "tangent_stiffness",
      [](const Model& model, py::handle x, bool clamp_transverse, bool include_return) {
        return tangent_stiffness(model, points_arg(x, "x", model.num_nodes()),
                                 {.clamp_transverse = clamp_transverse, .include_return = include_return});
      },
      "model"_a, "x"_a, "clamp_transverse"_a = false, "include_return"_a = true,
      "Tangent stiffness K = d^2 V / dx^2 (3N x 3N scipy.sparse.csc_matrix, all nodes, row 3a + d = node a, "
      "axis d), N/mm.");
  m.def(
      "max_residual",
      [](const Model& model, py::handle x, py::handle f_ext) {
        return max_residual(model, points_arg(x, "x", model.num_nodes()),
                            points_arg(f_ext, "f_ext", model.num_nodes()));
      },
      "model"_a, "x"_a, "f_ext"_a, "Largest per-node norm of f_ext + f_int over free nodes, N.");

  // ---- Static equilibrium ----
  py::class_<StaticSettings> static_settings(m, "StaticSettings",
                                             "Settings of the static Newton solve (§2.4).");
  static_settings.def_readwrite("tolerance", &StaticSettings::tolerance, "Max per-node residual, N (1e-10).")
      .def_readwrite("max_iterations", &StaticSettings::max_iterations, "(default 200)")
      .def_readwrite("max_backtracks", &StaticSettings::max_backtracks, "(default 40)");
  settings_helpers(static_settings);
  py::class_<StaticResult>(m, "StaticResult", "An equilibrium found by static_equilibrium.")
      .def_property_readonly(
          "x", [](py::object self) { return view_of(self.cast<const StaticResult&>().x, self); },
          "Equilibrium positions (N, 3), mm (read-only view).")
      .def_readonly("iterations", &StaticResult::iterations, "Newton iterations.")
      .def_readonly("residual", &StaticResult::residual, "Final max per-node residual, N.")
      .def("__repr__", [](const StaticResult& r) {
        return cat("<medspring.StaticResult ", r.iterations, " iterations, residual ", r.residual, " N>");
      });
  m.def(
      "static_equilibrium",
      [](const Model& model, py::handle f_ext, const StaticSettings& settings, py::handle x_start) {
        const Index n = model.num_nodes();
        const MatX3 F = points_arg(f_ext, "f_ext", n);
        const MatX3 X = x_start.is_none() ? MatX3() : points_arg(x_start, "x_start", n);
        py::gil_scoped_release release;
        return static_equilibrium(model, F, settings, X);
      },
      "model"_a, "f_ext"_a, "settings"_a = StaticSettings{}, "x_start"_a = py::none(),
      "Solves f_ext + f_int(x) = 0 for the free nodes by Newton-Raphson with line search (§2.4), starting "
      "from x_start (x0 if None); GIL released. f_ext: (N, 3) N. Raises SolverError if no equilibrium is "
      "found (e.g. a soft spring loaded above its peak force).");

  // ---- The quasi-static linear response (docs/linear-response.md) ----
  py::class_<LinearResponse, std::shared_ptr<LinearResponse>> linear(
      m, "LinearResponse",
      "The linear static response of a model at rest, x = x0 + K0^-1 f (docs/linear-response.md): K0 "
      "factored "
      "once, each loaded node's three columns of K0^-1 solved on first use and cached. The engine of "
      "Integrator.LinearStatic.");
  linear
      .def(py::init([](const Model& model, double cache_mb, const std::string& precision) {
             require(cache_mb >= 0 && std::isfinite(cache_mb), "LinearResponse: cache_mb must be >= 0 (got ",
                     cache_mb, ")");
             require(precision == "float" || precision == "double",
                     "LinearResponse: precision must be float or double (got '", precision, "')");
             py::gil_scoped_release release;
             return std::make_shared<LinearResponse>(
                 model, static_cast<std::size_t>(cache_mb * 1024 * 1024),
                 precision == "float" ? LinearResponse::Precision::Float : LinearResponse::Precision::Double);
           }),
           "model"_a, "cache_mb"_a = 256.0, "precision"_a = "float",
           "Factors the model's tangent stiffness at rest over its free nodes; GIL released. Raises "
           "InvalidInput "
           "when it is not positive definite (rigid motion left free). precision: of the cached columns.")
      .def(
          "positions",
          [](LinearResponse& R, py::handle f) {
            const MatX3 F = points_arg(f, "f", R.num_nodes());
            MatX3 x(R.num_nodes(), 3);
            VecX b, u;
            Index k = 0;
            {
              py::gil_scoped_release release;
              k = R.positions(F, x, b, u);
            }
            require(k >= 0, "LinearResponse.positions: f has a row that is not finite");
            return copy_of(x);
          },
          "f"_a,
          "x0 + K0^-1 f (N, 3) mm for the forces f (N, 3) N; rows of fixed nodes are ignored. Caches the "
          "columns of the loaded nodes (up to direct_threshold of them).")
      .def("block", &LinearResponse::block, "i"_a, "j"_a,
           "The 3x3 compliance du_i/df_j (mm/N) of free nodes i and j; solves and caches j's columns.")
      .def(
          "precompute", [](LinearResponse& R, const std::vector<Index>& nodes) { R.precompute(nodes); },
          "nodes"_a, "Solves and caches these nodes' columns now.")
      .def(
          "count_inverted",
          [](const LinearResponse& R, py::handle f, py::handle x) {
            return R.count_inverted(points_arg(f, "f", R.num_nodes()), points_arg(x, "x", R.num_nodes()));
          },
          "f"_a, "x"_a, "Inverted tetrahedra at x = positions(f) (count_inverted's count).")
      .def("cached", &LinearResponse::cached, "node"_a)
      .def_property_readonly("cached_nodes", &LinearResponse::cached_nodes)
      .def_property_readonly("cached_bytes", &LinearResponse::cached_bytes)
      .def_property_readonly("num_nodes", &LinearResponse::num_nodes)
      .def_property_readonly("free_dofs", &LinearResponse::free_dofs)
      .def_property_readonly("factor_nonzeros", &LinearResponse::factor_nonzeros)
      .def_property_readonly("factor_ms", &LinearResponse::factor_ms)
      .def_property_readonly("direct_threshold", &LinearResponse::direct_threshold)
      .def("__repr__", [](const LinearResponse& R) {
        return cat("<medspring.LinearResponse ", R.num_nodes(), " nodes, ", R.cached_nodes(), " cached>");
      });

  // ---- Stability ----
  m.def(
      "gershgorin_omega",
      [](const Model& model, py::handle x) {
        return gershgorin_omega(model, x.is_none() ? model.x0 : points_arg(x, "x", model.num_nodes()));
      },
      "model"_a, "x"_a = py::none(), "Gershgorin bound on omega_max (rad/ms) at positions x (x0 if None).");
  m.def(
      "power_iteration_omega",
      [](const Model& model, py::handle x, int iterations, double safety) {
        return power_iteration_omega(model, x.is_none() ? model.x0 : points_arg(x, "x", model.num_nodes()),
                                     iterations, safety);
      },
      "model"_a, "x"_a = py::none(), "iterations"_a = 15, "safety"_a = 1.05,
      "Lanczos estimate (from below) of omega_max (rad/ms) at positions x (x0 if None), times safety.");
  m.def("dt_safe", &dt_safe, "model"_a, "stiffening"_a = 1.0, "safety"_a = 0.8,
        "The run-time stable step safety * 2 / (omega_rest sqrt(stiffening)), ms.");
}

}  // namespace medspring::python
