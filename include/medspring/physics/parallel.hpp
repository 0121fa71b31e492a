// Persistent worker threads for the threaded step (docs/performance.md). Standard library only, so that
// the engine layers keep needing nothing but std + Eigen; the WebAssembly build (no pthreads) runs every
// pool on the calling thread.
#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "medspring/core/types.hpp"

namespace medspring {

/// Largest thread count accepted anywhere (StepSettings::threads, --threads, scenes, Python).
inline constexpr int kMaxThreads = 256;
/// Springs per thread below which a threaded step is not worth its synchronisation: a model with fewer
/// than threads x this many springs runs on fewer threads (one for anything below 2 x 25 000).
inline constexpr Index kMinSpringsPerThread = 25000;

/// True when this build can run worker threads (false in the single-threaded WebAssembly build).
bool threads_supported();

/// Validates a requested thread count: InvalidInput "<what>: must be an integer in 1..256 (got N)".
void require_thread_count(long threads, const char* what);

/// A fixed set of threads started once and reused: run(f) calls f(t) for t = 0 .. size()-1, t = 0 on the
/// caller, and returns when every call has returned. The calls must not throw. No allocation per run.
class WorkerPool {
 public:
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return static_cast<int>(workers_.size()) + 1; }

  template <class F>
  void run(F& f) {
    run_impl([](void* ctx, int t) { (*static_cast<F*>(ctx))(t); }, &f);
  }

 private:
  using Fn = void (*)(void*, int);
  void run_impl(Fn fn, void* ctx);
  void work(int t);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::atomic<unsigned long> generation_{0};
  std::atomic<int> pending_{0};
  std::atomic<bool> stop_{false};
  Fn fn_ = nullptr;
  void* ctx_ = nullptr;
};

}  // namespace medspring
