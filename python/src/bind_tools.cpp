// Tools layer (docs/tools.md): rigid tools on a Simulation from NumPy. Poses are a position (3,) and a
// quaternion (w, x, y, z); the contact set comes back as NumPy arrays.
//
//   tools = medspring.ToolSimulation(sim, friction=0.2)
//   k = tools.add_tool(medspring.Tool.sphere(8.0), position=(0, 0, 28))
//   tools.set_pose(k, position=(0, 0, 23)); tools.update(nsteps=200)
//   tools.state(k)["force"], tools.contacts()["normal"]
#include <cmath>

#include "bind_common.hpp"
#include "bind_params.hpp"
#include "medspring/sim/tool_sim.hpp"

namespace medspring::python {

using namespace pybind11::literals;

namespace {

Pose pose_arg(py::handle position, py::handle rotation) {
  Pose p;
  p.position = vec3_arg(position, "position");
  if (!rotation.is_none()) {
    const VecX q = vector_arg(rotation, "rotation", 4, "4 (w, x, y, z)");
    p.rotation = Quat(q[0], q[1], q[2], q[3]);
  }
  return checked_pose(p, "pose");
}

py::dict state_dict(const ToolState& s) {
  return py::dict("force"_a = copy_of(s.force), "torque"_a = copy_of(s.torque), "area"_a = s.area,
                  "penetration"_a = s.penetration, "triangle_penetration"_a = s.triangle_penetration,
                  "contacts"_a = s.contacts, "grasping"_a = s.grasping, "attached"_a = s.attached,
                  "grasp_force"_a = copy_of(s.grasp_force), "position"_a = copy_of(s.pose.position),
                  "rotation"_a = py::make_tuple(s.pose.rotation.w(), s.pose.rotation.x(), s.pose.rotation.y(),
                                                s.pose.rotation.z()));
}

}  // namespace

void bind_tools(py::module_& m) {
  py::class_<Tool>(m, "Tool",
                   "A rigid tool shape (docs/tools.md): Tool.sphere(r), Tool.capsule(r, length), "
                   "Tool.grasper(r, length, opening_rad), or Tool.parse('sphere:5').")
      .def_static("sphere", &Tool::sphere, "radius"_a)
      .def_static("capsule", &Tool::capsule, "radius"_a, "length"_a)
      .def_static("grasper", &Tool::grasper, "radius"_a, "length"_a, "opening"_a)
      .def_static("parse", &parse_tool, "text"_a)
      .def_property_readonly("kind", [](const Tool& t) { return to_string(t.kind); })
      .def_readonly("radius", &Tool::radius)
      .def_readonly("length", &Tool::length)
      .def_readonly("opening", &Tool::opening)
      .def("__repr__", [](const Tool& t) {
        return cat("Tool(", to_string(t.kind), ", radius=", t.radius, ", length=", t.length,
                   ", opening=", t.opening, ")");
      });

  py::class_<ContactSettings> contact(m, "ContactSettings",
                                      "Contact response of rigid tools (docs/tools.md, docs/parameters.md).");
  def_params(contact);  // friction, stiffness, kappa, ...: declared in tools/contact.hpp
  settings_helpers(contact);

  py::class_<ToolSimulation>(
      m, "ToolSimulation",
      "Rigid tools acting on a Simulation: every update collides them with the deformed surface and adds the "
      "contact forces to the update. Keeps the Simulation alive.")
      .def(py::init([](Simulation& sim, std::optional<double> friction, std::optional<double> stiffness,
                       std::optional<ContactSettings> settings) {
             ContactSettings s = settings.value_or(ContactSettings{});
             if (friction) s.friction = *friction;
             if (stiffness) s.stiffness = *stiffness;
             return std::make_unique<ToolSimulation>(sim, s);
           }),
           "sim"_a, "friction"_a = py::none(), "stiffness"_a = py::none(), "settings"_a = py::none(),
           py::keep_alive<1, 2>(),
           "settings: ContactSettings (defaults when None); friction and stiffness, when given, override it.")
      .def(
          "add_tool",
          [](ToolSimulation& t, const Tool& tool, py::handle position, py::handle rotation) {
            return t.add_tool(tool, pose_arg(position, rotation));
          },
          "tool"_a, "position"_a, "rotation"_a = py::none(),
          "Adds a tool at a pose; raises InvalidInput for a bad size or pose or a start inside the organ.")
      .def(
          "set_pose",
          [](ToolSimulation& t, Index k, py::handle position, py::handle rotation) {
            t.set_pose(k, pose_arg(position, rotation));
          },
          "tool"_a, "position"_a, "rotation"_a = py::none())
      .def("set_opening", &ToolSimulation::set_opening, "tool"_a, "opening"_a, "Grasper opening (rad).")
      .def(
          "set_path",
          [](ToolSimulation& t, Index k, py::handle times, py::handle positions) {
            const VecX tt = vector_arg(times, "times");
            const MatX3 P = points_arg(positions, "positions", static_cast<Index>(tt.size()), "len(times)");
            ToolPath path;
            for (Index i = 0; i < tt.size(); ++i)
              path.push_back({tt[i], Pose{P.row(i).transpose(), Quat::Identity()}});
            t.set_path(k, std::move(path));
          },
          "tool"_a, "times"_a, "positions"_a,
          "Keyframes: times (ms) and positions (N, 3), linear in between.")
      .def(
          "update",
          [](ToolSimulation& t, long nsteps) {
            require(nsteps >= 0, "nsteps: must be >= 0 (got ", nsteps, ")");
            py::gil_scoped_release release;
            StepStatus last;
            for (long i = 0; i < nsteps; ++i) last = t.update();
            return last.ok();
          },
          "nsteps"_a = 1, "Advances nsteps updates; returns whether the last one was ok.")
      .def("reset", &ToolSimulation::reset)
      .def_property_readonly("num_tools", [](const ToolSimulation& t) { return t.contact().num_tools(); })
      .def_property_readonly(
          "stiffness", [](const ToolSimulation& t) { return t.contact().stiffness(); },
          "Penalty stiffness in use, N/mm^3.")
      .def(
          "state",
          [](const ToolSimulation& t, Index k) {
            require_index(k, t.contact().num_tools(), "tool");
            return state_dict(t.contact().state(k));
          },
          "tool"_a, "Force (N) and torque (N mm) on the tool, contact area, penetration, grasp state.")
      .def(
          "contacts",
          [](const ToolSimulation& t) {
            const auto& c = t.contact().contacts();
            const Index n = static_cast<Index>(c.size());
            MatX3 point(n, 3), normal(n, 3), bary(n, 3), force(n, 3);
            VecX depth(n), area(n);
            Eigen::VectorXi tri(n), tool(n);
            for (Index i = 0; i < n; ++i) {
              const Contact& x = c[static_cast<std::size_t>(i)];
              point.row(i) = x.point.transpose();
              normal.row(i) = x.normal.transpose();
              bary.row(i) = x.bary.transpose();
              force.row(i) = x.force.transpose();
              depth[i] = x.depth;
              area[i] = x.area;
              tri[i] = x.triangle;
              tool[i] = x.tool;
            }
            return py::dict("triangle"_a = copy_of(tri), "tool"_a = copy_of(tool), "point"_a = copy_of(point),
                            "normal"_a = copy_of(normal), "bary"_a = copy_of(bary),
                            "depth"_a = copy_of(depth), "area"_a = copy_of(area), "force"_a = copy_of(force));
          },
          "The contact set of the last update as NumPy arrays (one row per contact).");
}

}  // namespace medspring::python
