// The compiled part of the `medspring` Python package (`medspring._medspring`): exceptions, then one
// binding function per engine layer. The pure-Python package medspring/__init__.py re-exports
// everything and adds helpers.
#include "bind_common.hpp"

#ifndef MEDSPRING_VERSION
#define MEDSPRING_VERSION "0.0.0"
#endif

namespace medspring::python {
namespace {

// Exception types, created once and kept for the life of the interpreter.
PyObject* g_error = nullptr;
PyObject* g_invalid_input = nullptr;
PyObject* g_io_error = nullptr;
PyObject* g_solver_error = nullptr;

PyObject* make_exception(py::module_& m, const char* name, py::tuple bases, const char* doc) {
  const std::string full = std::string("medspring.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(full.c_str(), doc, bases.ptr(), nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.attr(name) = py::reinterpret_borrow<py::object>(type);  // the module holds a second reference
  return type;                                              // this one is never released
}

void bind_exceptions(py::module_& m) {
  py::object exception = py::module_::import("builtins").attr("Exception");
  py::object value_error = py::module_::import("builtins").attr("ValueError");
  py::object os_error = py::module_::import("builtins").attr("OSError");
  py::object runtime_error = py::module_::import("builtins").attr("RuntimeError");
  g_error = make_exception(m, "Error", py::make_tuple(exception),
                           "Base of every MedSpring exception; the message is one line naming the file, "
                           "element or argument at fault.");
  py::object error = py::reinterpret_borrow<py::object>(g_error);
  g_invalid_input = make_exception(
      m, "InvalidInput", py::make_tuple(error, value_error),
      "Bad input: invalid mesh, negative stiffness, out-of-range index, NaN, wrong array shape or dtype "
      "(a ValueError).");
  g_io_error =
      make_exception(m, "IoError", py::make_tuple(error, os_error),
                     "A file could not be read or written; the message names the file (an OSError).");
  g_solver_error = make_exception(m, "SolverError", py::make_tuple(error, runtime_error),
                                  "A numerical solve failed: singular system, no equilibrium, no convergence "
                                  "(a RuntimeError).");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InvalidInput& e) {
      PyErr_SetString(g_invalid_input, e.what());
    } catch (const IoError& e) {
      PyErr_SetString(g_io_error, e.what());
    } catch (const SolverError& e) {
      PyErr_SetString(g_solver_error, e.what());
    } catch (const Error& e) {
      PyErr_SetString(g_error, e.what());
    }
  });
}

}  // namespace
#ifdef MEDSPRING_PYTHON_WITH_SCENE
void bind_scene(py::module_& m);  // bind_scene.cpp
#endif

#ifdef MEDSPRING_PYTHON_WITH_FEM
void bind_fem(py::module_& m);  // bind_fem.cpp
#endif
#ifdef MEDSPRING_PYTHON_WITH_PAPER
void bind_paper(py::module_& m);  // bind_paper.cpp
#endif
#ifdef MEDSPRING_PYTHON_WITH_GPU
void bind_gpu(py::module_& m);  // bind_gpu.cpp
#endif
}  // namespace medspring::python

PYBIND11_MODULE(_medspring, m) {
  using namespace medspring::python;
  m.doc() =
      "MedSpring: real-time soft-tissue simulation (nonlinear mass-spring + simplified medial "
      "representation), the C++ engine bound for NumPy. Units: mm, g, ms, N. Import `medspring`, not "
      "this module.";
  m.attr("__version__") = MEDSPRING_VERSION;
  bind_exceptions(m);
  bind_geometry(m);
  bind_physics(m);
  bind_local(m);
  bind_models(m);
  bind_sim(m);
  bind_tools(m);
#ifdef MEDSPRING_PYTHON_WITH_IO
  bind_io(m);
  m.attr("has_io") = true;
#else
  m.attr("has_io") = false;
#endif
#ifdef MEDSPRING_PYTHON_WITH_SCENE
  bind_scene(m);
  m.attr("has_scene") = true;
#else
  m.attr("has_scene") = false;
#endif
#ifdef MEDSPRING_PYTHON_WITH_FEM
  bind_fem(m);
  m.attr("has_fem") = true;
#else
  m.attr("has_fem") = false;
#endif
#ifdef MEDSPRING_PYTHON_WITH_BUILDERS
  m.attr("has_builders") = true;  // blended (watertight) vessel trees: blend=True, scenes' "blend"
#else
  m.attr("has_builders") = false;
#endif
#ifdef MEDSPRING_PYTHON_WITH_PAPER
  bind_paper(m);
  m.attr("has_paper") = true;
#else
  m.attr("has_paper") = false;
#endif
#ifdef MEDSPRING_PYTHON_WITH_GPU
  bind_gpu(m);
  m.attr("has_gpu") = true;
#else
  m.attr("has_gpu") = false;
#endif
}
