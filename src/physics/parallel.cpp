#include "medspring/physics/parallel.hpp"

#include "medspring/core/check.hpp"

#if defined(__EMSCRIPTEN__) && !defined(__EMSCRIPTEN_PTHREADS__)
#define MEDSPRING_NO_THREADS 1
#endif

namespace medspring {

namespace {

// Polls before a waiting thread blocks on the condition variable: a step's two phases follow each other
// within microseconds, a futex wake costs about as much as a 10k-spring pass.
constexpr int kSpin = 4000;

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

}  // namespace

bool threads_supported() {
#ifdef MEDSPRING_NO_THREADS
  return false;
#else
  return true;
#endif
}

void require_thread_count(long threads, const char* what) {
  require(threads >= 1 && threads <= kMaxThreads, what, ": must be an integer in 1..", kMaxThreads, " (got ",
          threads, ")");
}

WorkerPool::WorkerPool(int threads) {
  require_thread_count(threads, "worker pool: threads");
#ifndef MEDSPRING_NO_THREADS
  workers_.reserve(static_cast<std::size_t>(threads - 1));
  for (int t = 1; t < threads; ++t) workers_.emplace_back([this, t] { work(t); });
#endif
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_.store(true);
    generation_.fetch_add(1);
  }
  wake_.notify_all();
  for (std::thread& w : workers_) w.join();
}

void WorkerPool::work(int t) {
  unsigned long seen = 0;
  for (;;) {
    unsigned long g = generation_.load(std::memory_order_acquire);
    for (int spin = 0; g == seen && spin < kSpin; ++spin) {
      cpu_relax();
      g = generation_.load(std::memory_order_acquire);
    }
    if (g == seen) {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return generation_.load(std::memory_order_acquire) != seen; });
      g = generation_.load(std::memory_order_acquire);
    }
    seen = g;
    if (stop_.load()) return;
    fn_(ctx_, t);
    pending_.fetch_sub(1, std::memory_order_acq_rel);
  }
}

void WorkerPool::run_impl(Fn fn, void* ctx) {
  if (workers_.empty()) {
    fn(ctx, 0);
    return;
  }
  fn_ = fn;
  ctx_ = ctx;
  pending_.store(static_cast<int>(workers_.size()), std::memory_order_relaxed);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();
  fn(ctx, 0);
  for (int spin = 0; pending_.load(std::memory_order_acquire) != 0; ++spin) {
    if (spin < kSpin)
      cpu_relax();
    else
      std::this_thread::yield();
  }
}

}  // namespace medspring
