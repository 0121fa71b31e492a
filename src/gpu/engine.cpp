// The GPU engine's public face (medspring/gpu/engine.hpp): argument checks that need no device, then the
// backend of the chosen precision (backend.hpp). Device queries and errors: device.cpp; the frame loop:
// frame.cpp; the kernels: kernels.cu.
#include "medspring/gpu/engine.hpp"

#include <algorithm>

#include "backend.hpp"
#include "medspring/core/check.hpp"

namespace medspring::gpu {

using detail::Backend;
using detail::kCpuAlternative;

Engine::Engine(const std::vector<const Model*>& models, const StepSettings& settings,
               const Options& options) {
  require(!models.empty(), "gpu::Engine: no model given");
  require(models.size() <= 65535, "gpu::Engine: a batch holds at most 65535 models (got ", models.size(),
          "); split it into several engines");
  for (std::size_t b = 0; b < models.size(); ++b) {
    require(models[b] != nullptr, "gpu::Engine: model ", b, " is null");
    require(models[b]->finalized, models[b]->name,
            ": model is not finalized (call finalize or ModelBuilder::build)");
    if (models[b]->bending.size() > 0)
      throw GpuError(cat("GPU: model '", models[b]->name, "' has bending terms (", models[b]->bending.size(),
                         "), which the GPU path does not have; use ", kCpuAlternative));
    if (models[b]->volume.size() > 0)
      throw GpuError(cat("GPU: model '", models[b]->name, "' has volume terms (", models[b]->volume.size(),
                         " tetrahedra), which the GPU path does not have; use ", kCpuAlternative));
    if (models[b]->compression.size() > 0)
      throw GpuError(cat("GPU: model '", models[b]->name, "' has compression-stiffening terms (",
                         models[b]->compression.size(), "), which the GPU path does not have; use ",
                         kCpuAlternative));
    if (models[b]->thin.size() > 0)
      throw GpuError(cat("GPU: model '", models[b]->name, "' has thin-tetrahedron terms (",
                         models[b]->thin.size(), "), which the GPU path does not have; use ",
                         kCpuAlternative));
    validate_step_settings(*models[b], settings);
  }
  if (settings.integrator != Integrator::SymplecticEuler)
    throw GpuError(cat("GPU: the ", to_string(settings.integrator),
                       " integrator is not ported to the GPU path (symplectic_euler is); use ",
                       kCpuAlternative));
  if (settings.stable_step != StableStep::Bound)
    throw GpuError(cat("GPU: the stable_step rule '", to_string(settings.stable_step),
                       "' is not ported to the GPU path ('bound' is); use ", kCpuAlternative));
  require(options.block >= 32 && options.block <= 1024 && options.block % 32 == 0,
          "gpu::Options::block: must be a multiple of 32 in 32..1024 (got ", options.block, ")");
  require(options.gather_batch == 0 || options.gather_batch == 1 || options.gather_batch == 2 ||
              options.gather_batch == 4,
          "gpu::Options::gather_batch: must be 0 (automatic), 1, 2 or 4 (got ", options.gather_batch, ")");
  require(options.models_per_thread == 0 || options.models_per_thread == 1 ||
              options.models_per_thread == 2 || options.models_per_thread == 4,
          "gpu::Options::models_per_thread: must be 0 or 1 (one model per thread), 2 or 4 (got ",
          options.models_per_thread, ")");
  require(options.compact_max_classes >= 1 && options.compact_max_classes <= 65536,
          "gpu::Options::compact_max_classes: must be in 1..65536 (got ", options.compact_max_classes, ")");
  const DeviceInfo dev = require_device(options.device);
  if (options.precision == Precision::Double)
    impl_ = std::make_unique<Backend<double>>(models, settings, options, dev);
  else
    impl_ = std::make_unique<Backend<float>>(models, settings, options, dev);
}

Engine::~Engine() = default;

PackReport Engine::pack_report() const {
  return impl_->pack;
}
std::string Engine::packed_table_note() const {
  return impl_->pack_note;
}

int Engine::batch() const {
  return static_cast<int>(impl_->models.size());
}
Options::Kernel Engine::kernel() const {
  return impl_->kernel;
}
Index Engine::nodes() const {
  return impl_->models[0]->num_nodes();
}
const DeviceInfo& Engine::device() const {
  return impl_->device;
}
const StepSettings& Engine::settings() const {
  return impl_->settings;
}
Precision Engine::precision() const {
  return impl_->precision;
}
void Engine::set_loads(int b, const std::vector<PointLoad>& loads) {
  impl_->set_loads(b, loads);
}
void Engine::upload(int b, const State& state) {
  impl_->upload(b, state);
}
StepStatus Engine::step() {
  return impl_->step();
}
MatX3 Engine::positions(int b) const {
  return impl_->fetch(b, false);
}
MatX3 Engine::velocities(int b) const {
  return impl_->fetch(b, true);
}
void Engine::request_positions() {
  impl_->request_positions();
}
bool Engine::poll_positions(int b, MatX3& out) {
  return impl_->poll_positions(b, out);
}
void Engine::request_node(int b, Index node) {
  impl_->request_node(b, node);
}
bool Engine::poll_node(Vec3& out) {
  return impl_->poll_node(out);
}
Engine::DeviceState Engine::device_state() {
  return impl_->device_state();
}
void Engine::set_trace_probes(const std::vector<TraceProbe>& probes) {
  impl_->set_trace_probes(probes);
}
int Engine::trace_width() const {
  return impl_->trace_width();
}
void Engine::request_traces() {
  impl_->request_traces();
}
void Engine::traces(std::vector<double>& out) {
  impl_->traces(out);
}
double Engine::time() const {
  return impl_->t;
}
double Engine::stiffening() const {
  return *std::max_element(impl_->stiffening.begin(), impl_->stiffening.end());
}

double Engine::stiffening(int b) const {
  require(b >= 0 && b < batch(), "gpu::Engine::stiffening: model ", b, " out of range (batch of ", batch(),
          ")");
  return impl_->stiffening[static_cast<std::size_t>(b)];
}

std::uint64_t Engine::substeps(int b) const {
  require(b >= 0 && b < batch(), "gpu::Engine::substeps: model ", b, " out of range (batch of ", batch(),
          ")");
  return impl_->model_substeps[static_cast<std::size_t>(b)];
}
std::uint64_t Engine::frames() const {
  return impl_->frames;
}
std::uint64_t Engine::substeps() const {
  return impl_->substeps;
}
const Warnings& Engine::warnings() const {
  return impl_->warnings;
}
std::size_t Engine::device_bytes() const {
  return impl_->device_bytes();
}
double Engine::time_substeps(int count, int repeats) {
  return impl_->time_substeps(count, repeats);
}

}  // namespace medspring::gpu
