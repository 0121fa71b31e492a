// Tools layer (docs/tools.md): rigid tools on a Simulation from NumPy. Poses are a position (3,) and a
// quaternion (w, x, y, z); the contact set comes back as NumPy arrays.
//
//   tools = medspring.ToolSimulation(sim, friction=0.2)
//   k = tools.add_tool(medspring.Tool.sphere(8.0), position=(0, 0, 28))
//   tools.set_pose(k, position=(0, 0, 23)); tools.update(nsteps=200)
//   tools.state(k)["force"], tools.contacts()["normal"]
//   h = tools.record(200)          # per-update tool states and contacts of 200 updates (NumPy)
//   h["force"][:, k], h["contact"]["depth"][h["contact"]["update"] == 10]
#include <cmath>
#include <cstring>
#include <vector>

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
  return py::dict(
      "force"_a = copy_of(s.force), "torque"_a = copy_of(s.torque), "area"_a = s.area,
      "penetration"_a = s.penetration, "triangle_penetration"_a = s.triangle_penetration,
      "contacts"_a = s.contacts, "inside"_a = s.inside, "grasping"_a = s.grasping, "attached"_a = s.attached,
      "grasp_force"_a = copy_of(s.grasp_force), "position"_a = copy_of(s.pose.position),
      "rotation"_a =
          py::make_tuple(s.pose.rotation.w(), s.pose.rotation.x(), s.pose.rotation.y(), s.pose.rotation.z()));
}

py::dict contacts_dict(const std::vector<Contact>& c, const std::vector<Index>* update) {
  const Index n = static_cast<Index>(c.size());
  MatX3 point(n, 3), normal(n, 3), bary(n, 3), force(n, 3);
  VecX depth(n), area(n);
  Eigen::VectorXi tri(n), tool(n), part(n);
  for (Index i = 0; i < n; ++i) {
    const Contact& x = c[static_cast<std::size_t>(i)];
    point.row(i) = x.point.transpose();
    normal.row(i) = x.normal.transpose();
    bary.row(i) = x.bary.transpose();
    force.row(i) = x.force.transpose();
    depth[i] = x.depth;
    area[i] = x.area;
    tri[i] = static_cast<int>(x.triangle);
    tool[i] = x.tool;
    part[i] = x.part;
  }
  py::dict d("triangle"_a = copy_of(tri), "tool"_a = copy_of(tool), "part"_a = copy_of(part),
             "point"_a = copy_of(point), "normal"_a = copy_of(normal), "bary"_a = copy_of(bary),
             "depth"_a = copy_of(depth), "area"_a = copy_of(area), "force"_a = copy_of(force));
  if (update) d["update"] = copy_of(*update);
  return d;
}

// (n, k) or (n, k, 3) float64 array from a flat vector.
py::array shaped(const std::vector<double>& v, py::ssize_t n, py::ssize_t k, py::ssize_t c) {
  py::array_t<double> a = c > 1 ? py::array_t<double>({n, k, c}) : py::array_t<double>({n, k});
  if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), sizeof(double) * v.size());
  return a;
}

