// Fuzz target: read_mesh_with_report (io/mesh_io.hpp) on one mesh format, chosen at link time by
// fuzz::kExtension (".obj", ".stl", ".ply", ".vtp", ".vtk": one generated source per target,
// fuzz/CMakeLists.txt). The bytes go to a scratch file with that extension. Accepted: IoError / InvalidInput.
// A result must be a finite mesh with valid indices.
#include <cmath>

#include "fuzz_support.hpp"
#include "medspring/core/check.hpp"
#include "medspring/io/mesh_io.hpp"

using namespace medspring;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = fuzz::write_scratch(data, size, fuzz::kExtension);
  MeshReadResult r;
  if (!fuzz::accepts([&] { r = read_mesh_with_report(path); })) return 0;
  const SurfaceMesh& m = r.mesh;
  MEDSPRING_FUZZ_CHECK(m.num_faces() > 0 && m.num_vertices() > 0, cat(m.num_vertices(), " vertices"));
  MEDSPRING_FUZZ_CHECK(m.V.allFinite(), "non-finite vertex coordinates");
  MEDSPRING_FUZZ_CHECK(m.F.size() == 0 || (m.F.minCoeff() >= 0 && m.F.maxCoeff() < m.num_vertices()),
                       "face index out of range");
  MEDSPRING_FUZZ_CHECK(r.report.bad_indices == 0 && r.report.nonfinite_vertices == 0, "report");
  return 0;
}
