// Fuzz target: model packages (models/model_package.hpp), the web model format. The bytes are decoded
// as they are and again with the frame header rewritten (see checkpoint_fuzzer.cpp). A decoded package
// is rebuilt with make_body; a rebuilt body must have a finite rest state and survive a short
// simulation finitely. Accepted rejections: IoError / InvalidInput.
#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "medspring/core/binary.hpp"
#include "medspring/core/check.hpp"
#include "medspring/models/model_package.hpp"
#include "medspring/sim/simulation.hpp"

using namespace medspring;

namespace {

void try_decode(std::string_view bytes) {
  ModelPackage p;
  if (!fuzz::accepts([&] { p = decode_model_package(bytes, "fuzz"); })) return;
  BodyPtr body;
  if (!fuzz::accepts([&] { body = make_body(p); })) return;
  MEDSPRING_FUZZ_CHECK(body != nullptr, "make_body returned null");
  const Model& m = body->model();
  MEDSPRING_FUZZ_CHECK(m.x0.allFinite(), "rebuilt model has non-finite rest positions");
  (void)check_fingerprint(p, *body);
  (void)tissue_params(p);
  // Step only bodies of modest size (the target must stay fast).
  if (m.num_nodes() > 2000 || m.num_springs() > 12000) return;
  Simulation sim(body);
  for (int i = 0; i < 2; ++i) sim.update();
  MEDSPRING_FUZZ_CHECK(sim.state().x.allFinite() && sim.surface().allFinite(),
                       "a rebuilt model stepped to a non-finite state");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::decode_framed(data, size, kModelPackageMagic, kModelPackageVersion, try_decode);
  return 0;
}
