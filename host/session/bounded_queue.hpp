#pragma once
// The queue between two of the session's threads. A bounded one never makes
// its producer wait: try_push fails when it is full (the capture thread drops
// the frame there). Consumers wait in pop() until an item comes or the queue
// is closed and empty.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <utility>

namespace flutterscan::session {

/// \brief A queue with a capacity shared by producer and consumer threads.
template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(std::size_t capacity) : capacity_(capacity) {}

  /// \brief Adds `item` unless the queue is full (then `item` is left as it was).
  bool try_push(T&& item) {
    std::lock_guard lock(mutex_);
    if (items_.size() >= capacity_) return false;
    items_.push_back(std::move(item));
    ready_.notify_one();
    return true;
  }

  /// \brief Adds `item` whatever the capacity (for a queue nobody must wait on).
  void push(T&& item) {
    std::lock_guard lock(mutex_);
    items_.push_back(std::move(item));
    ready_.notify_one();
  }

  /// \brief Waits for an item; false once closed and empty.
  bool pop(T& item) {
    std::unique_lock lock(mutex_);
    ready_.wait(lock, [&] { return !items_.empty() || closed_; });
    if (items_.empty()) return false;
    item = std::move(items_.front());
    items_.pop_front();
    return true;
  }

  /// \brief The items waiting now.
  std::size_t size() const {
    std::lock_guard lock(mutex_);
    return items_.size();
  }

  /// \brief No more items: pop() returns false once the queue is empty.
  void close() {
    std::lock_guard lock(mutex_);
    closed_ = true;
    ready_.notify_all();
  }

 private:
  std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<T> items_;
  bool closed_ = false;
};

}  // namespace flutterscan::session
