// The host side of the per-frame trace values (physics/trace_kernels.hpp): what each model of a batch
// samples (TraceProbe, made from a scene run by scene/batch.hpp's trace_probe), packed into the arrays of
// an hd::TraceTable (shared by the batch where equal), and their values from a model's positions on the
// CPU with the same hd:: code the GPU's reduction runs (src/gpu/sample.cu, docs/gpu.md).
//
//   TraceTableData t = make_trace_table(probes);          // one probe per model, equal surface counts
//   std::vector<double> v(t.width());
//   trace_values(t, b, x, v.data());                      // [max |u| over the surface, |u| of each point]
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/core/types.hpp"
#include "medspring/physics/trace_kernels.hpp"

namespace medspring {

/// One model's sampled values: its surface (the DOF row of each surface node and the rest surface) and
/// its traced points (a DOF row and a rest position each).
struct TraceProbe {
  std::vector<Index> surface_dof;
  MatX3 surface_rest;
  std::vector<Index> point_dof;
  MatX3 point_rest;
};

/// The arrays of an hd::TraceTable in host memory.
struct TraceTableData {
  int batch = 0, surface = 0, points = 0;
  Index nodes = 0;                          // DOF rows per model
  std::vector<int> surface_dof, point_dof;  // surface_dof: one model's, or every model's (strides)
  std::vector<double> surface_rest, point_rest;
  long long dof_stride = 0, rest_stride = 0;
  int width() const { return 1 + points; }
  /// The table over these host arrays.
  hd::TraceTable view() const {
    return {batch,       surface, surface_dof.data(), surface_rest.data(), dof_stride,
            rest_stride, points,  point_dof.data(),   point_rest.data()};
  }
};

/// Packs one probe per model: the surface arrays once when every model's equal model 0's, the points
/// padded to the most any model has (DOF -1). InvalidInput for surfaces of different sizes, a DOF outside
/// [0, nodes) or mismatched rows.
inline TraceTableData make_trace_table(const std::vector<TraceProbe>& probes, Index nodes) {
  require(!probes.empty(), "trace table: no model");
  TraceTableData t;
  t.batch = static_cast<int>(probes.size());
  t.nodes = nodes;
  const TraceProbe& p0 = probes.front();
  t.surface = static_cast<int>(p0.surface_dof.size());
  bool shared = true;
  for (std::size_t b = 0; b < probes.size(); ++b) {
    const TraceProbe& p = probes[b];
    require(p.surface_dof.size() == p0.surface_dof.size(), "trace table: model ", b, " has ",
            p.surface_dof.size(), " surface nodes, model 0 ", p0.surface_dof.size());
    require(p.surface_rest.rows() == static_cast<Index>(p.surface_dof.size()) &&
                p.point_rest.rows() == static_cast<Index>(p.point_dof.size()),
            "trace table: model ", b, ": rest rows differ from the DOF rows");
    for (const std::vector<Index>* v : {&p.surface_dof, &p.point_dof})
      for (Index d : *v)
        require(d >= 0 && d < nodes, "trace table: model ", b, ": DOF ", d, " outside [0, ", nodes, ")");
    shared = shared && p.surface_dof == p0.surface_dof && p.surface_rest == p0.surface_rest;
    t.points = std::max(t.points, static_cast<int>(p.point_dof.size()));
  }
  const std::size_t copies = shared ? 1 : probes.size(), S = p0.surface_dof.size();
  t.dof_stride = shared ? 0 : static_cast<long long>(S);
  t.rest_stride = 3 * t.dof_stride;
  t.surface_dof.reserve(copies * S);
  t.surface_rest.reserve(3 * copies * S);
  for (std::size_t b = 0; b < copies; ++b)
    for (std::size_t s = 0; s < S; ++s) {
      t.surface_dof.push_back(static_cast<int>(probes[b].surface_dof[s]));
      for (int d = 0; d < 3; ++d) t.surface_rest.push_back(probes[b].surface_rest(static_cast<Index>(s), d));
    }
  const auto P = static_cast<std::size_t>(t.points);
  t.point_dof.assign(probes.size() * P, -1);
  t.point_rest.assign(3 * probes.size() * P, 0.0);
  for (std::size_t b = 0; b < probes.size(); ++b)
    for (std::size_t q = 0; q < probes[b].point_dof.size(); ++q) {
      t.point_dof[b * P + q] = static_cast<int>(probes[b].point_dof[q]);
      for (int d = 0; d < 3; ++d)
        t.point_rest[3 * (b * P + q) + static_cast<std::size_t>(d)] =
            probes[b].point_rest(static_cast<Index>(q), d);
    }
  return t;
}

/// Model b's values from its positions x (n x 3, in mm) on the CPU: hd::trace_sample, the device's code.
inline void trace_values(const TraceTableData& t, int b, const MatX3& x, double* out) {
  require(b >= 0 && b < t.batch, "trace_values: model ", b, " out of range (batch of ", t.batch, ")");
  require(x.rows() == t.nodes, "trace_values: positions of ", x.rows(), " nodes for models of ", t.nodes);
  const double origin[3] = {0.0, 0.0, 0.0};  // MatX3 is the engine's layout: n x 3 row-major
  hd::trace_sample(t.view(), b, x.data(), origin, out);
}

}  // namespace medspring
