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
  for (const int n : {128, 768}) {  // a power of two and a length with a factor 3
    std::mt19937 random(3);
    std::uniform_real_distribution<float> sample(-1.0f, 1.0f);
    const auto size = static_cast<std::size_t>(n);
    AlignedFloats pair(2 * size), spectrum(2 * size), back(2 * size);
    for (std::size_t t = 0; t < size; ++t) pair.complex()[t] = {sample(random), sample(random)};
    const RowPairFft fft(n);
    fft.forward(pair.complex(), spectrum.complex());
    double worst = 0;
    for (int j = 0; j < n; ++j) {
      std::complex<double> expected;
      for (std::size_t t = 0; t < size; ++t)
        expected += std::complex<double>(pair.complex()[t]) *
                    std::polar(1.0, -2.0 * std::numbers::pi * j * static_cast<double>(t) / n);
      worst = std::max(
          worst, std::abs(expected -
                          std::complex<double>(spectrum.complex()[static_cast<std::size_t>(j)])));
    }
    EXPECT_LT(worst, 1e-4) << n;
    fft.inverse(spectrum.complex(), back.complex());
    worst = 0;
    for (std::size_t t = 0; t < size; ++t)
      worst = std::max(worst, static_cast<double>(std::abs(
                                  back.complex()[t] / static_cast<float>(n) - pair.complex()[t])));
    EXPECT_LT(worst, 1e-5) << n;
  }
}

}  // namespace
}  // namespace flutterscan::imaging
