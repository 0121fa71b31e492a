// The CUDA backend (gpu::Engine, docs/gpu.md) from Python: medspring._medspring._gpu, re-exported as
// medspring.gpu (python/medspring/gpu.py, which also answers in a build without CUDA). Batches as
// (B, N, 3) NumPy arrays; the device state handed zero-copy through DLPack (__dlpack__) to CuPy/PyTorch.
#include <algorithm>
#include <memory>
#include <optional>

#include "bind_common.hpp"
#include "medspring/gpu/engine.hpp"
#include "medspring/physics/integrators.hpp"
#ifdef MEDSPRING_PYTHON_WITH_SCENE
#include "medspring/gpu/scene_batch.hpp"
#endif

namespace medspring::python {
namespace {

using namespace pybind11::literals;

// The DLPack ABI (dlpack.h, v0.8; stable since v0.6): a device tensor and its deleter.
struct DLDevice {
  int32_t device_type;  // kDLCUDA = 2
  int32_t device_id;
};
struct DLDataType {
  uint8_t code;  // kDLFloat = 2
  uint8_t bits;
  uint16_t lanes;
};
struct DLTensor {
  void* data;
  DLDevice device;
  int32_t ndim;
  DLDataType dtype;
  int64_t* shape;
  int64_t* strides;  // null: C-contiguous
  uint64_t byte_offset;
};
struct DLManagedTensor {
  DLTensor dl_tensor;
  void* manager_ctx;
  void (*deleter)(DLManagedTensor* self);
};
constexpr int32_t kDLCUDA = 2;

struct Managed {
  DLManagedTensor t{};
  int64_t shape[3]{};
  PyObject* owner = nullptr;  // the Python engine, kept alive while a consumer holds the tensor
};

void delete_managed(DLManagedTensor* self) {
  auto* m = static_cast<Managed*>(self->manager_ctx);
  {
    py::gil_scoped_acquire gil;
    Py_XDECREF(m->owner);
  }
  delete m;
}

void capsule_destructor(PyObject* capsule) {
  // A capsule never consumed (still named "dltensor") owns its tensor.
  if (PyCapsule_IsValid(capsule, "dltensor")) {
    auto* t = static_cast<DLManagedTensor*>(PyCapsule_GetPointer(capsule, "dltensor"));
    if (t && t->deleter) t->deleter(t);
  } else {
    PyErr_Clear();
  }
}

// Engine plus references to the models it points at (they must outlive it).
struct PyEngine {
  std::vector<py::object> keep;
  std::unique_ptr<gpu::Engine> e;
};

py::object dlpack(py::object self, bool velocities) {
  PyEngine& pe = self.cast<PyEngine&>();
  const gpu::Engine::DeviceState d = pe.e->device_state();
  auto* m = new Managed;
  m->shape[0] = d.batch;
  m->shape[1] = d.nodes;
  m->shape[2] = 3;
  DLTensor& t = m->t.dl_tensor;
  t.data = velocities ? d.v : d.x;
  t.device = {kDLCUDA, d.device};
  t.ndim = 3;
  t.dtype = {2, static_cast<uint8_t>(d.precision == gpu::Precision::Double ? 64 : 32), 1};
  t.shape = m->shape;
  t.strides = nullptr;
  t.byte_offset = 0;
  m->t.manager_ctx = m;
  m->t.deleter = delete_managed;
  m->owner = self.ptr();
  Py_INCREF(m->owner);
  PyObject* capsule = PyCapsule_New(&m->t, "dltensor", capsule_destructor);
  if (!capsule) {
    delete_managed(&m->t);
    throw py::error_already_set();
  }
  return py::reinterpret_steal<py::object>(capsule);
}

// (B, N, 3) float64 array of every model's positions or velocities.
py::array batch_array(gpu::Engine& e, bool velocities) {
  const int B = e.batch();
  const Index n = e.nodes();
  py::array_t<double> out({static_cast<py::ssize_t>(B), static_cast<py::ssize_t>(n), py::ssize_t{3}});
  double* dst = out.mutable_data();
  for (int b = 0; b < B; ++b) {
    const MatX3 M = velocities ? e.velocities(b) : e.positions(b);
    std::memcpy(dst + static_cast<std::size_t>(b) * 3 * static_cast<std::size_t>(n), M.data(),
                sizeof(double) * 3 * static_cast<std::size_t>(n));
  }
  return out;
}

// A (B, N, 3) float64 C-contiguous array argument.
py::array_t<double> batch_arg(py::handle obj, const char* name, int B, Index n) {
  const std::string expected = cat("a C-contiguous float64 array of shape (", B, ", ", n, ", 3)");
  if (!py::isinstance<py::array>(obj))
    throw InvalidInput(cat(name, ": expected ", expected, "; got ", describe_object(obj)));
  auto a = py::reinterpret_borrow<py::array>(obj);
  const bool ok = a.dtype().is(py::dtype::of<double>()) && a.ndim() == 3 && a.shape(0) == B &&
                  a.shape(1) == n && a.shape(2) == 3 && (a.flags() & py::array::c_style);
  if (!ok) throw InvalidInput(cat(name, ": expected ", expected, "; got ", describe_object(obj)));
  return py::array_t<double>::ensure(a);
}

}  // namespace

#ifdef MEDSPRING_PYTHON_WITH_SCENE
BatchStepperFactory& gpu_batch_factory();  // bind_scene.cpp
#endif

void bind_gpu(py::module_& parent) {
#ifdef MEDSPRING_PYTHON_WITH_SCENE
  gpu_batch_factory() = gpu::scene_batch_stepper();  // SceneRunner.run_batch(device="cuda")
#endif
  py::module_ m = parent.def_submodule("_gpu", "The CUDA backend (docs/gpu.md); use medspring.gpu.");
  py::object error = parent.attr("Error");
  py::object runtime_error = py::module_::import("builtins").attr("RuntimeError");
  static PyObject* gpu_error = nullptr;
  gpu_error = PyErr_NewExceptionWithDoc(
      "medspring.gpu.GpuError",
      "A GPU-side failure: no device, a driver older than the runtime, out of device memory, a model "
      "feature the GPU path lacks. The message names the cause and the CPU alternative.",
      py::make_tuple(error, runtime_error).ptr(), nullptr);
  if (!gpu_error) throw py::error_already_set();
  m.attr("GpuError") = py::reinterpret_borrow<py::object>(gpu_error);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const gpu::GpuError& e) {
      PyErr_SetString(gpu_error, e.what());
    }
  });

  m.def(
      "require_device",
      [](int index) {
        const gpu::DeviceInfo d = gpu::require_device(index);
        return py::dict("index"_a = d.index, "name"_a = d.name,
                        "compute_capability"_a = py::make_tuple(d.major, d.minor),
                        "multiprocessors"_a = d.multiprocessors, "memory_bytes"_a = d.memory_bytes,
                        "shared_per_block"_a = d.shared_per_block, "driver_version"_a = d.driver_version,
                        "runtime_version"_a = d.runtime_version);
      },
      "index"_a = 0, "The device `index` as a dict, or GpuError saying why it cannot be used.");
  m.def("require_supported", &gpu::require_supported, "kind"_a, "local_overlay"_a = false, "tools"_a = false,
        "GpuError naming the feature and the CPU alternative unless a model of this kind runs on the GPU.");

  py::class_<PyEngine>(m, "Engine",
                       "B spring networks of the same topology stepped together on the GPU (gpu::Engine, "
                       "docs/gpu.md). The models are kept alive by the engine.")
      .def(py::init([](py::list models, const StepSettings& settings, const std::string& precision,
                       const std::string& kernel, bool graphs, int device) {
             auto pe = std::make_unique<PyEngine>();
             std::vector<const Model*> ms;
             for (py::handle h : models) {
               pe->keep.push_back(py::reinterpret_borrow<py::object>(h));
               ms.push_back(&h.cast<const Model&>());
             }
             gpu::Options o;
             o.precision = gpu::parse_precision(precision);
             o.graphs = graphs;
             o.device = device;
             if (kernel == "auto")
               o.kernel = gpu::Options::Kernel::Auto;
             else if (kernel == "grid")
               o.kernel = gpu::Options::Kernel::Grid;
             else if (kernel == "block")
               o.kernel = gpu::Options::Kernel::PerBlock;
             else
               throw InvalidInput(cat("kernel: unknown value '", kernel, "' (expected auto, grid or block)"));
             pe->e = std::make_unique<gpu::Engine>(ms, settings, o);
             return pe;
           }),
           "models"_a, "settings"_a = StepSettings{}, "precision"_a = "fp64", "kernel"_a = "auto",
           "graphs"_a = true, "device"_a = 0)
      .def_property_readonly("batch", [](const PyEngine& p) { return p.e->batch(); })
      .def_property_readonly("nodes", [](const PyEngine& p) { return p.e->nodes(); })
      .def_property_readonly("precision", [](const PyEngine& p) { return gpu::to_string(p.e->precision()); })
      .def_property_readonly("kernel",
                             [](const PyEngine& p) {
                               return p.e->kernel() == gpu::Options::Kernel::PerBlock ? "block" : "grid";
                             })
      .def_property_readonly(
          "time", [](const PyEngine& p) { return p.e->time(); }, "ms")
      .def_property_readonly(
          "origin",
          [](PyEngine& p) {
            const gpu::Engine::DeviceState d = p.e->device_state();
            py::array_t<double> o({static_cast<py::ssize_t>(d.batch), py::ssize_t{3}});
            std::copy(d.origin, d.origin + 3 * d.batch, o.mutable_data());
            return o;
          },
          "(B, 3): the device positions handed over by DLPack are x - origin (0 in fp64; the rest shape's "
          "centre in fp32).")
      .def_property_readonly(
          "substeps", [](const PyEngine& p) { return p.e->substeps(); },
          "The batch's substeps: per frame the most any model took.")
      .def(
          "model_substeps", [](const PyEngine& p, int b) { return p.e->substeps(b); }, "b"_a,
          "Model b's substeps (each model takes its own, as its CPU run).")
      .def(
          "set_loads",
          [](PyEngine& p, int b, const std::vector<PointLoad>& loads) { p.e->set_loads(b, loads); }, "b"_a,
          "loads"_a, "PointLoads of model b (model node indices), held until changed.")
      .def(
          "step",
          [](PyEngine& p, long frames) {
            require(frames >= 0, "frames: must be >= 0 (got ", frames, ")");
            py::gil_scoped_release release;
            StepStatus worst, last;
            for (long f = 0; f < frames; ++f) {
              last = p.e->step();
              if (last.code != StepCode::Ok) worst = last;
            }
            return worst.code != StepCode::Ok ? worst : last;
          },
          "frames"_a = 1, "Advances every model by `frames` frames (GIL released); the worst status.")
      .def(
          "positions", [](PyEngine& p) { return batch_array(*p.e, false); },
          "(B, N, 3) float64 copy of every model's positions, mm.")
      .def(
          "velocities", [](PyEngine& p) { return batch_array(*p.e, true); },
          "(B, N, 3) float64 copy of every model's velocities, mm/ms.")
      .def(
          "upload",
          [](PyEngine& p, py::handle x, py::handle v) {
            const int B = p.e->batch();
            const Index n = p.e->nodes();
            const py::array_t<double> X = batch_arg(x, "x", B, n);
            std::optional<py::array_t<double>> V;
            if (!v.is_none()) V = batch_arg(v, "v", B, n);
            for (int b = 0; b < B; ++b) {
              State s;
              s.x = Eigen::Map<const MatX3>(X.data() + static_cast<std::size_t>(b) * 3 * n, n, 3);
              s.v = V ? MatX3(Eigen::Map<const MatX3>(V->data() + static_cast<std::size_t>(b) * 3 * n, n, 3))
                      : MatX3(MatX3::Zero(n, 3));
              s.t = p.e->time();
              s.stiffening = p.e->stiffening(b);
              p.e->upload(b, s);
            }
          },
          "x"_a, "v"_a = py::none(),
          "Sets every model's positions (and velocities, else zero) from (B, N, 3).")
      .def(
          "request_node", [](PyEngine& p, int b, Index node) { p.e->request_node(b, node); }, "b"_a, "node"_a,
          "Enqueues an asynchronous read of one node's position (the haptic read).")
      .def(
          "poll_node",
          [](PyEngine& p) -> py::object {
            Vec3 out;
            if (!p.e->poll_node(out)) return py::none();
            return copy_of(out);
          },
          "The newest finished request_node() read as a (3,) array, or None (never waits).")
      .def(
          "__dlpack__", [](py::object self, py::args, py::kwargs) { return dlpack(self, false); },
          "DLPack capsule of the device positions (B, N, 3), zero-copy, after the engine's work has finished "
          "(stream, max_version, ... accepted: a legacy 'dltensor' capsule is returned); valid until the "
          "next step().")
      .def("__dlpack_device__",
           [](const PyEngine& p) { return py::make_tuple(kDLCUDA, p.e->device().index); })
      .def(
          "velocities_dlpack", [](py::object self) { return dlpack(self, true); },
          "DLPack capsule of the device velocities (B, N, 3); valid until the next step().");
}

}  // namespace medspring::python
