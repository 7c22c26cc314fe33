#pragma once
// A distribution of values (latencies, blur deltas, window times) whose memory
// stays bounded however long the session runs: the values are kept exactly up
// to a capacity, and percentiles are then exact (linear between ranks); past
// it they are folded into logarithmic buckets, each value within a relative
// `accuracy` of its bucket's centre, so a percentile is within that relative
// error of the exact one whatever the distribution (values of either sign;
// magnitudes below 1e-9 count as 0). docs/session-output.md says which
// summary figures come from one.

#include <cstdint>
#include <map>
#include <vector>

namespace flutterscan::session {

/// \brief The `p`th percentile (0-100) of `values`, linear between ranks; 0 when empty.
double percentile(std::vector<double> values, double p);

class ValueDistribution {
 public:
  explicit ValueDistribution(std::size_t exact_capacity = 4096, double accuracy = 0.005);

  void add(double value);
  std::uint64_t count() const { return count_; }
  double min() const { return min_; }
  double max() const { return max_; }
  /// \brief True once the values were folded into buckets (percentiles approximate).
  bool folded() const { return exact_.empty() && count_ > 0; }

  /// \brief The `p`th percentile (0-100); 0 when empty.
  double percentile(double p) const;

  /// \brief How many values fall in each of `bins` equal bins over [min, max]
  /// (the last bin closed); a folded value counts in the bin of its bucket's centre.
  std::vector<std::uint64_t> histogram(int bins) const;

 private:
  int bucket_of(double value) const;
  double centre_of(int bucket) const;
  void fold();

  std::size_t capacity_;
  double log_gamma_;  ///< log of the buckets' ratio, (1 + accuracy) / (1 - accuracy)
  int shift_;         ///< added to a magnitude's log-bucket to make it >= 2
  std::vector<double> exact_;
  /// Bucket index -> count: negative indices below 0 mirror the positive ones
  /// (bucket_of), 0 is the zero bucket.
  std::map<int, std::uint64_t> buckets_;
  std::uint64_t count_ = 0;
  double min_ = 0, max_ = 0;
};

}  // namespace flutterscan::session
