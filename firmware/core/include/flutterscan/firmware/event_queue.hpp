#pragma once
// A fixed-capacity single-producer single-consumer queue: the exposure events
// produced in interrupt context and sent by the USB main loop.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <atomic>
#include <cstddef>

namespace flutterscan::firmware {

/// \brief Ring buffer of up to Capacity values of T (one producer, one consumer).
template <typename T, std::size_t Capacity>
class EventQueue {
  static_assert(Capacity >= 1);

 public:
  /// \brief Appends `value`; false (queue unchanged) when full.
  bool push(const T& value) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t next = (tail + 1) % kSlots;
    if (next == head_.load(std::memory_order_acquire)) return false;
    slots_[tail] = value;
    tail_.store(next, std::memory_order_release);
    return true;
  }

  /// \brief Removes the oldest value into `out`; false when empty.
  bool pop(T& out) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_.load(std::memory_order_acquire)) return false;
    out = slots_[head];
    head_.store((head + 1) % kSlots, std::memory_order_release);
    return true;
  }

  /// \brief Drops every queued value (consumer side).
  void clear() { head_.store(tail_.load(std::memory_order_acquire), std::memory_order_release); }

  bool empty() const {
    return head_.load(std::memory_order_acquire) == tail_.load(std::memory_order_acquire);
  }

 private:
  static constexpr std::size_t kSlots = Capacity + 1;  // one slot stays free
  std::array<T, kSlots> slots_{};
  std::atomic<std::size_t> head_{0};
  std::atomic<std::size_t> tail_{0};
};

}  // namespace flutterscan::firmware
