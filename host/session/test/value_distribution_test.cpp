// Bounded statistics of a long session: ValueDistribution's percentiles are
// exact up to its capacity and within its relative accuracy past it, for
// values of either sign; RateTimeline merges its spans instead of growing.
#include "session/value_distribution.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "session/rate_timeline.hpp"

namespace flutterscan::session {
namespace {

TEST(Percentile, InterpolatesBetweenRanks) {
  EXPECT_EQ(percentile({}, 50), 0);
  EXPECT_DOUBLE_EQ(percentile({4, 1, 3, 2}, 50), 2.5);
  EXPECT_DOUBLE_EQ(percentile({4, 1, 3, 2}, 100), 4);
  EXPECT_DOUBLE_EQ(percentile({10, 20}, 99), 19.9);
}

TEST(ValueDistribution, IsExactUpToItsCapacity) {
  ValueDistribution d(100);
  std::vector<double> values;
  for (int i = 0; i < 100; ++i) {
    values.push_back(std::sin(i) * 40 + 3);
    d.add(values.back());
  }
  EXPECT_FALSE(d.folded());
  EXPECT_EQ(d.count(), 100u);
  for (double p : {0.0, 5.0, 50.0, 95.0, 99.0, 100.0})
    EXPECT_DOUBLE_EQ(d.percentile(p), percentile(values, p)) << p;
  EXPECT_EQ(ValueDistribution().percentile(50), 0);
}

TEST(ValueDistribution, PastItsCapacityPercentilesStayWithinTheRelativeAccuracy) {
  // Latencies with a long tail, and blur deltas of either sign with zeros among them.
  std::mt19937 rng(7);
  std::lognormal_distribution<double> latency(std::log(20.0), 0.6);
  std::normal_distribution<double> delta(0.01, 0.05);
  ValueDistribution latencies(1000, 0.005), deltas(1000, 0.005);
  std::vector<double> all_latencies, all_deltas;
  for (int i = 0; i < 200'000; ++i) {
    all_latencies.push_back(latency(rng));
    latencies.add(all_latencies.back());
    all_deltas.push_back(i % 10 == 0 ? 0.0 : delta(rng));
    deltas.add(all_deltas.back());
  }
  ASSERT_TRUE(latencies.folded());
  EXPECT_EQ(latencies.count(), 200'000u);
  for (double p : {1.0, 50.0, 90.0, 99.0, 99.9}) {
    const double exact = percentile(all_latencies, p);
    // Within the accuracy, plus the step between neighbouring ranks at the tail.
    EXPECT_NEAR(latencies.percentile(p), exact, exact * 0.006) << "latency p" << p;
  }
  for (double p : {5.0, 25.0, 50.0, 75.0, 95.0}) {
    const double exact = percentile(all_deltas, p);
    EXPECT_NEAR(deltas.percentile(p), exact, std::fabs(exact) * 0.006 + 1e-6) << "delta p" << p;
  }
  EXPECT_EQ(latencies.percentile(0), latencies.min());
  EXPECT_EQ(latencies.percentile(100), latencies.max());
}

TEST(ValueDistribution, HistogramCountsEveryValueExactOrFolded) {
  ValueDistribution exact(1000), folded(10);
  for (int i = 0; i < 100; ++i) {
    exact.add(i);
    folded.add(i);
  }
  ASSERT_TRUE(folded.folded());
  for (const auto* d : {&exact, &folded}) {
    const auto counts = d->histogram(10);
    ASSERT_EQ(counts.size(), 10u);
    std::uint64_t total = 0;
    for (auto c : counts) total += c;
    EXPECT_EQ(total, 100u);
  }
  // 0..99 in ten bins of 9.9: bin b holds ceil(9.9 (b + 1)) - ceil(9.9 b) values.
  const auto counts = exact.histogram(10);
  EXPECT_EQ(counts[0], 10u);
  EXPECT_EQ(counts[9], 10u);
  // Folded, each value is within 0.5% of its bucket's centre: bins hold 9 to 11.
  for (auto c : folded.histogram(10)) EXPECT_NEAR(static_cast<double>(c), 10, 1);
}

TEST(ValueDistribution, IgnoresValuesThatAreNotFinite) {
  ValueDistribution d;
  d.add(std::nan(""));
  d.add(INFINITY);
  d.add(2);
  EXPECT_EQ(d.count(), 1u);
  EXPECT_EQ(d.percentile(50), 2);
}

TEST(RateTimeline, CountsPerSecondAndMergesSpansPastItsLimit) {
  RateTimeline t;
  for (double s : {0.1, 0.5, 1.2, 2.9, 3.1}) t.add(s);
  EXPECT_EQ(t.per_second(), (std::vector<double>{2, 1, 1}));  // the partial last second left out
  // A day at 10 frames per second: the spans widen, the counts stay bounded.
  RateTimeline day;
  for (int i = 0; i < 24 * 3600 * 10; ++i) day.add(i * 0.1);
  EXPECT_LE(day.per_second().size(), RateTimeline::kMaxSpans);
  EXPECT_EQ(day.span_s(), 32);  // 86400 s in at most 4096 spans
  // 320 frames per span, give or take one that i * 0.1 rounds across a boundary.
  for (double rate : day.per_second()) EXPECT_NEAR(rate, 10, 1.01 / 32);
}

}  // namespace
}  // namespace flutterscan::session
