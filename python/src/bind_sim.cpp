// Sim layer: Simulation, the main user API (loads on surface nodes -> step -> surface map -> local
// overlay -> normals). update / advance release the GIL. Positions and velocities are zero-copy views.
#include "bind_common.hpp"
#include "bind_params.hpp"
#include "medspring/sim/checkpoint.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring::python {

using namespace pybind11::literals;

namespace {

// Simulation::reset and set_state replace the State object, which would leave NumPy views of the old
// x / v / f_ext buffers dangling. Run `fn` with the current buffers set aside and move the new values
// back into them, so every view handed out stays valid and sees the new state.
template <class Fn>
void keep_state_buffers(Simulation& sim, Fn&& fn) {
  MatX3 saved[3];
  auto fields = [&]() {
    State& s = sim.state();
    return std::array<MatX3*, 3>{&s.x, &s.v, &s.f_ext};
  };
  {
    // set the viewed buffers aside and leave equal copies in the state, which `fn` may read
    auto f = fields();
    for (int i = 0; i < 3; ++i) {
      saved[i].swap(*f[i]);
      *f[i] = saved[i];
    }
  }
  auto restore = [&]() {
    auto f = fields();
    for (int i = 0; i < 3; ++i) {
      if (f[i]->rows() == saved[i].rows() && f[i]->data() != nullptr)
        saved[i] = *f[i];  // same size: no realloc
      f[i]->swap(saved[i]);
    }
  };
  try {
    fn();
  } catch (...) {
    restore();
    throw;
  }
  restore();
}

StepStatus run_frames(Simulation& sim, long nsteps) {
  require(nsteps >= 0, "nsteps: must be >= 0 (got ", nsteps, ")");
  py::gil_scoped_release release;
  StepStatus worst, last;
  for (long i = 0; i < nsteps; ++i) {
    last = sim.update();
    if (last.code != StepCode::Ok) worst = last;
  }
  return worst.code != StepCode::Ok ? worst : last;
}

}  // namespace

