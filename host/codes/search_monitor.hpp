#pragma once
// Shared state of a running search: budget, evaluation count, best objective
// and progress reports. Workers write, the calling thread reads.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>

#include "codes/search.hpp"

namespace flutterscan::codes {

class SearchMonitor {
 public:
  explicit SearchMonitor(const SearchOptions& options)
      : options_(options), start_(std::chrono::steady_clock::now()) {}

  double elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  /// \brief Share of the budget used: by evaluations when that is the budget, else by time.
  double fraction(long long evaluations_done, long long evaluation_budget) const {
    if (evaluation_budget > 0)
      return static_cast<double>(evaluations_done) / static_cast<double>(evaluation_budget);
    return elapsed() / options_.seconds;
  }
  void add_evaluations(long long n) { evaluations_.fetch_add(n, std::memory_order_relaxed); }
  void offer_best(double objective) {
    const std::lock_guard lock(mutex_);
    if (!has_best_ || objective > best_) best_ = objective;
    has_best_ = true;
  }
  void set_generation(int generation, double selection_pressure) {
    const std::lock_guard lock(mutex_);
    generation_ = generation;
    pressure_ = selection_pressure;
  }
  SearchProgress snapshot() const {
    const std::lock_guard lock(mutex_);
    SearchProgress progress;
    progress.evaluations = evaluations_.load(std::memory_order_relaxed);
    progress.seconds = elapsed();
    progress.best_objective = best_;
    progress.generation = generation_;
    progress.selection_pressure = pressure_;
    return progress;
  }

 private:
  const SearchOptions& options_;
  std::chrono::steady_clock::time_point start_;
  std::atomic<long long> evaluations_{0};
  mutable std::mutex mutex_;
  bool has_best_ = false;
  double best_ = 0;
  int generation_ = -1;
  double pressure_ = 0;
};

/// \brief A 64-bit seed for stream `stream` of a search seeded with `seed` (SplitMix64 step).
inline std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/// \brief The seed's GA (genetic_search.cpp).
SearchResult run_genetic_search(const SearchOptions& options, SearchMonitor& monitor);
/// \brief Annealing chains on every thread (anneal_search.cpp).
SearchResult run_anneal_search(const SearchOptions& options, SearchMonitor& monitor);

}  // namespace flutterscan::codes