// nsteps updates recording every tool's state and the contact set of each update.
py::dict record_updates(ToolSimulation& t, long nsteps) {
  require(nsteps >= 0, "nsteps: must be >= 0 (got ", nsteps, ")");
  const Index K = t.contact().num_tools();
  std::vector<double> time, force, torque, position, grasp, area, pen, tri_pen, contacts, inside, grasping;
  std::vector<std::uint8_t> ok;
  std::vector<Contact> all;
  std::vector<Index> update, offsets{0};
  {
    py::gil_scoped_release release;
    for (long i = 0; i < nsteps; ++i) {
      ok.push_back(t.update().ok() ? 1 : 0);
      time.push_back(t.simulation().time());
      for (Index k = 0; k < K; ++k) {
        const ToolState& s = t.contact().state(k);
        for (int d = 0; d < 3; ++d) {
          force.push_back(s.force[d]);
          torque.push_back(s.torque[d]);
          position.push_back(s.pose.position[d]);
          grasp.push_back(s.grasp_force[d]);
        }
        area.push_back(s.area);
        pen.push_back(s.penetration);
        tri_pen.push_back(s.triangle_penetration);
        contacts.push_back(static_cast<double>(s.contacts));
        inside.push_back(s.inside ? 1 : 0);
        grasping.push_back(s.grasping ? 1 : 0);
      }
      for (const Contact& c : t.contact().contacts()) {
        all.push_back(c);
        update.push_back(static_cast<Index>(i));
      }
      offsets.push_back(static_cast<Index>(all.size()));
    }
  }
  const py::ssize_t n = static_cast<py::ssize_t>(nsteps), k = static_cast<py::ssize_t>(K);
  py::array_t<bool> okk(n);
  for (py::ssize_t i = 0; i < n; ++i) okk.mutable_at(i) = ok[static_cast<std::size_t>(i)] != 0;
  auto as_int = [&](const std::vector<double>& v) {
    py::array_t<Index> a({n, k});
    for (std::size_t i = 0; i < v.size(); ++i) a.mutable_data()[i] = static_cast<Index>(v[i]);
    return a;
  };
  auto as_bool = [&](const std::vector<double>& v) {
    py::array_t<bool> a({n, k});
    for (std::size_t i = 0; i < v.size(); ++i) a.mutable_data()[i] = v[i] != 0;
    return a;
  };
  return py::dict("time"_a = copy_of(time), "ok"_a = okk, "force"_a = shaped(force, n, k, 3),
                  "torque"_a = shaped(torque, n, k, 3), "position"_a = shaped(position, n, k, 3),
                  "grasp_force"_a = shaped(grasp, n, k, 3), "area"_a = shaped(area, n, k, 1),
                  "penetration"_a = shaped(pen, n, k, 1), "triangle_penetration"_a = shaped(tri_pen, n, k, 1),
                  "contacts"_a = as_int(contacts), "inside"_a = as_bool(inside),
                  "grasping"_a = as_bool(grasping), "offsets"_a = copy_of(offsets),
                  "contact"_a = contacts_dict(all, &update));
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
                       std::optional<ContactSettings> settings, std::optional<bool> substep) {
             ContactSettings s = settings.value_or(ContactSettings{});
             if (friction) s.friction = *friction;
             if (stiffness) s.stiffness = *stiffness;
             if (substep) s.substep = *substep;
             return std::make_unique<ToolSimulation>(sim, s);
           }),
           "sim"_a, "friction"_a = py::none(), "stiffness"_a = py::none(), "settings"_a = py::none(),
           "substep"_a = py::none(), py::keep_alive<1, 2>(),
           "settings: ContactSettings (defaults when None); friction, stiffness and substep (penalty forces "
           "re-evaluated every substep), when given, override it.")
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
          "contacts", [](const ToolSimulation& t) { return contacts_dict(t.contact().contacts(), nullptr); },
          "The contact set of the last update as NumPy arrays (one row per contact): triangle, tool, part "
          "(grasper jaw), point, normal (out of the tissue), bary, depth (mm), area (rest, mm^2), force on "
          "the "
          "tissue (N).")
      .def("record", &record_updates, "nsteps"_a,
           "Advances nsteps updates and returns what each one gave as NumPy arrays: time (n,) ms, ok (n,), "
           "per tool force and torque on it (n, k, 3), position, grasp_force (n, k, 3), area, penetration, "
           "triangle_penetration (n, k), contacts, inside, grasping (n, k); and 'contact', every update's "
           "contact set stacked (the columns of contacts() plus 'update', the row of the update), with "
           "'offsets' (n + 1,): update i's contacts are rows offsets[i]:offsets[i + 1].")
      .def(
          "save_history", [](const ToolSimulation& t) { return py::bytes(t.save_history()); },
          "The contact's history as bytes (what a checkpoint keeps: poses, last poses, grasp attachments, "
          "multipliers, the last surface).")
      .def(
          "restore_history",
          [](ToolSimulation& t, py::bytes b) { t.restore_history(std::string(b), "contact history"); },
          "data"_a,
          "Restores save_history() bytes into a ToolSimulation with the same tools on the same model (its "
          "Simulation restored to the same state): the next updates repeat the saved run's bit for bit.");
}

}  // namespace medspring::python
