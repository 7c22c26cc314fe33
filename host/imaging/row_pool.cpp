#include "imaging/row_pool.hpp"

#include <algorithm>

namespace flutterscan::imaging {

RowPool::RowPool(int threads) : threads_(std::max(1, threads)) {
  for (int worker = 1; worker < threads_; ++worker)
    helpers_.emplace_back([this, worker] { serve(worker); });
}

RowPool::~RowPool() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  start_.notify_all();
  for (auto& helper : helpers_) helper.join();
}

void RowPool::run(int rows, const std::function<void(int, int, int)>& work) {
  {
    const std::lock_guard lock(mutex_);
    work_ = &work;
    rows_ = rows;
    pending_ = threads_ - 1;
    ++generation_;
  }
  start_.notify_all();
  work(0, rows / threads_, 0);
  std::unique_lock lock(mutex_);
  finished_.wait(lock, [this] { return pending_ == 0; });
  work_ = nullptr;
}

void RowPool::serve(int worker) {
  long long seen = 0;
  for (;;) {
    const std::function<void(int, int, int)>* work;
    int rows;
    {
      std::unique_lock lock(mutex_);
      start_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
      work = work_;
      rows = rows_;
    }
    (*work)(rows * worker / threads_, rows * (worker + 1) / threads_, worker);
    {
      const std::lock_guard lock(mutex_);
      --pending_;
    }
    finished_.notify_one();
  }
}

}  // namespace flutterscan::imaging
