// Fuzz target: parse_frd (fem/frd.hpp), the reader of CalculiX result files. Accepted: IoError. A result
// must have unique positive node ids, finite coordinates and one finite displacement per node in every
// DISP block; last_displacement must then either succeed with finite values or throw IoError.
#include <cmath>
#include <set>
#include <string_view>

#include "fuzz_support.hpp"
#include "medspring/core/check.hpp"
#include "medspring/fem/frd.hpp"

using namespace medspring;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  fem::FrdData d;
  if (!fuzz::accepts([&] { d = fem::parse_frd(text, "fuzz.frd"); })) return 0;
  const std::set<Index> ids(d.ids.begin(), d.ids.end());
  MEDSPRING_FUZZ_CHECK(ids.size() == d.ids.size(), "repeated node ids");
  MEDSPRING_FUZZ_CHECK(ids.empty() || *ids.begin() > 0, "non-positive node id");
  MEDSPRING_FUZZ_CHECK(d.X.rows() == static_cast<Eigen::Index>(d.ids.size()) && d.X.allFinite(),
                       "node block");
  for (const auto& b : d.disp)
    MEDSPRING_FUZZ_CHECK(b.u.rows() == d.X.rows() && b.u.allFinite() && std::isfinite(b.time), "DISP block");
  MatX3 u;
  if (fuzz::accepts([&] { u = fem::last_displacement(d, static_cast<Index>(d.ids.size()), 1.0); }))
    MEDSPRING_FUZZ_CHECK(u.allFinite(), "last displacement");
  return 0;
}
