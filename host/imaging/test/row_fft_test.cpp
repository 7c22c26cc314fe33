#include "imaging/row_fft.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

namespace flutterscan::imaging {
namespace {

/// The definition, one sum per bin.
std::vector<std::complex<double>> direct_dft_bins(const std::vector<double>& x, int n) {
  std::vector<std::complex<double>> bins(static_cast<std::size_t>(n / 2 + 1));
  for (std::size_t j = 0; j < bins.size(); ++j)
    for (std::size_t t = 0; t < x.size(); ++t)
      bins[j] += x[t] * std::polar(1.0, -2.0 * std::numbers::pi * static_cast<double>(j * t) / n);
  return bins;
}

double largest_difference(const std::vector<std::complex<double>>& a,
                          const std::vector<std::complex<double>>& b) {
  double worst = 0;
  for (std::size_t j = 0; j < a.size(); ++j) worst = std::max(worst, std::abs(a[j] - b[j]));
  return worst;
}

TEST(RealDftBins, MatchesTheDefinitionForShortAndWrappedInput) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> tap(0.0, 1.0);
  for (int n : {64, 100, 2048}) {
    for (std::size_t length : {std::size_t{1}, std::size_t{53}, std::size_t(n) + 17}) {
      std::vector<double> x(length);
      for (double& v : x) v = tap(random);
      const auto fast = real_dft_bins(x, n);
      ASSERT_EQ(fast.size(), static_cast<std::size_t>(n / 2 + 1));
      EXPECT_LT(largest_difference(fast, direct_dft_bins(x, n)), 1e-9)
          << "n " << n << ", " << length << " samples";
    }
  }
}

TEST(RealDftBins, ThreadsAndManyLengthsGiveTheSameAnswers) {
  const std::vector<double> x = {0.5, 0, 1, 1, 0, 0.25};
  const auto expected = direct_dft_bins(x, 96);
  std::vector<double> worst(2, 0.0);
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < worst.size(); ++i)
    threads.emplace_back([&, i] {
      for (int round = 0; round < 50; ++round) {
        // Other lengths in between push the 96-point plan out of the per-thread cache.
        for (int n : {128, 160, 192, 224, 256}) real_dft_bins(x, n);
        worst[i] = std::max(worst[i], largest_difference(real_dft_bins(x, 96), expected));
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_LT(worst[0], 1e-12);
  EXPECT_LT(worst[1], 1e-12);
}

// Two real rows as one complex row: the forward transform is the DFT of
// a + i b, and the inverse of it gives a and b back times n.
TEST(RowPairFft, TransformsTwoRowsAsOneComplexRowAndBack) {
  const int n = 128;
  std::mt19937 random(3);
  std::uniform_real_distribution<float> sample(-1.0f, 1.0f);
  AlignedFloats a(n), b(n), re(n), im(n), back_a(n), back_b(n);
  for (int t = 0; t < n; ++t) {
    a[static_cast<std::size_t>(t)] = sample(random);
    b[static_cast<std::size_t>(t)] = sample(random);
  }
  const RowPairFft fft(n);
  fft.forward(a.data(), b.data(), re.data(), im.data());
  double worst = 0;
  for (int j = 0; j < n; ++j) {
    std::complex<double> expected;
    for (int t = 0; t < n; ++t)
      expected +=
          std::complex<double>(a[static_cast<std::size_t>(t)], b[static_cast<std::size_t>(t)]) *
          std::polar(1.0, -2.0 * std::numbers::pi * j * t / n);
    worst =
        std::max(worst, std::abs(expected - std::complex<double>(re[static_cast<std::size_t>(j)],
                                                                 im[static_cast<std::size_t>(j)])));
  }
  EXPECT_LT(worst, 1e-4);
  fft.inverse(re.data(), im.data(), back_a.data(), back_b.data());
  worst = 0;
  for (std::size_t t = 0; t < static_cast<std::size_t>(n); ++t)
    worst = std::max(
        {worst, std::abs(back_a[t] / n - a[t] + 0.0), std::abs(back_b[t] / n - b[t] + 0.0)});
  EXPECT_LT(worst, 1e-5);
}

}  // namespace
}  // namespace flutterscan::imaging
