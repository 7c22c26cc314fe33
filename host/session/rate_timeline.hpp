#pragma once
// Events (processed frames) counted per span of time since the start of a
// session, in at most kMaxSpans counts however long it runs: spans start one
// second wide and double (neighbours merged) whenever the next event would
// fall past the last span. The report's throughput chart reads it.

#include <algorithm>
#include <cstdint>
#include <vector>

namespace flutterscan::session {

class RateTimeline {
 public:
  static constexpr std::size_t kMaxSpans = 4096;

  /// \brief One event `t_s` seconds after the start (t_s >= 0).
  void add(double t_s) {
    auto span = static_cast<std::size_t>(std::max(t_s, 0.0) / span_s_);
    while (span >= kMaxSpans) {
      for (std::size_t i = 0; i < counts_.size(); i += 2)
        counts_[i / 2] = counts_[i] + (i + 1 < counts_.size() ? counts_[i + 1] : 0);
      counts_.resize((counts_.size() + 1) / 2);
      span_s_ *= 2;
      span = static_cast<std::size_t>(std::max(t_s, 0.0) / span_s_);
    }
    if (span >= counts_.size()) counts_.resize(span + 1, 0);
    ++counts_[span];
  }

  /// \brief Events per second in each span, the last (partial) span left out
  /// unless it is the only one.
  std::vector<double> per_second() const {
    std::vector<double> rates;
    for (std::uint64_t n : counts_) rates.push_back(static_cast<double>(n) / span_s_);
    if (rates.size() > 1) rates.pop_back();
    return rates;
  }

  double span_s() const { return span_s_; }

 private:
  double span_s_ = 1;
  std::vector<std::uint64_t> counts_;
};

}  // namespace flutterscan::session
