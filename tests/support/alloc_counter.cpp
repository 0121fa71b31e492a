// The heap-allocation counter of alloc_counter.hpp: a replaced global operator new and counting
// wrappers around glibc's malloc family. operator new calls glibc's allocator directly, so an
// allocation is counted once.
#include "alloc_counter.hpp"

#include <cstdlib>  // defines __GLIBC__
#include <new>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define MEDSPRING_COUNT_ALLOCATIONS 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define MEDSPRING_COUNT_ALLOCATIONS 0
#endif
#endif
#ifndef MEDSPRING_COUNT_ALLOCATIONS
#if defined(__GLIBC__)
#define MEDSPRING_COUNT_ALLOCATIONS 1
#else
#define MEDSPRING_COUNT_ALLOCATIONS 0
#endif
#endif

#if MEDSPRING_COUNT_ALLOCATIONS

#include <atomic>
#include <cerrno>
#include <cstddef>

namespace {
std::atomic<long> g_allocations{0};
void count() {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);

void* malloc(std::size_t n) noexcept {
  count();
  return __libc_malloc(n);
}
void* calloc(std::size_t a, std::size_t b) noexcept {
  count();
  return __libc_calloc(a, b);
}
void* realloc(void* p, std::size_t n) noexcept {
  count();
  return __libc_realloc(p, n);
}
void* aligned_alloc(std::size_t a, std::size_t n) noexcept {
  count();
  return __libc_memalign(a, n);
}
void* memalign(std::size_t a, std::size_t n) noexcept {
  count();
  return __libc_memalign(a, n);
}
int posix_memalign(void** p, std::size_t a, std::size_t n) noexcept {
  count();
  *p = __libc_memalign(a, n);
  return *p ? 0 : ENOMEM;
}
}

namespace {
void* counted_new(std::size_t n) {
  count();
  if (void* p = __libc_malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* counted_new_aligned(std::size_t n, std::align_val_t a) {
  count();
  if (void* p = __libc_memalign(static_cast<std::size_t>(a), n ? n : 1)) return p;
  throw std::bad_alloc();
}
}  // namespace

// Every replaceable allocation form; the matching deletes are glibc's free (the default ones).
void* operator new(std::size_t n) {
  return counted_new(n);
}
void* operator new[](std::size_t n) {
  return counted_new(n);
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  count();
  return __libc_malloc(n ? n : 1);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  count();
  return __libc_malloc(n ? n : 1);
}
void* operator new(std::size_t n, std::align_val_t a) {
  return counted_new_aligned(n, a);
}
void* operator new[](std::size_t n, std::align_val_t a) {
  return counted_new_aligned(n, a);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}

namespace medspring::testing {
bool counting_allocations() {
  return true;
}
long heap_allocations() {
  return g_allocations.load(std::memory_order_relaxed);
}
}  // namespace medspring::testing

#else

namespace medspring::testing {
bool counting_allocations() {
  return false;
}
long heap_allocations() {
  return 0;
}
}  // namespace medspring::testing

#endif
