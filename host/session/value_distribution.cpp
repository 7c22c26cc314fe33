#include "session/value_distribution.hpp"

#include <algorithm>
#include <cmath>

namespace flutterscan::session {

namespace {

constexpr double kZero = 1e-9;

}  // namespace

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(rank));
  const auto hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (values[hi] - values[lo]) * (rank - static_cast<double>(lo));
}

ValueDistribution::ValueDistribution(std::size_t exact_capacity, double accuracy)
    : capacity_(exact_capacity),
      log_gamma_(std::log((1 + accuracy) / (1 - accuracy))),
      // Magnitudes from kZero up land in buckets from 2 up (0 is the zero bucket).
      shift_(2 - static_cast<int>(std::ceil(std::log(kZero) / log_gamma_))) {}

int ValueDistribution::bucket_of(double value) const {
  const double magnitude = std::fabs(value);
  if (!(magnitude >= kZero)) return 0;
  // Bucket k + shift_ holds magnitudes in (gamma^(k-1), gamma^k]; its sign says
  // which side of 0.
  const int bucket = static_cast<int>(std::ceil(std::log(magnitude) / log_gamma_)) + shift_;
  return value < 0 ? -bucket : bucket;
}

double ValueDistribution::centre_of(int bucket) const {
  if (bucket == 0) return 0;
  const int k = std::abs(bucket) - shift_;
  const double gamma = std::exp(log_gamma_);
  // Within (gamma^(k-1), gamma^k], 2 gamma^k / (gamma + 1) is at most a relative
  // (gamma - 1) / (gamma + 1) = accuracy from either end.
  const double centre = 2 * std::exp(k * log_gamma_) / (gamma + 1);
  return bucket < 0 ? -centre : centre;
}

void ValueDistribution::fold() {
  for (double v : exact_) ++buckets_[bucket_of(v)];
  exact_.clear();
  exact_.shrink_to_fit();
}

void ValueDistribution::add(double value) {
  if (!std::isfinite(value)) return;
  min_ = count_ == 0 ? value : std::min(min_, value);
  max_ = count_ == 0 ? value : std::max(max_, value);
  ++count_;
  if (buckets_.empty() && exact_.size() < capacity_) {
    exact_.push_back(value);
    return;
  }
  if (!exact_.empty()) fold();
  ++buckets_[bucket_of(value)];
}

double ValueDistribution::percentile(double p) const {
  if (count_ == 0) return 0;
  if (!exact_.empty()) return session::percentile(exact_, p);
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(count_ - 1);
  const auto wanted = static_cast<std::uint64_t>(std::llround(rank));
  if (wanted == 0) return min_;  // the extremes are known exactly
  if (wanted + 1 >= count_) return max_;
  std::uint64_t seen = 0;
  for (const auto& [bucket, n] : buckets_) {
    seen += n;
    if (seen > wanted) return std::clamp(centre_of(bucket), min_, max_);
  }
  return max_;
}

std::vector<std::uint64_t> ValueDistribution::histogram(int bins) const {
  std::vector<std::uint64_t> counts(static_cast<std::size_t>(std::max(bins, 1)), 0);
  if (count_ == 0) return counts;
  const double width = (max_ > min_ ? max_ - min_ : 1.0) / static_cast<double>(counts.size());
  const auto put = [&](double v, std::uint64_t n) {
    const auto b = static_cast<long>(std::floor((v - min_) / width));
    counts[static_cast<std::size_t>(std::clamp(b, 0L, static_cast<long>(counts.size()) - 1))] += n;
  };
  for (double v : exact_) put(v, 1);
  for (const auto& [bucket, n] : buckets_) put(std::clamp(centre_of(bucket), min_, max_), n);
  return counts;
}

}  // namespace flutterscan::session
