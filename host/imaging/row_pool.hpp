#pragma once
// A fixed set of worker threads that split a frame's rows between them, made
// once and reused for every frame (no thread start-up or allocation per frame).

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace flutterscan::imaging {

class RowPool {
 public:
  /// \brief `threads` workers in all, the calling thread included.
  explicit RowPool(int threads);
  ~RowPool();
  RowPool(const RowPool&) = delete;
  RowPool& operator=(const RowPool&) = delete;

  int threads() const { return threads_; }

  /// \brief Calls work(first, last, worker) for a contiguous share of rows
  /// 0..rows on every worker and returns when all are done.
  void run(int rows, const std::function<void(int first, int last, int worker)>& work);

 private:
  void serve(int worker);

  int threads_;
  std::vector<std::thread> helpers_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable finished_;
  const std::function<void(int, int, int)>* work_ = nullptr;
  int rows_ = 0;
  long long generation_ = 0;
  int pending_ = 0;
  bool stopping_ = false;
};

}  // namespace flutterscan::imaging
