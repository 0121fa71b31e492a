// Shared helpers of the fuzz targets (fuzz/README.md): a scratch file per process for the readers that
// take a path, the rule for what counts as a clean rejection, and checks on accepted results.
//
// Every target defines LLVMFuzzerTestOneInput. Built with clang -fsanitize=fuzzer it is a libFuzzer
// binary; built with fuzz/replay_main.cpp (any compiler) it is a replay driver that feeds files and
// folders to it (the `fuzz-regression` CTest tests).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <string_view>
#include <typeinfo>

#include "medspring/core/binary.hpp"
#include "medspring/core/error.hpp"

namespace medspring::fuzz {

/// A folder private to this process (under $MEDSPRING_FUZZ_TMP, /dev/shm or the system temp folder),
/// created on first use and removed at exit.
const std::filesystem::path& scratch_dir();

/// The extension of the scratch file of a target that reads one of several formats through the same source
/// (mesh_fuzzer.cpp, volume_fuzzer.cpp): defined per target in a generated source (fuzz/CMakeLists.txt,
/// medspring_fuzz_target's EXT).
extern const char* const kExtension;

/// Writes `data` to scratch_dir()/"input<ext>" (replacing it) and returns the path.
std::filesystem::path write_scratch(const std::uint8_t* data, std::size_t size, const std::string& ext);

/// Reports a bug found by a target and aborts (libFuzzer saves the input as a crash).
[[noreturn]] void report_bug(const char* what, const std::string& detail);

/// True when MEDSPRING_FUZZ_VERBOSE is set: accepts() prints every rejection message to stderr.
bool verbose();

/// Runs `f`: a medspring::Error is a clean rejection (returns false); any other exception is a bug
/// (report_bug). Returns true when `f` accepted the input.
template <class F>
bool accepts(F&& f) {
  try {
    f();
    return true;
  } catch (const Error& e) {
    if (verbose()) std::fprintf(stderr, "rejected: %s\n", e.what());
    return false;
  } catch (const std::exception& e) {
    report_bug("a non-MedSpring exception escaped", std::string(typeid(e).name()) + ": " + e.what());
  } catch (...) {
    report_bug("a non-std exception escaped", "(unknown type)");
  }
}

/// For the framed binary formats (checkpoints, model packages): `decode` runs on the bytes as they are
/// and, when they start with `magic`, once more with the frame header (size, checksum) rewritten to
/// match the payload, so that mutations reach the payload parser instead of stopping at the checksum.
template <class Decode>
void decode_framed(const std::uint8_t* data, std::size_t size, const char* magic, std::uint32_t version,
                   Decode&& decode) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  decode(bytes);
  if (size >= kFrameHeaderSize && bytes.substr(0, 8) == std::string_view(magic, 8)) {
    const std::string framed = frame_payload(magic, version, std::string(bytes.substr(kFrameHeaderSize)));
    if (framed != bytes) decode(std::string_view(framed));
  }
}

}  // namespace medspring::fuzz

/// Aborts with a message when an accepted result breaks a promise of the API (e.g. a NaN coordinate).
#define MEDSPRING_FUZZ_CHECK(cond, detail)                                                 \
  do {                                                                                     \
    if (!(cond)) ::medspring::fuzz::report_bug("accepted input breaks: " #cond, (detail)); \
  } while (0)
