// Refusing work that cannot fit in memory before allocating it (issue 15, bad input): a model too large
// for the machine gets one clear line instead of std::bad_alloc, an index overflow or the OOM killer.
#pragma once

#include <cstdint>
#include <string>

namespace medspring {

/// Memory this process may use, in bytes: the machine's physical memory, lowered to a cgroup (container)
/// limit when one is set; 0 when unknown (then nothing is refused). MEDSPRING_MEMORY_LIMIT_MB overrides it.
std::uint64_t usable_memory_bytes();

/// Throws InvalidInput "<what>: needs about X GB of memory, more than the Y GB this machine has" when
/// `bytes` exceeds usable_memory_bytes() (never when that is unknown).
void require_memory(double bytes, const std::string& what);

/// Throws InvalidInput "<what>: <count> is too large (indices are 32-bit: at most 2147483647)" when a
/// count does not fit an Index.
void require_index_count(double count, const std::string& what);

}  // namespace medspring
