// A pool of objects that hold large buffers, kept between calls so that the
// buffers are reused rather than allocated anew: a fresh page costs the
// kernel a fault and a zeroing, and for the scan's images and the SDF's
// working grids that was a large share of the work (docs/benchmarks.md).
//
// One object per call in flight: a Lease takes one (default-constructed when
// the pool has none free) and gives it back when it ends. Not thread_local:
// TBB may run another call on a thread that waits inside a nested parallel
// loop of the first, and both would then use the same object. The objects
// live as long as the pool (a function-local static lives until the process
// ends); the pool holds as many as ever ran at once. Thread-safe.
#pragma once

#include <memory>
#include <mutex>
#include <utility>
#include <vector>

namespace samp {

template <typename T>
class ObjectPool {
 public:
  class Lease {
   public:
    explicit Lease(ObjectPool* pool) : pool_(pool), object_(pool->Take()) {}
    ~Lease() { pool_->Give(std::move(object_)); }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    T* get() const { return object_.get(); }
    T* operator->() const { return object_.get(); }
    T& operator*() const { return *object_; }

   private:
    ObjectPool* pool_;
    std::unique_ptr<T> object_;
  };

  // Objects not leased at the moment.
  size_t NumFree() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return free_.size();
  }

 private:
  std::unique_ptr<T> Take() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (free_.empty()) return std::make_unique<T>();
    std::unique_ptr<T> object = std::move(free_.back());
    free_.pop_back();
    return object;
  }
  void Give(std::unique_ptr<T> object) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(object));
  }

  mutable std::mutex mutex_;
  std::vector<std::unique_ptr<T>> free_;
};

}  // namespace samp
