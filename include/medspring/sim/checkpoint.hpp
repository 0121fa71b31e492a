// Checkpoints of a running Simulation: a versioned, checksummed binary file, written atomically, from
// which a run resumes bit-for-bit (docs/reliability.md describes the format).
//
//   save_checkpoint("run.mscp", sim);        // temp file + rename: the old file or the new, never half
//   ...
//   Simulation again(body);                  // the same model (checked by fingerprint)
//   restore_checkpoint("run.mscp", again);   // state, loads and step settings as saved
//   again.update();                          // == sim.update() bit for bit
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "medspring/core/binary.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/physics/state.hpp"
#include "medspring/sim/simulation.hpp"

namespace medspring {

/// File magic (8 bytes) and the format version this build writes.
inline constexpr char kCheckpointMagic[9] = "MSPRCKPT";
/// Version 2 added the application section `extra`; version 1 files are still read.
inline constexpr std::uint32_t kCheckpointVersion = 2;

/// Everything a checkpoint holds. `state` carries x, v, f_ext, t, frames, substeps, stiffening,
/// warnings and the implicit warm start dv; its other scratch is rebuilt by make_state (step_coef is a
/// pure function of the step and is recomputed identically).
struct Checkpoint {
  std::uint64_t fingerprint = 0;  // model_fingerprint of the simulated model
  std::string model_name;         // Model::name (reported in errors)
  std::string body_kind;          // Body::kind(): "surface", "hybrid" or "smrm"
  StepSettings step;              // the step settings the run used (restored with the state)
  State state;
  std::vector<PointLoad> loads;  // the load schedule (absolute times, ms)
  /// Application section, opaque to the engine (e.g. the CLI's traces so far); at most 1 GiB.
  std::string extra;
};

/// Snapshot of a simulation (no I/O).
Checkpoint make_checkpoint(const Simulation& sim);

/// The file bytes of a checkpoint: header (magic, version, payload size, FNV-1a 64 of the payload)
/// + payload, little-endian.
std::string encode_checkpoint(const Checkpoint& checkpoint);

/// Parses file bytes. Throws IoError "<what>: ..." when they are truncated, corrupted (checksum),
/// of another version or malformed. Does not check the model (see apply_checkpoint).
Checkpoint decode_checkpoint(std::string_view bytes, const std::string& what = "checkpoint");

/// Puts a checkpoint into a simulation: step settings (the local and normals options are kept),
/// loads and state. Throws InvalidInput "<what>: ..." when it was saved from another model (fingerprint,
/// node count or body kind differ) or its contents are invalid; the simulation is unchanged then.
void apply_checkpoint(const Checkpoint& checkpoint, Simulation& sim, const std::string& what = "checkpoint");

/// Writes a checkpoint of `sim` to `path` atomically: the bytes go to a temporary file beside it which
/// is then renamed over `path`. On failure the temporary file is removed, `path` is left as it was and
/// IoError names the file.
void save_checkpoint(const std::filesystem::path& path, const Simulation& sim);

/// Reads and decodes a checkpoint file (IoError naming the file when missing, truncated, corrupted or
/// of another version).
Checkpoint read_checkpoint(const std::filesystem::path& path);

/// read_checkpoint + apply_checkpoint: resumes `sim` from the file. The next update() gives the same
/// bits as the update after the save in the original run.
void restore_checkpoint(const std::filesystem::path& path, Simulation& sim);

}  // namespace medspring
