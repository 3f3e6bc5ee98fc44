#pragma once
// One module skeleton: a module is step(const Item&), tick() and finish(), fed from a bounded
// SPSC ring. The same module code runs synchronously (deterministic replay drains the ring
// between frames) or on its own thread, placed from the board's task table: the thread steps
// through what is queued, ticks (for work with a period of its own, such as a heartbeat),
// and sleeps until notified or until the idle period ends. Stopping steps through what is
// still queued, then finishes.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>

#include "rgbdtam/port/spsc_ring.hpp"
#include "rgbdtam/port/thread_placement.hpp"

namespace rgbdtam {

// The modules' clock (steady, ns), injected so that tests can drive time.
using ClockFn = int64_t (*)();

// Synchronous mode: every queued item, in order, on the caller's thread. Returns how many.
template <typename Item, typename Module>
int drain(SpscRing<Item>* queue, Module* module) {
  int steps = 0;
  for (; Item* item = queue->front(); ++steps) {
    module->step(*item);
    queue->pop();
  }
  return steps;
}

template <typename Item, typename Module>
class WorkerThread {
 public:
  ~WorkerThread() {
    if (thread_.joinable()) stop();
  }
  // idle: the longest sleep; it also bounds the delay of a notify that lands between the
  // thread's last look at the queue and its wait (producers never take the lock).
  Status start(SpscRing<Item>* queue, Module* module, const ThreadPlacement& placement,
               const char* name, std::chrono::milliseconds idle = std::chrono::milliseconds(5)) {
    queue_ = queue;
    module_ = module;
    idle_ = idle;
    stopping_ = false;
    thread_ = std::thread([this] { run(); });
    return place_thread(thread_, placement, name);
  }
  void notify() { wake_.notify_one(); }
  // Steps through what is queued, finishes the module, and joins.
  void stop() {
    stopping_.store(true, std::memory_order_release);
    wake_.notify_one();
    thread_.join();
  }
  bool running() const { return thread_.joinable(); }

 private:
  void run() {
    for (;;) {
      while (Item* item = queue_->front()) {
        module_->step(*item);
        queue_->pop();
      }
      module_->tick();
      if (stopping_.load(std::memory_order_acquire) && queue_->front() == nullptr) break;
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait_for(lock, idle_, [this] {
        return stopping_.load(std::memory_order_acquire) || queue_->front() != nullptr;
      });
    }
    module_->finish();
  }

  SpscRing<Item>* queue_ = nullptr;
  Module* module_ = nullptr;
  std::chrono::milliseconds idle_{5};
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::atomic<bool> stopping_{false};
};

}  // namespace rgbdtam
