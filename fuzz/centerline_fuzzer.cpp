// Fuzz target: read_centerlines (io/centerline_io.hpp). Inputs that start with "# vtk" are written as a
// legacy .vtk file, the others as .vtp. Accepted: IoError / InvalidInput. Every accepted line must have
// >= 2 finite points and one finite radius > 0 per point.
#include <cmath>
#include <cstring>

#include "fuzz_support.hpp"
#include "medspring/core/check.hpp"
#include "medspring/io/centerline_io.hpp"

using namespace medspring;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const bool legacy = size >= 5 && std::memcmp(data, "# vtk", 5) == 0;
  const auto path = fuzz::write_scratch(data, size, legacy ? ".vtk" : ".vtp");
  std::vector<Centerline> lines;
  if (!fuzz::accepts([&] { lines = read_centerlines(path, LengthUnit::Centimetre); })) return 0;
  MEDSPRING_FUZZ_CHECK(!lines.empty(), "no lines");
  for (const Centerline& c : lines) {
    MEDSPRING_FUZZ_CHECK(c.size() >= 2, c.name);
    MEDSPRING_FUZZ_CHECK(c.points.allFinite(), c.name);
    MEDSPRING_FUZZ_CHECK(c.radii.size() == c.size() && c.radii.allFinite() && (c.radii.array() > 0).all(),
                         c.name);
  }
  return 0;
}
