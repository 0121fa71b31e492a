#include "medspring/core/memory.hpp"

#include <cstdlib>
#include <fstream>
#include <limits>

#include "medspring/core/check.hpp"

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#endif

namespace medspring {

std::uint64_t usable_memory_bytes() {
  if (const char* env = std::getenv("MEDSPRING_MEMORY_LIMIT_MB"); env && *env) {
    char* end = nullptr;
    const unsigned long long mb = std::strtoull(env, &end, 10);
    if (end && *end == '\0' && mb > 0) return static_cast<std::uint64_t>(mb) << 20;
  }
  std::uint64_t bytes = 0;
#if (defined(__unix__) || defined(__APPLE__)) && !defined(__EMSCRIPTEN__)
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page > 0) bytes = static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page);
  std::ifstream cg("/sys/fs/cgroup/memory.max");  // cgroup v2 limit ("max" when none)
  unsigned long long limit = 0;
  if (cg >> limit && limit > 0 && (bytes == 0 || limit < bytes)) bytes = limit;
#endif
  return bytes;
}

void require_memory(double bytes, const std::string& what) {
  const std::uint64_t have = usable_memory_bytes();
  if (have == 0 || !(bytes > static_cast<double>(have))) return;
  const double gb = 1024.0 * 1024.0 * 1024.0;
  throw InvalidInput(cat(what, ": needs about ", std::round(bytes / gb * 10) / 10,
                         " GB of memory, more than the ",
                         std::round(static_cast<double>(have) / gb * 10) / 10, " GB this machine has"));
}

void require_index_count(double count, const std::string& what) {
  constexpr double most = static_cast<double>(std::numeric_limits<Index>::max());
  require(count <= most, what, ": ", count, " is too large (indices are 32-bit: at most ", most, ")");
}

}  // namespace medspring