void bind_sim(py::module_& m) {
  py::class_<LocalOptions> lo(m, "LocalOptions", "Local deformation overlay of a Simulation (eq. 6, §6.5).");
  lo.def_readwrite("enabled", &LocalOptions::enabled, "Overlay while a force acts (False).")
      .def_readwrite("settings", &LocalOptions::settings, "LocalDeformationSettings.")
      .def_readwrite("use_body_stiffness", &LocalOptions::use_body_stiffness,
                     "k_loc = body.local_stiffness (True).")
      .def_readwrite("guard", &LocalOptions::guard,
                     "Limit |U_c| to 0.9 x the contact's spoke length (False).");
  def_params(lo);  // enabled, stiffness, k_loc, cache, ...: declared in sim/simulation.hpp
  settings_helpers(lo);

  py::class_<SimulationSettings> sset(m, "SimulationSettings", "Settings of a Simulation.");
  sset.def_readwrite("step", &SimulationSettings::step,
                     "StepSettings (dt 0.5 ms, symplectic Euler, sub-stepping).")
      .def_readwrite("local", &SimulationSettings::local, "LocalOptions.")
      .def_readwrite(
          "normals", &SimulationSettings::normals,
          "Vertex normals available (True): computed when read after an update, not in every update.");
  settings_helpers(sset);

  py::class_<Simulation>(
      m, "Simulation",
      "One simulated organ over time: a Body, its state, loads on surface nodes and the local overlay. One "
      "update = loads -> DOF forces -> step -> map to the surface -> + local displacement (normals when "
      "read) "
      "(D-18).\n\n"
      "    sim = medspring.Simulation(medspring.hybrid_kidney_phantom())\n"
      "    sim.set_loads([medspring.PointLoad(node=223, force=(0, 0, -1), t_release=500)])\n"
      "    sim.update(nsteps=2000)          # 1000 ms at 0.5 ms per frame, GIL released\n"
      "    S = sim.surface                  # (S, 3) read-only view, mm\n\n"
      "positions / velocities are writable zero-copy views of the physics state. Not thread-safe: use one "
      "Simulation per thread.")
      .def(py::init([](std::shared_ptr<Body> body, const SimulationSettings& settings) {
             require(body != nullptr, "body: expected a Body, got None");
             return std::make_unique<Simulation>(std::move(body), settings);
           }),
           "body"_a, "settings"_a = SimulationSettings{},
           "A simulation of `body` at rest (t = 0). Raises InvalidInput for invalid settings.")
      .def("set_loads", &Simulation::set_loads, "loads"_a,
           "Replaces the loads (PointLoads on SURFACE nodes; the body transfers them to its DOFs). Raises "
           "InvalidInput naming 'loads[k].field'.")
      .def_property(
          "loads", [](const Simulation& s) { return s.loads(); },
          [](Simulation& s, std::vector<PointLoad> loads) { s.set_loads(std::move(loads)); },
          "The loads (a copy; assign a list to replace them).")
      .def(
          "set_tool_force",
          [](Simulation& s, Index node, py::handle F) { s.set_tool_force(node, vec3_arg(F, "F")); }, "node"_a,
          "F"_a,
          "External tool force F (N) on surface node `node`, added to the loads in every update until "
          "changed "
          "or cleared: the per-tick force of a haptic coupling. Raises InvalidInput for a bad node or force.")
      .def("clear_tool_force", &Simulation::clear_tool_force, "Removes the tool force.")
      .def_property_readonly("tool_node", &Simulation::tool_node, "The tool's surface node (-1 when none).")
      .def_property_readonly(
          "tool_force", [](const Simulation& s) { return copy_of(Vec3(s.tool_force())); },
          "The tool force, N.")
      .def("update", &run_frames, "nsteps"_a = 1,
           "Advances `nsteps` frames of settings.step.dt (GIL released) and refreshes the surface. Returns "
           "the "
           "status of the last frame that was not Ok (or Ok). Never raises for numerical trouble: see the "
           "status and state.warnings.")
      .def("step", &run_frames, "nsteps"_a = 1, "Same as update(nsteps).")
      .def("advance", &run_frames, "frames"_a, "Same as update(frames).")
      .def_property_readonly("time", &Simulation::time, "Simulated time, ms.")
      .def_property_readonly(
          "body", [](const Simulation& s) { return std::const_pointer_cast<Body>(s.body_ptr()); },
          "The Body.")
      .def_property_readonly("model", &Simulation::model, py::return_value_policy::reference_internal,
                             "The physics Model.")
      .def_property_readonly(
          "state", [](Simulation& s) -> State& { return s.state(); },
          py::return_value_policy::reference_internal,
          "The physics State (not a copy: its x, v, f_ext are writable views).")
      .def_property(
          "positions",
          [](py::object self) { return view_of(self.cast<Simulation&>().state().x, self, true); },
          [](Simulation& s, py::handle X) { assign_points(s.state().x, X, "positions"); },
          "DOF positions (N, 3) float64, mm: a WRITABLE zero-copy view of state.x. Writing moves the nodes; "
          "the displayed surface follows at the next update.")
      .def_property(
          "velocities",
          [](py::object self) { return view_of(self.cast<Simulation&>().state().v, self, true); },
          [](Simulation& s, py::handle V) { assign_points(s.state().v, V, "velocities"); },
          "DOF velocities (N, 3) float64, mm/ms: a WRITABLE zero-copy view of state.v.")
      .def_property_readonly(
          "surface", [](py::object self) { return view_of(self.cast<const Simulation&>().surface(), self); },
          "Displayed surface (S, 3), mm: mapped global positions + local overlay (read-only view, updated in "
          "place by every update).")
      .def_property_readonly(
          "global_surface",
          [](py::object self) { return view_of(self.cast<const Simulation&>().global_surface(), self); },
          "Mapped surface without the local overlay (S, 3), read-only view.")
      .def_property_readonly(
          "normals", [](py::object self) { return view_of(self.cast<const Simulation&>().normals(), self); },
          "Unit vertex normals of the surface (S, 3), read-only view, computed on access: reading it after "
          "an "
          "update recomputes them (a view held across updates is refreshed by the next read). Empty when "
          "settings.normals is False.")
      .def(
          "displacement", [](const Simulation& s) { return copy_of(s.displacement()); },
          "Displacement of the displayed surface from rest (S, 3), mm (a new array).")
      .def(
          "applied_force", [](const Simulation& s) { return copy_of(Vec3(s.applied_force())); },
          "Total external force now applied (N) = minus the reaction felt by the tool.")
      .def_property_readonly(
          "local_nodes", [](const Simulation& s) { return copy_of(s.local_nodes()); },
          "Surface indices of the local patch of the last update (empty if none).")
      .def_property_readonly(
          "local_displacement", [](const Simulation& s) { return copy_of(MatX3(s.local_displacement())); },
          "Displacement (P, 3) of the local patch nodes in the last update, mm (a copy).")
      .def_property_readonly("settings", &Simulation::settings,
                             "SimulationSettings (a copy; use set_settings).")
      .def("set_settings", &Simulation::set_settings, "settings"_a,
           "Replaces the settings (validated; the local deformer is rebuilt).")
      .def(
          "reset", [](Simulation& s) { keep_state_buffers(s, [&] { s.reset(); }); },
          "Back to rest: x = x0, v = 0, t = 0 (loads kept). Existing position / velocity views stay valid.")
      .def(
          "set_state",
          [](Simulation& s, const State& state) {
            const State copy = state;  // state may be s.state() itself
            keep_state_buffers(s, [&] { s.set_state(copy); });
          },
          "state"_a,
          "Replaces the state (e.g. a checkpoint from state.copy()); sizes must match the model. Existing "
          "views stay valid.")
      .def(
          "save_checkpoint", [](const Simulation& s, const std::string& path) { save_checkpoint(path, s); },
          "path"_a,
          "Writes a checkpoint (state, loads, step settings; versioned and checksummed) atomically: a "
          "temporary "
          "file renamed over `path` (docs/reliability.md).")
      .def(
          "restore_checkpoint",
          [](Simulation& s, const std::string& path) {
            keep_state_buffers(s, [&] { restore_checkpoint(path, s); });
          },
          "path"_a,
          "Resumes from a checkpoint of the same model: the next update gives the same bits as in the saved "
          "run. Raises IoError (truncated, corrupted, other version) or InvalidInput (another model); the "
          "simulation is unchanged then. Existing views stay valid.")
      .def("__repr__", [](const Simulation& s) {
        return cat("<medspring.Simulation ", s.body().kind(), " body, ", s.model().num_nodes(),
                   " nodes, t = ", s.time(), " ms>");
      });
}

}  // namespace medspring::python
