// One heap-allocation counter for the "no allocation in the update loop" tests (DESIGN.md). Link
// alloc_counter.cpp into the test executable: it replaces the global operator new (every form) and
// interposes glibc's malloc family (Eigen allocates with malloc), so every heap allocation of the
// process is counted. Off (counting() false) under AddressSanitizer, which owns the allocator, and
// without glibc; the tests skip then.
#pragma once

namespace medspring::testing {

/// True when heap_allocations() counts (glibc, no sanitizer).
bool counting_allocations();

/// Heap allocations of the process so far (operator new, malloc, calloc, realloc, aligned).
long heap_allocations();

}  // namespace medspring::testing
