// A fixed-capacity single-producer / single-consumer queue of trivially copyable values,
// lock-free and allocation-free: one thread (a library's callback thread) pushes, one
// thread (the pipeline) pops. Capacity is a compile-time power of two; a push onto a
// full queue fails and the producer counts it rather than blocking.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <type_traits>

namespace skyloc {

template <typename T, std::size_t kCapacity>
class SpscQueue {
  static_assert(kCapacity >= 2 && (kCapacity & (kCapacity - 1)) == 0,
                "SpscQueue capacity must be a power of two");
  static_assert(std::is_trivially_copyable_v<T>, "SpscQueue holds trivially copyable values");

 public:
  SpscQueue() = default;
  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;

  // Producer thread only. False when full.
  [[nodiscard]] bool TryPush(const T& value) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) == kCapacity)
      return false;
    slots_[head & (kCapacity - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  // Consumer thread only. False when empty.
  [[nodiscard]] bool TryPop(T* value) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (head_.load(std::memory_order_acquire) == tail)
      return false;
    *value = slots_[tail & (kCapacity - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  // Approximate when called concurrently; exact when both sides are quiet.
  std::size_t size() const {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }
  static constexpr std::size_t capacity() { return kCapacity; }

 private:
  std::array<T, kCapacity> slots_{};
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace skyloc
