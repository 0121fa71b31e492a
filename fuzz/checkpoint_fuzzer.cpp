// Fuzz target: checkpoints (sim/checkpoint.hpp). The bytes are decoded as they are, and again with the
// frame header (size, checksum) rewritten for the bytes after it, so that mutations reach the payload
// parser instead of stopping at the checksum. A decoded checkpoint is applied to the fuzz model with
// the same fingerprint (tube, hybrid kidney or vessel phantom; models.hpp); an applied one must leave a
// finite state that steps finitely. Accepted rejections: IoError / InvalidInput.
#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "medspring/core/binary.hpp"
#include "medspring/core/check.hpp"
#include "medspring/sim/checkpoint.hpp"
#include "models.hpp"

using namespace medspring;

namespace {

struct Fixture {
  std::vector<std::unique_ptr<Simulation>> sims;
  std::vector<Checkpoint> pristine;
  Fixture() {
    for (const BodyPtr& b : fuzz::fuzz_bodies()) {
      sims.push_back(std::make_unique<Simulation>(b));
      pristine.push_back(make_checkpoint(*sims.back()));
    }
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

bool finite_state(const State& s) {
  return s.x.allFinite() && s.v.allFinite() && std::isfinite(s.t);
}

void try_apply(const Checkpoint& c) {
  Fixture& f = fixture();
  std::size_t k = 0;
  while (k + 1 < f.sims.size() && model_fingerprint(f.sims[k]->model()) != c.fingerprint) ++k;
  Simulation& sim = *f.sims[k];
  const std::string before = encode_checkpoint(make_checkpoint(sim));
  if (fuzz::accepts([&] { apply_checkpoint(c, sim, "fuzz"); })) {
    MEDSPRING_FUZZ_CHECK(finite_state(sim.state()), "applied checkpoint left a non-finite state");
    const StepSettings& s = sim.settings().step;
    // A few updates when the settings keep them cheap (max_substeps may legitimately be 2^31 - 1).
    if (s.max_substeps <= 64 && s.cg_max_iterations <= 400 && s.newton_iterations <= 4 &&
        s.max_rollbacks <= 8) {
      for (int i = 0; i < 3; ++i) sim.update();
      MEDSPRING_FUZZ_CHECK(finite_state(sim.state()), "a restored simulation stepped to a non-finite state");
      MEDSPRING_FUZZ_CHECK(sim.surface().allFinite(), "non-finite surface after restoring");
    }
  } else {
    const std::string after = encode_checkpoint(make_checkpoint(sim));
    MEDSPRING_FUZZ_CHECK(before == after, "a rejected checkpoint changed the simulation");
  }
  apply_checkpoint(f.pristine[k], sim, "pristine");
}

void try_decode(std::string_view bytes) {
  Checkpoint c;
  if (fuzz::accepts([&] { c = decode_checkpoint(bytes, "fuzz"); })) try_apply(c);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::decode_framed(data, size, kCheckpointMagic, kCheckpointVersion, try_decode);
  return 0;
}
