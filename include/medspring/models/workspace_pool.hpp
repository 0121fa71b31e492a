// Per-update buffers for a const method that many callers may run at once (Body::map_to_surface of
// one model shared by several simulations or threads), without hidden thread-local state:
//
//   auto ws = pool_.acquire([&] { return make_workspace(); });  // a free one, or a new one
//   map_to_surface(state.x, *ws, surface);                     // returned when `ws` goes out of scope
//
// No allocation once every concurrent caller has had a workspace (the update loop after its first
// update). A copy or move of the owner starts with an empty pool: its workspaces fit the old owner.
#pragma once

#include <memory>
#include <mutex>
#include <utility>
#include <vector>

namespace medspring {

template <class W>
class WorkspacePool {
 public:
  WorkspacePool() = default;
  WorkspacePool(const WorkspacePool&) {}
  WorkspacePool(WorkspacePool&&) noexcept {}
  WorkspacePool& operator=(const WorkspacePool&) {
    clear();
    return *this;
  }
  WorkspacePool& operator=(WorkspacePool&&) noexcept {
    clear();
    return *this;
  }

  /// A workspace lent until the Lease is destroyed.
  class Lease {
   public:
    Lease(const WorkspacePool* pool, std::unique_ptr<W> w) : pool_(pool), w_(std::move(w)) {}
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    ~Lease() { pool_->give_back(std::move(w_)); }
    W& operator*() const { return *w_; }
    W* operator->() const { return w_.get(); }

   private:
    const WorkspacePool* pool_;
    std::unique_ptr<W> w_;
  };

  /// A free workspace, or make() when none is free.
  template <class Make>
  Lease acquire(Make&& make) const {
    std::unique_ptr<W> w;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (!free_.empty()) {
        w = std::move(free_.back());
        free_.pop_back();
      }
    }
    if (!w) w = std::make_unique<W>(make());
    return Lease(this, std::move(w));
  }

  void clear() {
    const std::lock_guard<std::mutex> lock(mutex_);
    free_.clear();
  }

 private:
  void give_back(std::unique_ptr<W> w) const {
    const std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(w));  // within the capacity after the first round: no allocation
  }
  mutable std::mutex mutex_;
  mutable std::vector<std::unique_ptr<W>> free_;
};

}  // namespace medspring
