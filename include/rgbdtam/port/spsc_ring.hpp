#pragma once
// A bounded single-producer single-consumer queue of fixed slots, allocated once at init.
// The producer fills a slot in place (begin_push, then publish); the consumer reads the
// oldest in place (front, then pop). Neither side ever waits: a full queue returns null to
// the producer, whose policy decides (drop and count).

#include <atomic>
#include <cstdint>
#include <memory>

namespace rgbdtam {

template <typename T>
class SpscRing {
 public:
  // Init time only. Slots are default-constructed; the owner sizes their buffers.
  void allocate(int capacity) {
    capacity_ = static_cast<uint32_t>(capacity);
    slots_.reset(new T[capacity_]);
  }
  int capacity() const { return static_cast<int>(capacity_); }
  T& slot(int i) { return slots_[static_cast<uint32_t>(i)]; }

  // Producer: a free slot, or null when the queue is full.
  T* begin_push() {
    const uint32_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) >= capacity_) return nullptr;
    return &slots_[tail % capacity_];
  }
  void publish() {
    tail_.store(tail_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }
  // Consumer: the oldest published slot, or null.
  T* front() {
    const uint32_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_.load(std::memory_order_acquire)) return nullptr;
    return &slots_[head % capacity_];
  }
  void pop() { head_.store(head_.load(std::memory_order_relaxed) + 1, std::memory_order_release); }
  // Consumer: how many are published and not popped (the one being read included).
  int size() const {
    return static_cast<int>(tail_.load(std::memory_order_acquire) -
                            head_.load(std::memory_order_relaxed));
  }

 private:
  std::unique_ptr<T[]> slots_;
  uint32_t capacity_ = 0;
  std::atomic<uint32_t> head_{0};  // next to pop
  std::atomic<uint32_t> tail_{0};  // next to publish
};

}  // namespace rgbdtam
