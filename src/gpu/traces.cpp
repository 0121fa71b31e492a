// The device-side trace reduction of the GPU engine (Engine::set_trace_probes / request_traces / traces,
// docs/gpu.md "Study runs on the GPU"): the probes' table uploaded once, then per request one launch of
// the reduction kernel (sample.cu) on the compute stream and a copy of its B x width doubles to pinned
// host memory.
#include "backend.hpp"
#include "medspring/core/check.hpp"

namespace medspring::gpu::detail {

template <class R>
void Backend<R>::set_trace_probes(const std::vector<TraceProbe>& probes) {
  require(static_cast<int>(probes.size()) == B, "gpu::Engine::set_trace_probes: ", probes.size(),
          " probes for a batch of ", B);
  const TraceTableData table = make_trace_table(probes, n);
  check(cudaStreamSynchronize(stream), "finishing the work in flight");  // a request may read the old table
  trace.surface_dof.assign(table.surface_dof, "allocating the trace table", "uploading the trace table");
  trace.surface_rest.assign(table.surface_rest, "allocating the trace table", "uploading the trace table");
  trace.point_dof.assign(table.point_dof, "allocating the trace table", "uploading the trace table");
  trace.point_rest.assign(table.point_rest, "allocating the trace table", "uploading the trace table");
  trace.origin.assign(origin, "allocating the trace table", "uploading the trace table");
  const std::size_t values = static_cast<std::size_t>(B) * static_cast<std::size_t>(table.width());
  trace.out.allocate(values, "allocating the trace values");
  trace.host.allocate(values, "allocating pinned memory for the trace values");
  if (!trace.done) check(cudaEventCreateWithFlags(&trace.done, cudaEventDisableTiming), "creating an event");
  trace.requested = false;
  hd::TraceTable T = table.view();
  T.surface_dof = trace.surface_dof.p;
  T.surface_rest = trace.surface_rest.p;
  T.point_dof = trace.point_dof.p;
  T.point_rest = trace.point_rest.p;
  trace.table = T;
}

template <class R>
void Backend<R>::request_traces() {
  require(trace.table.batch == B, "gpu::Engine::request_traces: no trace probes (set_trace_probes first)");
  check(cudaMemsetAsync(trace.out.p, 0, trace.out.n * sizeof(double), stream), "resetting the trace values");
  check(launch_trace_sample<R>(trace.table, xb[cur].p, 3 * static_cast<long long>(n), trace.origin.p,
                               trace.out.p, stream),
        "launching the trace reduction");
  check(cudaMemcpyAsync(trace.host.p, trace.out.p, trace.out.n * sizeof(double), cudaMemcpyDeviceToHost,
                        stream),
        "reading back the trace values");
  check(cudaEventRecord(trace.done, stream), "ordering the trace readback");
  trace.requested = true;
}

template <class R>
void Backend<R>::traces(std::vector<double>& out) {
  require(trace.requested, "gpu::Engine::traces: nothing requested (request_traces first)");
  check(cudaEventSynchronize(trace.done), "reducing the traces");
  out.assign(trace.host.p, trace.host.p + trace.out.n);
}

template struct Backend<double>;
template struct Backend<float>;

}  // namespace medspring::gpu::detail
